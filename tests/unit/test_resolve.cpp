// The two resolve paths (compute kernel, host loop) must produce the same frame and error.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>

#include "brdfa/renderer.h"

#include "render/host_resolve.h"

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

TEST(ToneMap, CurvesOfTheBrief) {
  // Clamp: min(e, 1).
  EXPECT_EQ(toneMapValue(0.25f, ToneMap::Clamp), 0.25f);
  EXPECT_EQ(toneMapValue(3.0f, ToneMap::Clamp), 1.0f);
  // Reinhard et al. 2002: e / (1 + e).
  EXPECT_FLOAT_EQ(toneMapValue(1.0f, ToneMap::Reinhard), 0.5f);
  EXPECT_FLOAT_EQ(toneMapValue(3.0f, ToneMap::Reinhard), 0.75f);
  // Narkowicz 2015: (e (2.51 e + 0.03)) / (e (2.43 e + 0.59) + 0.14), clamped to [0, 1].
  EXPECT_FLOAT_EQ(toneMapValue(1.0f, ToneMap::Aces), 2.54f / 3.16f);
  EXPECT_FLOAT_EQ(toneMapValue(0.18f, ToneMap::Aces),
                  0.18f * (2.51f * 0.18f + 0.03f) / (0.18f * (2.43f * 0.18f + 0.59f) + 0.14f));
  EXPECT_EQ(toneMapValue(100.0f, ToneMap::Aces), 1.0f);  // the fit tends to 2.51 / 2.43 > 1
  for (ToneMap t : {ToneMap::Clamp, ToneMap::Reinhard, ToneMap::Aces}) {
    EXPECT_EQ(toneMapValue(0.0f, t), 0.0f);
    EXPECT_EQ(toneMapValue(-2.0f, t), 0.0f);  // negative radiance from a bad BRDF
    EXPECT_EQ(toneMapValue(NAN, t), 0.0f);
    EXPECT_NEAR(toneMapValue(INFINITY, t), 1.0f, 1e-4f);  // never Inf / Inf
    EXPECT_NEAR(toneMapValue(3.0e38f, t), 1.0f, 1e-4f);
    float previous = 0.0f;  // monotonic
    for (float e = 0.001f; e < 50.0f; e *= 1.1f) {
      float v = toneMapValue(e, t);
      EXPECT_GE(v, previous) << e;
      EXPECT_LE(v, 1.0f);
      previous = v;
    }
  }
}

Frame renderWith(ResolveMode mode, ToneMap toneMap = ToneMap::Clamp, float exposure = 0.5f, int width = 96,
                 int height = 64, uint64_t samples = 40) {
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
  s.render.width = width;
  s.render.height = height;
  s.render.samplesPerFrame = 4;
  s.render.maxSamples = samples;
  s.render.exposure = exposure;
  s.render.toneMap = toneMap;
  SceneObject o;
  o.brdf = std::make_shared<BrdfDefinition>(parseBrdf(text.str()).value());
  s.objects.push_back(o);
  auto view = (*renderer)->createView();
  EXPECT_TRUE((*view)->setScene(s).ok());
  while (!(*view)->renderPass()->done()) {
  }
  return (*view)->readFrame(true).value();
}

void expectSameFrames(const Frame& host, const Frame& device) {
  ASSERT_EQ(host.rgba32f.size(), device.rgba32f.size());
  ASSERT_EQ(host.rgba8.size(), device.rgba8.size());
  for (size_t i = 0; i < host.rgba32f.size(); ++i)
    ASSERT_NEAR(host.rgba32f[i], device.rgba32f[i], 1e-5f * std::max(1.0f, std::fabs(host.rgba32f[i]))) << i;
  for (size_t i = 0; i < host.rgba8.size(); ++i) ASSERT_LE(std::abs(host.rgba8[i] - device.rgba8[i]), 1) << i;
  ASSERT_TRUE(host.stats.relError && device.stats.relError);
  EXPECT_NEAR(*host.stats.relError, *device.stats.relError, 1e-4 * *host.stats.relError);
  EXPECT_GT(*host.stats.relError, 0.0);
}

TEST(Resolve, HostAndDevicePathsAgree) {
  expectSameFrames(renderWith(ResolveMode::Host), renderWith(ResolveMode::Device));
}

// From 2^16 pixels the host resolve splits the image over two threads (host_resolve.cpp): the
// same frame and error sums, the sphere's pixels in both halves of the image.
TEST(Resolve, HostAndDevicePathsAgreeOnAnImageSplitOverThreads) {
  expectSameFrames(renderWith(ResolveMode::Host, ToneMap::Clamp, 0.5f, 320, 240, 8),
                   renderWith(ResolveMode::Device, ToneMap::Clamp, 0.5f, 320, 240, 8));
}

// The tone maps of shaders/lib/tonemap.glsl and host_resolve.cpp agree, on a frame exposed so
// that much of it is above 1 (where the curves differ most from a clamp).
TEST(Resolve, HostAndDeviceToneMapsAgree) {
  for (ToneMap t : {ToneMap::Reinhard, ToneMap::Aces}) {
    SCOPED_TRACE(toneMapName(t));
    Frame host = renderWith(ResolveMode::Host, t, 3.0f);
    Frame device = renderWith(ResolveMode::Device, t, 3.0f);
    expectSameFrames(host, device);
    // The display image is the tone map of the exposed radiance, then sRGB.
    int saturated = 0;
    for (size_t i = 0; i < host.rgba32f.size(); i += 4)
      for (int c = 0; c < 3; ++c) {
        const float e = host.rgba32f[i + c] * 8.0f;
        saturated += e > 1.0f;
        ASSERT_EQ(host.rgba8[i + c], linearToSrgb8(toneMapValue(e, t))) << i;
      }
    EXPECT_GT(saturated, 100);
  }
}

}  // namespace
}  // namespace brdfa
