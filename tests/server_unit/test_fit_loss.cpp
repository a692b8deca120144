// The fit job's host side: its bins, its losses against hand-computed values, the residual
// slice, and the .brdf text with fitted defaults.
#include <gtest/gtest.h>

#include <cmath>

#include "brdfa/brdf.h"
#include "jobs/fit_job.h"
#include "jobs/fit_loss.h"

namespace brdfa::server {
namespace {

TEST(FitLoss, TheGridKeepsBinsAboveTheHorizonAtTheirCentres) {
  const FitBins grid = fitGridBins();
  const size_t full = size_t(kMerlThetaHBins) * (kMerlThetaDBins / kFitThetaDStride) * (kMerlPhiDBins / kFitPhiDStride);
  EXPECT_GT(grid.bins.size(), full / 2);
  EXPECT_LT(grid.bins.size(), full);  // some centres lie below the horizon
  ASSERT_EQ(grid.pairs.size(), grid.bins.size());
  for (size_t i = 0; i < grid.bins.size(); i += 97) {
    EXPECT_GT(grid.pairs[i].light[2], kFitHorizonCos);
    EXPECT_GT(grid.pairs[i].view[2], kFitHorizonCos);
    // Each pair maps back to its own bin.
    const MerlBin back = merlBinOf(halfDiffFromDirections(grid.pairs[i].light, grid.pairs[i].view));
    EXPECT_EQ(back.thetaH, grid.bins[i].thetaH);
    EXPECT_EQ(back.thetaD, grid.bins[i].thetaD);
    EXPECT_EQ(back.phiD, grid.bins[i].phiD);
  }
}

TEST(FitLoss, TheLossesMatchTheirFormulas) {
  DirectionPair pair;
  const float c = std::sqrt(0.5f);
  pair.light = Vec3{c, 0, c};
  pair.view = Vec3{0, 0, 1};
  // log: ln(1 + cos_L f_m) - ln(1 + cos_L f_t).
  EXPECT_NEAR(fitTerm(FitLoss::Log, pair, 2.0, 1.0), std::log(1 + c * 2.0) - std::log(1 + c * 1.0), 1e-6);
  EXPECT_NEAR(fitTerm(FitLoss::Log, pair, -5.0, 0.0), 0.0, 1e-12);  // negative counts as 0
  // relative: sqrt(cos_L cos_V) (f_m - f_t) / hypot(f_t, delta).
  EXPECT_NEAR(fitTerm(FitLoss::Relative, pair, 3.0, 2.0), std::sqrt(c) * 1.0 / std::hypot(2.0, kFitRelativeFloor),
              1e-6);
  EXPECT_EQ(fitTerm(FitLoss::Log, pair, NAN, 1.0), kFitPenalty);

  FitBins bins;
  bins.bins = {MerlBin{0, 0, 0}, MerlBin{1, 0, 0}};
  bins.pairs = {pair, pair};
  bins.target = {Vec3{1, 1, 1}, Vec3{0.5f, 0.5f, 0.5f}};
  EXPECT_EQ(fitLossValue(FitLoss::Log, bins, bins.target), 0.0);
  const std::vector<Vec3> model = {Vec3{2, 1, 1}, Vec3{0.5f, 0.5f, 0.5f}};
  const double t = fitTerm(FitLoss::Log, pair, 2.0, 1.0);
  EXPECT_NEAR(fitLossValue(FitLoss::Log, bins, model), t * t / 6.0, 1e-9);  // mean over 2 bins x 3 channels

  const ResidualSlice slice = residualSlice(FitLoss::Log, bins, model);
  ASSERT_EQ(slice.values.size(), size_t(kMerlThetaDBins) * kMerlThetaHBins);
  EXPECT_NEAR(*slice.values[0], t / 3.0, 1e-9);
  EXPECT_EQ(*slice.values[1], 0.0);
  EXPECT_FALSE(slice.values[2].has_value());
  EXPECT_NEAR(slice.maxAbs, t / 3.0, 1e-9);
}

TEST(FitLoss, MeasuredAndEvaluatedTargetsKeepOnlyBinsWithValues) {
  FitBins bins;
  bins.bins = {MerlBin{0, 0, 0}, MerlBin{0, 0, 1}, MerlBin{0, 0, 2}};
  bins.pairs.resize(3);
  const FitBins evaluated = withEvaluatedTarget(bins, {Vec3{1, 1, 1}, Vec3{NAN, 0, 0}, Vec3{0, -1, 0}});
  ASSERT_EQ(evaluated.bins.size(), 1u);
  EXPECT_EQ(evaluated.bins[0].phiD, 0);

  MeasuredTable table;
  table.rgb.assign(3 * kMerlBins, 0.25f);
  for (int c = 0; c < 3; ++c) table.rgb[3 * merlIndex(MerlBin{0, 0, 1}) + c] = -1.0f;
  const FitBins measured = withMeasuredTarget(bins, table);
  ASSERT_EQ(measured.bins.size(), 2u);
  EXPECT_EQ(measured.bins[1].phiD, 2);
  EXPECT_EQ(measured.target[1][2], 0.25f);
}

TEST(FitJob, TheSourceCarriesTheFittedValuesAsDefaults) {
  const std::string source =
      "# a test\n::begin parameters\nfloat roughness 0.001 1 0.3    # width\ncolor F0 0.95 0.64 0.54\nbool flip 0\n"
      "::end parameters\n::begin shader\nvec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return F0 * roughness; "
      "}\n::end shader\n";
  Result<BrdfDefinition> def = parseBrdf(source);
  ASSERT_TRUE(def.ok());
  const std::string out =
      sourceWithDefaults(source, def.value(), {{"roughness", Vec3{0.125f, 0, 0}}, {"F0", Vec3{0.5f, 0.25f, 1}}});
  EXPECT_NE(out.find("float roughness 0.001 1 0.125    # width\n"), std::string::npos) << out;
  EXPECT_NE(out.find("color F0 0.5 0.25 1\n"), std::string::npos) << out;
  EXPECT_NE(out.find("bool flip 0\n"), std::string::npos) << out;  // not fitted: as it was
  Result<BrdfDefinition> back = parseBrdf(out);
  ASSERT_TRUE(back.ok());
  EXPECT_EQ(back.value().findParam("roughness")->defaultValue[0], 0.125f);
  EXPECT_EQ(back.value().shader, def.value().shader);
}

}  // namespace
}  // namespace brdfa::server
