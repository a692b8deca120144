// A pass's samples picked from a frame-time target (PassSizer, RenderView::renderPass's
// frameTargetMs): predictions from the passes measured, and the view's passes under a target.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "brdfa/renderer.h"

#include "device_test.h"
#include "render/pass_sizer.h"

namespace brdfa {
namespace {

TEST(PassSizer, NothingMeasuredKeepsTheCap) {
  PassSizer s;
  EXPECT_LT(s.predict(4), 0.0);
  EXPECT_EQ(s.fit(1.0, 8), 8u);
  EXPECT_EQ(s.fit(1.0, 0), 1u);
}

// Passes of a fixed 19 ms plus 10 ms a sample (GGX, mis, 512^2 on the 2-core VM): the line
// through two measured counts predicts the others exactly.
TEST(PassSizer, TheLineThroughTwoCountsPicksTheLargestPassThatFits) {
  PassSizer s;
  s.record(1, 29);
  s.record(2, 39);
  EXPECT_NEAR(s.predict(4), 59, 1e-9);
  EXPECT_NEAR(s.predict(16), 179, 1e-9);
  EXPECT_EQ(s.fit(45, 4), 2u);
  EXPECT_EQ(s.fit(49, 8), 3u);
  EXPECT_EQ(s.fit(59, 4), 4u);
  EXPECT_EQ(s.fit(1000, 4), 4u);  // never above the cap
  // Under a target that one sample meets but two do not, no fewer samples than fit in the
  // fixed part's time (19 / 10 -> 1).
  EXPECT_EQ(s.fit(30, 4), 1u);
  // Where even those would take over twice the target, the frame rate is out of reach: the cap.
  EXPECT_EQ(s.fit(14, 4), 4u);
}

TEST(PassSizer, ALargeFixedPartKeepsPassesFromShrinkingBelowIt) {
  PassSizer s;
  s.record(4, 50);  // 30 ms fixed, 5 ms a sample: 6 samples fit in the fixed part's time
  s.record(8, 70);
  EXPECT_EQ(s.fit(45, 16), 6u);  // 3 samples would fit 45 ms, at 50 % of the pass on fixed work
  EXPECT_EQ(s.fit(65, 16), 7u);
  EXPECT_EQ(s.fit(29, 16), 16u);  // 6 samples take 60 ms, over twice 29: out of reach
}

TEST(PassSizer, ASmallFixedPartLetsPassesShrinkToOneSample) {
  PassSizer s;
  s.record(2, 22);  // 2 ms fixed, 10 ms a sample
  s.record(4, 42);
  EXPECT_EQ(s.fit(30, 8), 2u);
  EXPECT_EQ(s.fit(12, 8), 1u);
  EXPECT_EQ(s.fit(8, 8), 1u);  // 12 ms: within twice the target
  EXPECT_EQ(s.fit(5, 8), 8u);  // out of reach
  EXPECT_EQ(s.fit(12, 0), 1u);
}

// One count measured: predictions scale it; where it missed the target the next pass takes
// half as many samples (a second count, and with it the line), else the cap.
TEST(PassSizer, OneCountIsScaledInProportionAndHalvedOnceWhereItMissed) {
  PassSizer s;
  s.record(4, 60);
  EXPECT_NEAR(s.predict(2), 30, 1e-9);
  EXPECT_NEAR(s.predict(8), 120, 1e-9);
  EXPECT_EQ(s.fit(45, 8), 2u);
  EXPECT_EQ(s.fit(1, 8), 2u);
  EXPECT_EQ(s.fit(45, 1), 1u);
  EXPECT_EQ(s.fit(60, 8), 8u);
  s.record(2, 40);  // the line: 20 ms fixed, 10 a sample
  EXPECT_EQ(s.fit(45, 8), 2u);
  EXPECT_EQ(s.fit(70, 8), 5u);
}

// Noise can make more samples read cheaper (a pass measured under load): the line would
// predict less for more; the nearest measured count is scaled instead, and nothing is sized.
TEST(PassSizer, ATiltedLineFallsBackToTheNearestCount) {
  PassSizer s;
  s.record(1, 40);
  s.record(2, 30);
  EXPECT_NEAR(s.predict(3), 45, 1e-9);
  EXPECT_NEAR(s.predict(4), 60, 1e-9);
  EXPECT_EQ(s.fit(44, 4), 4u);  // no line: nothing sized
}

TEST(PassSizer, RepeatedCountsFollowTheNewerTimesAndNonsenseIsIgnored) {
  PassSizer s;
  s.record(2, 40);
  s.record(2, 20);
  EXPECT_NEAR(s.predict(2), 30, 1e-9);
  s.record(2, std::numeric_limits<double>::quiet_NaN());
  s.record(2, -5);
  s.record(0, 10);
  EXPECT_NEAR(s.predict(2), 30, 1e-9);
  s.reset();
  EXPECT_LT(s.predict(2), 0.0);
}

// Through a real view, the ends that do not depend on the device's speed: without a frame
// target, or under one every pass meets, passes ramp 1, 2, 4, 8, 8; under one nothing meets,
// the measured pass of 8 that missed is followed by one of 4 (the sizing between is timed
// through the server, test_sessions.cpp). The white Lambertian in the furnace is 1 either way.
TEST(PassSizer, AViewKeepsItsPassesWhereTheTargetIsOutOfReachOrAlwaysMet) {
  RendererOptions options;
  options.shaderDir = std::string(BRDFA_SOURCE_DIR) + "/shaders";
  auto renderer = Renderer::create(options);
  ASSERT_TRUE(renderer.ok());
  Scene scene;
  scene.environment.name = "furnace";
  scene.environment.visible = false;
  scene.render.width = scene.render.height = 64;
  scene.render.samplesPerFrame = 8;
  scene.render.maxSamples = 23;
  scene.render.sampling = SamplingMode::Cosine;
  SceneObject o;
  o.brdf = inlineBrdf(kWhiteLambert);
  scene.objects.push_back(o);
  for (double targetMs : {0.0, 1e-3, 1e9}) {
    SCOPED_TRACE(targetMs);
    auto view = (*renderer)->createView();
    ASSERT_TRUE(view.ok());
    ASSERT_TRUE((*view)->setScene(scene).ok());
    std::vector<uint64_t> spp;  // after each complete pass
    for (int calls = 0; spp.size() < 100 && calls < 100000; ++calls) {
      auto pass = (*view)->renderPass(targetMs);
      ASSERT_TRUE(pass.ok()) << pass.error().message;
      // Under the tiny target a pass after the first returns partway at every submission
      // (RenderView::renderPass) and the next call goes on with it.
      if (targetMs != 1e-3) {
        EXPECT_FALSE(pass->passInProgress);
      }
      if (pass->passInProgress) continue;
      spp.push_back(pass->spp);
      if (pass->done()) break;
    }
    // Under the tiny target the first measured pass (of 8; the three before it carry the
    // restart's work or are split, and are not measured) missed, so the next takes half as
    // many to measure a second count.
    const std::vector<uint64_t> expected =
        targetMs == 1e-3 ? std::vector<uint64_t>{1, 3, 7, 15, 19, 23} : std::vector<uint64_t>{1, 3, 7, 15, 23};
    EXPECT_EQ(spp, expected);
    auto frame = (*view)->readFrame(true);
    ASSERT_TRUE(frame.ok());
    const Frame& f = frame.value();
    ASSERT_EQ(f.stats.spp, 23u);
    const size_t centre = 4 * (size_t(f.height / 2) * f.width + f.width / 2);
    EXPECT_NEAR(f.rgba32f[centre], 1.0f, 1e-5f);
  }
}

}  // namespace
}  // namespace brdfa
