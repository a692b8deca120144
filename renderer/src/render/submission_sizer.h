// Sizes the submissions a view's pass is split into (RenderView::renderPass): a pass is cut into
// submissions of about a device-time target each, so that the other views get the queue between
// two of them. The sizer learns what a cost unit (about one sample of one covered pixel) takes
// from the view's own measured submissions and says how many units the next one may take.
// Pure logic: the caller measures the submissions and passes their times in.
#pragma once

#include <cstdint>

namespace brdfa {

class SubmissionSizer {
 public:
  // The initial guess: the first submission after the shading changed is a probe of this many
  // units, small enough for the most loop-heavy BRDF to pass the target by little.
  static constexpr double kProbeUnits = 2048;
  // A submission takes at most this many times the largest one measured so far: a cost measured
  // where the objects are thin can be too low.
  static constexpr double kGrowth = 4;
  // The learned cost rises at once but falls by at most this factor per submission.
  static constexpr double kCostDecay = 0.75;
  // A pass's last submission may take this many budgets: no small last submission, whose fixed
  // costs would come on top for little.
  static constexpr double kTail = 1.25;
  // An interactive pass (right after a restart's first) goes in at least this many
  // submissions, so that an interruption takes effect within a fraction of it.
  static constexpr double kInteractiveSplits = 4;

  // What the next submission may take, from the pass as it stands.
  struct Request {
    double targetMs = 0;       // device time a submission aims at (0 or less: no target, no split)
    double passUnits = 0;      // the whole pass's cost units
    double passDone = 0;       // units shaded so far in this pass
    bool interactive = false;  // split in kInteractiveSplits or more (with a target only)
    double frameMs = 0;        // a watched pass's frame time: two or more submissions per frame (0: none)
  };
  struct Budget {
    double sized = 0;     // the units the sizing allows (INFINITY: no limit)
    double units = 0;     // the units the submission may take: `sized`, or INFINITY for the tail
    double targetMs = 0;  // the request's target, for record()
  };

  // What the shading runs changed, so a submission's cost is learned again (by a probe).
  // `samePrograms`: the same pipelines with other parameters (or textures, or lighting): no
  // driver compile comes with the probe, the largest submission so far still bounds the growth,
  // and the old cost is kept as how far the estimate may fall at once after the probe. Else the
  // next submission is a warm-up (it may carry the driver's compile) that teaches nothing.
  void shadingChanged(bool samePrograms);
  // Everything forgotten, as after a change of programs.
  void forget() { shadingChanged(false); }
  // A pass completed: the cost before a change of parameters no longer bounds the fall.
  void passEnded() { priorMsPerUnit_ = 0; }

  bool measured() const { return msPerUnit_ > 0; }
  double msPerUnit() const { return msPerUnit_; }  // 0: not measured
  double maxUnits() const { return maxUnits_; }    // largest submission recorded, in units

  // Samples per sweep of a pass of `count` samples, where one sample of a workgroup is
  // `groupUnits` units: as many as one workgroup's dispatch fits in the target, in [1, count];
  // `count` (no split) without a target or a measured cost.
  uint32_t samplesPerSweep(double targetMs, uint32_t count, double groupUnits) const;

  // The next submission's units: a probe of kProbeUnits while unmeasured; then what the target
  // allows at the learned cost, at most kGrowth times the largest recorded submission; at most
  // a kInteractiveSplits-th of an interactive pass, and half a watched frame. Unlimited without
  // a target, and for a measured pass's remainder within kTail budgets.
  Budget budget(const Request& request) const;

  // A submission of `units` took `ms`, sized by `budget`. The first after a change of programs
  // is a warm-up and teaches nothing. The cost is learned from submissions that filled half
  // their budget or more (a pass's small remainder carries the fixed costs and would read as
  // expensive), from any that passed the target, and from any while unmeasured. A time that is
  // negative, NaN or infinite teaches nothing.
  void record(double units, double ms, const Budget& budget);

 private:
  double msPerUnit_ = 0;       // learned device time per unit (0: not measured)
  double maxUnits_ = 0;        // the largest submission recorded, in units
  bool warmUp_ = true;         // the next submission is a warm-up
  double priorMsPerUnit_ = 0;  // msPerUnit_ before a change of parameters only (0: none)
};

}  // namespace brdfa
