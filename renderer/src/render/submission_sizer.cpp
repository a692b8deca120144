#include "render/submission_sizer.h"

#include <algorithm>
#include <cmath>

namespace brdfa {

void SubmissionSizer::shadingChanged(bool samePrograms) {
  // The same pipelines with other parameters: the old cost is a fair guess, kept to let the
  // estimate fall to it after the probe.
  priorMsPerUnit_ = samePrograms ? msPerUnit_ : 0;
  msPerUnit_ = 0;
  if (!samePrograms) {
    maxUnits_ = 0;
    warmUp_ = true;
  }
}

uint32_t SubmissionSizer::samplesPerSweep(double targetMs, uint32_t count, double groupUnits) const {
  if (!(targetMs > 0) || msPerUnit_ <= 0) return count;
  return static_cast<uint32_t>(std::clamp(std::floor(targetMs / msPerUnit_ / groupUnits), 1.0, double(count)));
}

SubmissionSizer::Budget SubmissionSizer::budget(const Request& r) const {
  Budget b;
  b.targetMs = r.targetMs;
  b.sized = std::min({r.targetMs <= 0   ? INFINITY
                      : msPerUnit_ <= 0 ? kProbeUnits
                                        : std::min(r.targetMs / msPerUnit_, kGrowth * maxUnits_),
                      r.interactive && r.targetMs > 0 ? r.passUnits / kInteractiveSplits : INFINITY,
                      r.frameMs > 0 && msPerUnit_ > 0 ? 0.5 * r.frameMs / msPerUnit_ : INFINITY});
  b.units = msPerUnit_ > 0 && r.passUnits - r.passDone <= kTail * b.sized ? INFINITY : b.sized;
  return b;
}

void SubmissionSizer::record(double units, double ms, const Budget& b) {
  // The first submission of a shading can carry the driver's compile of its pipeline (lavapipe
  // compiles at the first dispatch): learned from it, the cost reads orders of magnitude too
  // high, and the view would go on in one-workgroup submissions, each waiting its turn behind
  // every other view's. A second probe measures.
  // A probe's few units carry a whole submission's fixed costs (wake-ups, fence): for a plain
  // BRDF it reads far too high, and falling from there by kCostDecay would take a slider's pass
  // many submissions. After a change of parameters only, the estimate may fall at once as far
  // as the cost before the change.
  // The cost falls by at most kCostDecay per submission: where an object is thin (the bottom of
  // a sphere, before the next pass starts at its top) its covered pixels are few and the
  // measure is noisy, and a low reading would make the next submission too long.
  if (units > 0 && warmUp_) {
    warmUp_ = false;
  } else if (units > 0 && std::isfinite(ms) && ms >= 0 &&
             (msPerUnit_ <= 0 || units >= 0.5 * b.sized || ms > b.targetMs)) {
    const double floor =
        priorMsPerUnit_ > 0 ? std::min(kCostDecay * msPerUnit_, priorMsPerUnit_) : kCostDecay * msPerUnit_;
    msPerUnit_ = std::max(ms / units, floor);
  }
  maxUnits_ = std::max(maxUnits_, units);
}

}  // namespace brdfa
