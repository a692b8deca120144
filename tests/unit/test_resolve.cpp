// The two resolve paths (compute kernel, host loop) must produce the same frame and error.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "brdfa/renderer.h"
#include "host_resolve.h"

namespace brdfa {
namespace {

TEST(SrgbEncode, MatchesTheExactRoundingRuleEverywhere) {
  auto exact = [](double c) {
    double e = c <= 0.0031308 ? 12.92 * c : 1.055 * std::pow(c, 1.0 / 2.4) - 0.055;
    return static_cast<int>(std::floor(e * 255.0 + 0.5));
  };
  int mismatches = 0;
  for (int i = 0; i <= 200000; ++i) {
    double c = std::pow(static_cast<double>(i) / 200000.0, 3.0);  // dense near black
    int got = linearToSrgb8(static_cast<float>(c));
    int want = exact(static_cast<float>(c));
    // Only a value within float rounding of a code boundary may land on either side.
    if (got != want) {
      ++mismatches;
      ASSERT_LE(std::abs(got - want), 1) << c;
    }
  }
  EXPECT_LT(mismatches, 20);
  EXPECT_EQ(linearToSrgb8(0.0f), 0);
  EXPECT_EQ(linearToSrgb8(-1.0f), 0);
  EXPECT_EQ(linearToSrgb8(NAN), 0);
  EXPECT_EQ(linearToSrgb8(1.0f), 255);
  EXPECT_EQ(linearToSrgb8(INFINITY), 255);
  EXPECT_EQ(linearToSrgb8(0.5f), 188);
  EXPECT_EQ(linearToSrgb8(0.18f), 118);  // mid grey
}

Frame renderWith(ResolveMode mode) {
  RendererOptions options;
  options.shaderDir = std::string(BRDFA_SOURCE_DIR) + "/shaders";
  options.resolve = mode;
  auto renderer = Renderer::create(options);
  EXPECT_TRUE(renderer.ok());
  std::ifstream in(std::string(BRDFA_SOURCE_DIR) + "/shaders/brdfs/ggx.brdf");
  std::stringstream text;
  text << in.rdbuf();
  Scene s;
  s.environment.name = "sky";
  s.render.width = 96;
  s.render.height = 64;
  s.render.samplesPerFrame = 4;
  s.render.maxSamples = 40;
  s.render.exposure = 0.5f;
  SceneObject o;
  o.brdf = std::make_shared<BrdfDefinition>(parseBrdf(text.str()).value());
  s.objects.push_back(o);
  auto view = (*renderer)->createView();
  EXPECT_TRUE((*view)->setScene(s).ok());
  while (!(*view)->renderPass()->converged) {
  }
  return (*view)->readFrame(true).value();
}

TEST(Resolve, HostAndDevicePathsAgree) {
  Frame host = renderWith(ResolveMode::Host);
  Frame device = renderWith(ResolveMode::Device);
  ASSERT_EQ(host.rgba32f.size(), device.rgba32f.size());
  ASSERT_EQ(host.rgba8.size(), device.rgba8.size());
  for (size_t i = 0; i < host.rgba32f.size(); ++i)
    ASSERT_NEAR(host.rgba32f[i], device.rgba32f[i], 1e-5f * std::max(1.0f, std::fabs(host.rgba32f[i]))) << i;
  for (size_t i = 0; i < host.rgba8.size(); ++i) ASSERT_LE(std::abs(host.rgba8[i] - device.rgba8[i]), 1) << i;
  ASSERT_TRUE(host.stats.relError && device.stats.relError);
  EXPECT_NEAR(*host.stats.relError, *device.stats.relError, 1e-4 * *host.stats.relError);
  EXPECT_GT(*host.stats.relError, 0.0);
}

}  // namespace
}  // namespace brdfa
