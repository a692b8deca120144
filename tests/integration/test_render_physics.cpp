// Physics through the whole service: POST /api/render in the white furnace (docs/design.md section 4:
// a white Lambertian sphere in the furnace renders exactly 1.0 in linear float output).
#include <cmath>

#include "server_fixture.h"

namespace brdfa::itest {
namespace {

using nlohmann::json;

class RenderPhysics : public ServerTest {
 protected:
  // One-shot render; returns the decoded image (asserting status 200 and a valid PFM).
  static void render(const json& body, Image& img, httplib::Headers* headers = nullptr) {
    auto r = post("/api/render", body.dump());
    ASSERT_TRUE(r);
    ASSERT_EQ(r->status, 200) << r->body;
    ASSERT_EQ(r->get_header_value("Content-Type"), "application/x-portable-floatmap");
    ASSERT_TRUE(decodeImage(r->body, img));
    if (headers) *headers = r->headers;
  }
};

json lambertFurnaceRender(const std::string& sampling, int size, int spp) {
  return {{"scene",
           {{"environment", {{"name", "furnace"}, {"visible", false}}},
            {"objects", json::array({{{"mesh", "sphere"}, {"brdf", "inline"}}})},
            {"render", {{"width", size}, {"height", size}, {"sampling", sampling}}}}},
          {"spp", spp},
          {"format", "pfm"},
          {"brdf_source", kLambertWhite}};
}

TEST_F(RenderPhysics, WhiteLambertInFurnaceIsOneCosineSampling) {
  Image img;
  httplib::Headers headers;
  ASSERT_NO_FATAL_FAILURE(render(lambertFurnaceRender("cosine", 128, 256), img, &headers));
  ASSERT_EQ(img.width, 128);
  ASSERT_EQ(img.height, 128);
  EXPECT_EQ(headers.find("X-Samples")->second, "256");
  EXPECT_NE(headers.find("X-Render-Ms"), headers.end());

  auto interior = interiorPixels(img);
  // The unit sphere at distance 3 under a 45 degree fov spans ~55 px of radius: ~9000 pixels.
  ASSERT_GT(interior.size(), 5000u);
  double sum = 0;
  int bad = 0;
  for (auto [x, y] : interior) {
    for (int c = 0; c < 3; ++c) {
      float v = img.at(x, y, c);
      if (!(std::fabs(v - 1.0f) <= 0.01f) && bad++ < 5)
        ADD_FAILURE() << "pixel (" << x << "," << y << ") c" << c << " = " << v;
    }
    sum += img.lum(x, y);
  }
  EXPECT_EQ(bad, 0) << "interior pixels off by more than 1%";
  double mean = sum / interior.size();
  EXPECT_NEAR(mean, 1.0, 0.002);

  // Background (hidden furnace): exactly zero, checked well away from the sphere.
  int nonzero = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      double r = std::hypot(x + 0.5 - 64.0, y + 0.5 - 64.0);
      if (r > 60.0)
        for (int c = 0; c < 3; ++c) nonzero += img.at(x, y, c) != 0.0f;
    }
  EXPECT_EQ(nonzero, 0) << "background must be exactly 0 with the environment hidden";
}

TEST_F(RenderPhysics, WhiteLambertInFurnaceIsOneUniformSampling) {
  // Uniform hemisphere sampling is unbiased but noisy (per-sample sigma ~0.58): the per-pixel
  // values scatter, the mean over the sphere must still be 1. Also exercises the other body
  // form: scene fields at the top level next to spp/format/brdf_source.
  json body = lambertFurnaceRender("uniform", 128, 256);
  json flat = body["scene"];
  for (auto& [k, v] : body.items())
    if (k != "scene") flat[k] = v;
  Image img;
  ASSERT_NO_FATAL_FAILURE(render(flat, img));
  auto interior = interiorPixels(img);
  ASSERT_GT(interior.size(), 5000u);
  double sum = 0;
  for (auto [x, y] : interior) {
    ASSERT_TRUE(std::isfinite(img.lum(x, y)));
    sum += img.lum(x, y);
  }
  EXPECT_NEAR(sum / interior.size(), 1.0, 0.005);
}

// The built-in GGX with F0 = 1 in the furnace: finite everywhere and never brighter than the
// light it receives (single-scattering microfacet models lose energy, never gain it).
TEST_F(RenderPhysics, GgxInFurnaceIsFiniteAndConservesEnergy) {
  const int size = 96;
  const double center = size / 2.0;
  // Projected radius of the unit sphere seen from distance 3 with a 45 degree vertical fov.
  const double radiusPx = std::tan(std::asin(1.0 / 3.0)) / std::tan(22.5 * M_PI / 180.0) * center;
  for (double roughness : {0.05, 0.3, 1.0}) {
    SCOPED_TRACE("roughness " + std::to_string(roughness));
    json body = {
        {"environment", {{"name", "furnace"}, {"visible", false}}},
        {"objects", json::array({{{"brdf", "ggx"}, {"params", {{"roughness", roughness}, {"F0", {1, 1, 1}}}}}})},
        {"render", {{"width", size}, {"height", size}}},
        {"spp", 1024},
        {"format", "pfm"}};
    Image img;
    ASSERT_NO_FATAL_FAILURE(render(body, img));
    for (float v : img.rgba) ASSERT_TRUE(std::isfinite(v)) << "non-finite value in the image";

    // Pixels well inside the silhouette (geometry, not values: a sharp lobe sampled by cosine
    // can leave a pixel at exactly 0). Binned into rings of similar n.v, whose true values
    // are equal, so each ring's mean must be <= 1 up to its own standard error.
    constexpr int kRings = 6;
    double sum[kRings] = {}, sum2[kRings] = {};
    int n[kRings] = {};
    double maxPixel = 0, total = 0;
    int count = 0;
    for (int y = 0; y < size; ++y)
      for (int x = 0; x < size; ++x) {
        double r = std::hypot(x + 0.5 - center, y + 0.5 - center) / radiusPx;
        if (r > 0.9) continue;
        int ring = std::min(kRings - 1, static_cast<int>(r / 0.9 * kRings));
        double v = img.lum(x, y);
        sum[ring] += v;
        sum2[ring] += v * v;
        n[ring]++;
        maxPixel = std::max(maxPixel, v);
        total += v;
        count++;
      }
    ASSERT_GT(count, 1000);
    EXPECT_GT(total / count, 0.05) << "GGX sphere renders black";
    for (int i = 0; i < kRings; ++i) {
      ASSERT_GT(n[i], 10);
      double mean = sum[i] / n[i];
      double var = std::max(0.0, sum2[i] / n[i] - mean * mean);
      double stderr_ = std::sqrt(var / n[i]);
      EXPECT_LE(mean, 1.0 + 3.0 * stderr_ + 0.005) << "ring " << i << " gains energy (stderr " << stderr_ << ")";
    }
    // At roughness 1 the estimator is smooth (per-pixel noise well below 1%), so every pixel
    // must stay below 1 + 3 sigma; sharper lobes sampled by the cosine are too noisy per pixel.
    if (roughness >= 1.0) {
      EXPECT_LE(maxPixel, 1.02);
    }
  }
}

}  // namespace
}  // namespace brdfa::itest
