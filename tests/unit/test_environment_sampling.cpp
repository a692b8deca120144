// The environment's importance-sampling distribution on the host: what the device
// table holds, checked against direct integrals.
#include <gtest/gtest.h>

#include <cmath>

#include "assets/environment_maps.h"
#include "assets/environment_sampling.h"

namespace brdfa {
namespace {

constexpr double kPi = 3.14159265358979323846;

// A cube of `size` texels per face whose luminance is `f(direction)` (grey, so luminance = value).
EnvironmentData cubeOf(uint32_t size, double (*f)(const float*)) {
  EnvironmentData env;
  env.faceSize = size;
  env.texels.resize(size_t(6) * size * size * 4);
  for (int face = 0; face < 6; ++face)
    for (uint32_t y = 0; y < size; ++y)
      for (uint32_t x = 0; x < size; ++x) {
        float d[3];
        cubeTexelDirection(face, x, y, size, d);
        float* t = &env.texels[((size_t(face) * size + y) * size + x) * 4];
        t[0] = t[1] = t[2] = float(f(d));
        t[3] = 1.0f;
      }
  return env;
}

double skyLike(const float* d) {
  const double sun = d[0] * 0.3 + d[1] * 0.8 + d[2] * 0.52;  // a bright spot, a bright half
  return (d[1] > 0 ? 1.0 : 0.05) + (sun > 0.99 ? 500.0 : 0.0);
}

// The integral of pdf over the sphere by the midpoint rule on a fine grid of every face.
double integralOverSphere(const EnvironmentDistribution& dist, int n) {
  double sum = 0;
  for (int face = 0; face < 6; ++face)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const double s = 2.0 * (i + 0.5) / n - 1.0, t = 2.0 * (j + 0.5) / n - 1.0;
        float d[3];
        cubeFaceDirection(face, float(s), float(t), d);
        const double r2 = 1.0 + s * s + t * t;
        sum += dist.pdf(d) * (4.0 / (double(n) * n)) / (r2 * std::sqrt(r2));  // d omega = dA / r^3
      }
  return sum;
}

TEST(EnvironmentDistribution, PdfIntegratesToOneAndTheAliasTableRealisesIt) {
  for (uint32_t size : {16u, 64u, 96u}) {  // 96: cells span fractional texel ranges (D = 64)
    EnvironmentDistribution dist = buildEnvironmentDistribution(cubeOf(size, skyLike));
    EXPECT_EQ(dist.cellsPerEdge & (dist.cellsPerEdge - 1), 0u) << "a power of two";
    EXPECT_LE(dist.cellsPerEdge, size);
    EXPECT_NEAR(integralOverSphere(dist, 8 * int(dist.cellsPerEdge)), 1.0, 1e-4) << size;
    // The alias table's realised cell probabilities are the densities the pdf reports, and
    // every cell is reachable.
    const std::vector<double> realised = dist.realisedCellProbabilities();
    const uint32_t D = dist.cellsPerEdge;
    double total = 0;
    for (size_t c = 0; c < realised.size(); ++c) {
      const double reported = dist.density(c) / (double(D) * D / 4.0);
      ASSERT_NEAR(realised[c], reported, 1e-6 * reported) << "cell " << c;
      ASSERT_GT(realised[c], 0.0) << "cell " << c;
      ASSERT_LT(dist.aliasOf(c), realised.size()) << "cell " << c;
      total += realised[c];
    }
    EXPECT_NEAR(total, 1.0, 1e-9);
  }
}

TEST(EnvironmentDistribution, DensityFollowsLuminanceAndHasAFloor) {
  EnvironmentDistribution dist = buildEnvironmentDistribution(cubeOf(32, skyLike));
  const float up[3] = {0, 1, 0}, down[3] = {0, -1, 0}, sun[3] = {0.3f, 0.8f, 0.52f};
  // Radiance 1 above, 0.05 below: the density follows (the floor is 1e-4 of the total).
  EXPECT_NEAR(dist.pdf(up) / dist.pdf(down), 20.0, 0.2);
  EXPECT_GT(dist.pdf(sun), 50 * dist.pdf(up));
  // A black map becomes uniform over the sphere: 1 / (4 pi), up to the |w_major|^3 variation
  // inside each cell (uniform in the face's s, t): within 2% at face centres, 10% anywhere.
  EnvironmentDistribution black = buildEnvironmentDistribution(cubeOf(16, [](const float*) { return 0.0; }));
  for (const float* d : {up, down}) EXPECT_NEAR(black.pdf(d) * 4.0 * kPi, 1.0, 0.02);
  EXPECT_NEAR(black.pdf(sun) * 4.0 * kPi, 1.0, 0.10);
  // Every direction is reachable: the floor keeps a black half non-zero.
  EnvironmentDistribution half =
      buildEnvironmentDistribution(cubeOf(16, [](const float* d) { return d[1] > 0 ? 1.0 : 0.0; }));
  EXPECT_GT(half.pdf(down), 0.0);
  EXPECT_LT(half.pdf(down), 1e-3 * half.pdf(up));
  // The effective density (integral of pdf^2) is 1/(4 pi) for a uniform map and larger when
  // the light is concentrated.
  EXPECT_NEAR(black.effectiveDensity * 4.0 * kPi, 1.0, 0.01);
  EXPECT_GT(dist.effectiveDensity, 10.0 / (4.0 * kPi));
}

}  // namespace
}  // namespace brdfa
