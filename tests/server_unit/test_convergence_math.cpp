// The server's convergence maths without a device: the series a session records (restarts,
// bounded length, thinning in log-time), the log-log fit and its prediction, and the strategy
// job's true relative error against a reference.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "jobs/convergence.h"
#include "jobs/convergence_job.h"

namespace brdfa::server {
namespace {

// Stats after `passes` passes of one sample taking `msPerPass`, with the error measured now
// and falling as c / sqrt(spp).
FrameStats statsAt(uint64_t passes, double msPerPass, double firstPassMs = 0, uint64_t version = 1) {
  FrameStats s;
  s.passes = passes;
  s.spp = passes;
  s.elapsedMs = firstPassMs + msPerPass * static_cast<double>(passes - (firstPassMs > 0 ? 1 : 0));
  s.relErrorSpp = s.spp;
  s.relErrorElapsedMs = s.elapsedMs;
  s.relError = 2.0 / std::sqrt(static_cast<double>(s.spp));
  s.sceneVersion = version;
  return s;
}

TEST(ConvergenceSeries, RecordsEachNewMeasurementOnce) {
  ConvergenceSeries series;
  FrameStats fresh;
  fresh.sceneVersion = 1;
  series.observe(fresh);
  EXPECT_TRUE(series.points().empty()) << "no measurement yet";
  for (uint64_t p = 1; p <= 10; ++p) {
    series.observe(statsAt(p, 5));
    series.observe(statsAt(p, 5));  // the same snapshot again (a frame read after the pass)
  }
  ASSERT_EQ(series.points().size(), 10u);
  EXPECT_EQ(series.points().back().spp, 10u);
  EXPECT_EQ(series.points().back().passes, 10u);
  EXPECT_DOUBLE_EQ(series.points().back().elapsedMs, 50.0);
  // A pass without a new measurement adds nothing.
  FrameStats later = statsAt(11, 5);
  later.relErrorSpp = 10;
  series.observe(later);
  EXPECT_EQ(series.points().size(), 10u);
}

TEST(ConvergenceSeries, RestartsWhenTheAccumulationDoes) {
  ConvergenceSeries series;
  for (uint64_t p = 1; p <= 20; ++p) series.observe(statsAt(p, 5));
  ASSERT_EQ(series.points().size(), 20u);
  // A display-only change: a new version, the samples kept.
  FrameStats same = statsAt(20, 5, 0, 2);
  series.observe(same);
  EXPECT_EQ(series.points().size(), 20u);
  // A restart: a new version with no passes yet.
  FrameStats restarted;
  restarted.sceneVersion = 3;
  series.observe(restarted);
  EXPECT_TRUE(series.points().empty());
  for (uint64_t p = 1; p <= 5; ++p) series.observe(statsAt(p, 5, 0, 3));
  EXPECT_EQ(series.points().size(), 5u);
  // A restart seen only after some passes (spp went back).
  series.observe(statsAt(2, 5, 0, 4));
  EXPECT_EQ(series.points().size(), 1u);
}

TEST(ConvergenceSeries, StaysBoundedAndKeepsEveryDecade) {
  ConvergenceSeries series;
  const uint64_t total = 20000;
  for (uint64_t p = 1; p <= total; ++p) {
    series.observe(statsAt(p, 1));
    ASSERT_LE(series.points().size(), ConvergenceSeries::kMaxPoints);
  }
  const auto& pts = series.points();
  EXPECT_EQ(pts.front().spp, 1u) << "the first point stays";
  EXPECT_GT(pts.size(), ConvergenceSeries::kMaxPoints / 4);
  for (size_t i = 1; i < pts.size(); ++i) ASSERT_GT(pts[i].elapsedMs, pts[i - 1].elapsedMs);
  // Every decade of time keeps points.
  for (double decade : {1.0, 10.0, 100.0, 1000.0}) {
    size_t in = 0;
    for (const auto& p : pts) in += p.elapsedMs >= decade && p.elapsedMs < 10 * decade;
    EXPECT_GE(in, 2u) << "decade " << decade;
  }
}

TEST(ConvergenceSeries, ThinningKeepsFirstAndLast) {
  std::vector<ConvergencePoint> pts;
  for (int i = 1; i <= 500; ++i) pts.push_back({double(i), uint64_t(i), 1.0 / i, uint64_t(i)});
  auto thin = thinLogTime(pts, 10);
  ASSERT_LE(thin.size(), 10u);
  ASSERT_GE(thin.size(), 2u);
  EXPECT_EQ(thin.front().spp, 1u);
  EXPECT_EQ(thin.back().spp, 500u);
  EXPECT_EQ(thinLogTime(pts, 1000).size(), pts.size()) << "short enough: unchanged";
}

TEST(LogLogFit, FindsTheMonteCarloSlopeBehindAFirstPassOffset) {
  // A slow first pass (a driver compile) of 500 ms, then 1 ms per sample.
  ConvergenceSeries series;
  for (uint64_t p = 1; p <= 4000; ++p) series.observe(statsAt(p, 1, 500));
  EXPECT_DOUBLE_EQ(series.firstPassMs(), 500.0);
  auto fit = fitLogLog(series.points(), series.firstPassMs());
  ASSERT_TRUE(fit);
  EXPECT_NEAR(fit->slope, -0.5, 0.01);
  EXPECT_GE(fit->pointsUsed, 3u);
  // Without the offset the same data bends away from -0.5.
  auto raw = fitLogLog(series.points(), 0);
  ASSERT_TRUE(raw);
  EXPECT_LT(raw->slope, -0.6);
  // err = 2 / sqrt(spp) reaches 0.01 at spp = 40000, i.e. 500 + 39999 ms.
  auto ms = predictMs(*fit, 0.01);
  ASSERT_TRUE(ms);
  EXPECT_NEAR(*ms, 500 + 39999, 800);
  EXPECT_FALSE(predictMs(LogLogFit{0.1, 0, 3, 0}, 0.01)) << "a rising line never gets there";
}

TEST(LogLogFit, NeedsThreeUsablePoints) {
  std::vector<ConvergencePoint> pts{{10, 1, 0.5, 1}, {20, 2, 0.3, 2}};
  EXPECT_FALSE(fitLogLog(pts));
  pts.push_back({40, 4, 0.0, 4});  // rel_error 0 has no logarithm
  EXPECT_FALSE(fitLogLog(pts));
  pts.push_back({80, 8, 0.1, 8});
  EXPECT_TRUE(fitLogLog(pts));
}

std::vector<float> image(const std::vector<float>& lums) {
  std::vector<float> rgba;
  for (float l : lums) rgba.insert(rgba.end(), {l, l, l, 1.0f});
  return rgba;
}

TEST(TrueRelError, SubtractsTheReferenceVariance) {
  // Reference 1 on 4 pixels, 0 (background, left out) on 2.
  std::vector<float> ref = image({1, 1, 1, 1, 0, 0});
  std::vector<float> x = image({1.5f, 0.5f, 1.5f, 0.5f, 7, 7});
  double mean = 0, raw = 0;
  size_t pixels = 0;
  auto e = trueRelError(x, ref, 0, &mean, &pixels, &raw);
  ASSERT_TRUE(e);
  EXPECT_EQ(pixels, 4u);
  EXPECT_NEAR(mean, 1.0, 1e-6);
  EXPECT_NEAR(*e, 0.5, 1e-6);  // sqrt(mean (0.5^2)) / 1
  EXPECT_NEAR(raw, 0.5, 1e-6);
  // A reference with its own rel_error 0.3: variance 0.09 of the 0.25 is the reference's.
  e = trueRelError(x, ref, 0.3, nullptr, nullptr, &raw);
  ASSERT_TRUE(e);
  EXPECT_NEAR(*e, 0.4, 1e-6);
  EXPECT_NEAR(raw, 0.5, 1e-6);
  // Never negative: a reference noisier than the difference gives 0.
  e = trueRelError(x, ref, 0.9);
  ASSERT_TRUE(e);
  EXPECT_EQ(*e, 0.0);
  EXPECT_FALSE(trueRelError(x, image({0, 0, 0, 0, 0, 0}), 0)) << "no reference pixel lit";
}

TEST(TrueRelError, MatchesTheSpreadOfNoise) {
  std::mt19937 rng(7);
  std::normal_distribution<float> noise(0.0f, 0.1f);
  std::vector<float> refL(10000, 2.0f), xL(10000);
  for (float& v : xL) v = 2.0f + noise(rng);
  auto e = trueRelError(image(xL), image(refL), 0);
  ASSERT_TRUE(e);
  EXPECT_NEAR(*e, 0.05, 0.002);  // sigma / mean
}

}  // namespace
}  // namespace brdfa::server
