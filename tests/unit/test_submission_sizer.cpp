// The split of a pass into submissions (SubmissionSizer): the cost per unit learned from
// measured submission times, and the units each next submission may take.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "render/submission_sizer.h"

namespace brdfa {
namespace {

constexpr double kTarget = 10;     // ms a submission aims at
constexpr double kLongPass = 1e9;  // pass units: the tail rule never applies

SubmissionSizer::Request longPass(double targetMs = kTarget) {
  SubmissionSizer::Request r;
  r.targetMs = targetMs;
  r.passUnits = kLongPass;
  return r;
}

// One simulated submission on a device whose cost is `msPerUnit`: takes the whole budget.
double submit(SubmissionSizer& s, double msPerUnit, const SubmissionSizer::Request& r = longPass()) {
  const SubmissionSizer::Budget b = s.budget(r);
  s.record(b.units, b.units * msPerUnit, b);
  return b.units;
}

// A sizer past its warm-up and with a cost learned of `msPerUnit`, at steady state.
SubmissionSizer steady(double msPerUnit, int submissions = 30) {
  SubmissionSizer s;
  for (int i = 0; i < submissions; ++i) submit(s, msPerUnit);
  return s;
}

TEST(SubmissionSizer, FirstSubmissionIsTheProbe) {
  SubmissionSizer s;
  EXPECT_FALSE(s.measured());
  const SubmissionSizer::Budget b = s.budget(longPass());
  EXPECT_EQ(b.sized, SubmissionSizer::kProbeUnits);
  EXPECT_EQ(b.units, SubmissionSizer::kProbeUnits);
  // Unmeasured, a pass is not split into sweeps.
  EXPECT_EQ(s.samplesPerSweep(kTarget, 16, 64), 16u);
}

TEST(SubmissionSizer, NoTargetMeansNoLimit) {
  SubmissionSizer s = steady(1e-3);
  const SubmissionSizer::Budget b = s.budget(longPass(0));
  EXPECT_TRUE(std::isinf(b.units));
  EXPECT_EQ(s.samplesPerSweep(0, 16, 64), 16u);
}

TEST(SubmissionSizer, TheWarmUpTeachesNothing) {
  SubmissionSizer s;
  // The first submission carries the driver's compile: a huge time that must not be learned.
  const SubmissionSizer::Budget probe = s.budget(longPass());
  s.record(probe.units, 500, probe);
  EXPECT_FALSE(s.measured());
  EXPECT_EQ(s.budget(longPass()).units, SubmissionSizer::kProbeUnits);
  // The second probe measures.
  const SubmissionSizer::Budget second = s.budget(longPass());
  s.record(second.units, 2048 * 1e-3, second);
  EXPECT_TRUE(s.measured());
  EXPECT_DOUBLE_EQ(s.msPerUnit(), 1e-3);
}

TEST(SubmissionSizer, ConvergesToTheTargetWhenCostsAreSteady) {
  const double cost = 1e-3;  // ms per unit: the target holds 10000 units
  SubmissionSizer s;
  double units = 0;
  int reached = -1;
  for (int i = 0; i < 20; ++i) {
    units = submit(s, cost);
    if (reached < 0 && std::abs(units * cost - kTarget) < 1e-9) reached = i;
  }
  ASSERT_GE(reached, 0) << "never reached the target";
  EXPECT_LE(reached, 6);  // a warm-up, a probe, then growth by kGrowth per submission
  EXPECT_NEAR(units * cost, kTarget, 1e-9);
  EXPECT_NEAR(s.msPerUnit(), cost, 1e-15);
}

TEST(SubmissionSizer, GrowsAtMostByTheGrowthFactor) {
  SubmissionSizer s;
  submit(s, 1e-6);                    // warm-up
  double previous = submit(s, 1e-6);  // probe
  for (int i = 0; i < 5; ++i) {
    const double units = submit(s, 1e-6);
    EXPECT_LE(units, SubmissionSizer::kGrowth * previous + 1e-9);
    EXPECT_GT(units, previous);
    previous = units;
  }
}

TEST(SubmissionSizer, ReactsToACostStepUpAtOnce) {
  SubmissionSizer s = steady(1e-3);
  submit(s, 4e-3);  // the cost quadruples: this submission passes the target
  EXPECT_NEAR(s.msPerUnit(), 4e-3, 1e-15);
  const double units = submit(s, 4e-3);
  EXPECT_NEAR(units * 4e-3, kTarget, 1e-9);
}

TEST(SubmissionSizer, ReactsToACostStepDownGradually) {
  SubmissionSizer s = steady(4e-3);
  double previousCost = s.msPerUnit();
  // The learned cost falls by at most kCostDecay per submission ...
  for (int i = 0; i < 3; ++i) {
    submit(s, 1e-3);
    EXPECT_GE(s.msPerUnit(), SubmissionSizer::kCostDecay * previousCost - 1e-15);
    EXPECT_LT(s.msPerUnit(), previousCost);
    previousCost = s.msPerUnit();
  }
  // ... and settles on the new cost, the submissions back at the target.
  double units = 0;
  for (int i = 0; i < 20; ++i) units = submit(s, 1e-3);
  EXPECT_NEAR(s.msPerUnit(), 1e-3, 1e-15);
  EXPECT_NEAR(units * 1e-3, kTarget, 1e-9);
}

TEST(SubmissionSizer, ClampsAtTheGrowthBoundAndTheSweepLimits) {
  SubmissionSizer s;
  submit(s, 1e-3);  // warm-up
  submit(s, 1e-3);  // probe: 2048 units, largest so far
  // The target would allow 10000 units: at most kGrowth times the largest recorded.
  EXPECT_EQ(s.budget(longPass()).units, SubmissionSizer::kGrowth * SubmissionSizer::kProbeUnits);
  // Samples per sweep: at least 1 (one workgroup's sample passing the target), at most `count`.
  EXPECT_EQ(s.samplesPerSweep(kTarget, 16, 1e9), 1u);
  EXPECT_EQ(s.samplesPerSweep(kTarget, 16, 1), 16u);
  EXPECT_EQ(s.samplesPerSweep(kTarget, 16, 2400), 4u);  // the target holds 10000 units: 4 samples
}

TEST(SubmissionSizer, InteractiveAndWatchedPassesAreSplit) {
  SubmissionSizer s = steady(1e-3);
  SubmissionSizer::Request r = longPass();
  r.passUnits = 8000;
  r.interactive = true;
  EXPECT_EQ(s.budget(r).units, 8000 / SubmissionSizer::kInteractiveSplits);
  r = longPass();
  r.frameMs = 8;  // half a frame: 4 ms, 4000 units
  EXPECT_NEAR(s.budget(r).units, 4000, 1e-9);
}

TEST(SubmissionSizer, ATailWithinOneAndAQuarterBudgetsGoesWhole) {
  SubmissionSizer s = steady(1e-3);
  SubmissionSizer::Request r = longPass();
  r.passUnits = 20000;
  r.passDone = 20000 - SubmissionSizer::kTail * 10000 + 1;  // 1 unit under the tail's limit
  EXPECT_TRUE(std::isinf(s.budget(r).units));
  EXPECT_NEAR(s.budget(r).sized, 10000, 1e-9);
  r.passDone -= 2;  // 1 unit over
  EXPECT_NEAR(s.budget(r).units, 10000, 1e-9);
}

TEST(SubmissionSizer, AHugeSingleDurationDoesNotBlowUpTheSize) {
  SubmissionSizer s = steady(1e-3);
  const double steadyUnits = s.budget(longPass()).units;
  // One submission stalls (the host was preempted).
  const SubmissionSizer::Budget b = s.budget(longPass());
  s.record(b.units, 1e6, b);
  const double after = s.budget(longPass()).units;
  EXPECT_TRUE(std::isfinite(after));
  EXPECT_GT(after, 0);
  EXPECT_LT(after, steadyUnits);
  // Back to the steady size as the cost decays, never beyond it.
  double units = 0;
  for (int i = 0; i < 60; ++i) {
    units = submit(s, 1e-3);
    EXPECT_LE(units, steadyUnits + 1e-9);
  }
  EXPECT_NEAR(units, steadyUnits, 1e-6);
}

TEST(SubmissionSizer, ATinySingleDurationDoesNotBlowUpTheSize) {
  SubmissionSizer s = steady(1e-3);
  const double steadyUnits = s.budget(longPass()).units;
  const SubmissionSizer::Budget b = s.budget(longPass());
  s.record(b.units, 1e-9, b);
  EXPECT_LE(s.budget(longPass()).units, steadyUnits / SubmissionSizer::kCostDecay + 1e-9);
}

TEST(SubmissionSizer, ZeroNegativeAndNonFiniteDurationsAreGuarded) {
  SubmissionSizer s = steady(1e-3);
  const double cost = s.msPerUnit();
  const SubmissionSizer::Budget b = s.budget(longPass());
  s.record(b.units, 0, b);  // zero: the cost falls by kCostDecay only
  EXPECT_NEAR(s.msPerUnit(), SubmissionSizer::kCostDecay * cost, 1e-15);
  const double afterZero = s.msPerUnit();
  for (double bad : {-5.0, std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity()}) {
    s.record(b.units, bad, b);
    EXPECT_EQ(s.msPerUnit(), afterZero) << bad;
  }
  const SubmissionSizer::Budget next = s.budget(longPass());
  EXPECT_TRUE(std::isfinite(next.units));
  EXPECT_GT(next.units, 0);

  // Unmeasured, a zero time leaves it unmeasured: the next is a probe again, not a division
  // by zero.
  SubmissionSizer fresh;
  submit(fresh, 1e-3);  // warm-up
  const SubmissionSizer::Budget probe = fresh.budget(longPass());
  fresh.record(probe.units, 0, probe);
  EXPECT_FALSE(fresh.measured());
  EXPECT_EQ(fresh.budget(longPass()).units, SubmissionSizer::kProbeUnits);
  // No units recorded teaches nothing either, nor uses up the warm-up.
  SubmissionSizer empty;
  empty.record(0, 5, empty.budget(longPass()));
  empty.record(-1, 5, empty.budget(longPass()));
  submit(empty, 1e-3);  // still the warm-up
  EXPECT_FALSE(empty.measured());
}

TEST(SubmissionSizer, AChangeOfParametersKeepsThePriorCostAsAFloor) {
  SubmissionSizer s = steady(1e-3);
  const double maxUnits = s.maxUnits();
  s.shadingChanged(/*samePrograms=*/true);
  EXPECT_FALSE(s.measured());
  EXPECT_EQ(s.maxUnits(), maxUnits);
  // No warm-up: the probe measures, and its high reading falls at once to the prior cost.
  const SubmissionSizer::Budget probe = s.budget(longPass());
  EXPECT_EQ(probe.units, SubmissionSizer::kProbeUnits);
  s.record(probe.units, probe.units * 20e-3, probe);
  EXPECT_NEAR(s.msPerUnit(), 20e-3, 1e-15);
  submit(s, 1e-3);
  EXPECT_NEAR(s.msPerUnit(), 1e-3, 1e-15);
  // After a completed pass the prior no longer bounds the fall.
  s.passEnded();
  s.record(1000, 1000 * 100e-3, s.budget(longPass()));
  submit(s, 1e-3);
  EXPECT_NEAR(s.msPerUnit(), SubmissionSizer::kCostDecay * 100e-3, 1e-15);
}

TEST(SubmissionSizer, AChangeOfProgramsForgetsEverything) {
  SubmissionSizer s = steady(1e-3);
  s.shadingChanged(/*samePrograms=*/false);
  EXPECT_FALSE(s.measured());
  EXPECT_EQ(s.maxUnits(), 0);
  submit(s, 1.0);  // a warm-up again: not learned
  EXPECT_FALSE(s.measured());
  s.forget();
  EXPECT_EQ(s.budget(longPass()).units, SubmissionSizer::kProbeUnits);
}

}  // namespace
}  // namespace brdfa
