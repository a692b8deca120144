// Error against time: the series a session records since its last accumulation
// restart, and the straight-line fit in log-log space that GET .../convergence reports.
//
// Monte Carlo error falls as 1/sqrt(N), so with a steady pass rate log(rel_error) against
// log(elapsed) is a line of slope -1/2; a flatter slope shows bias or a restart that was missed,
// a steeper one an estimator still warming up. The intercept ranks estimators at equal time.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "brdfa/renderer.h"

namespace brdfa::server {

// One measurement of the renderer's rel_error (FrameStats::relError), taken when it was measured
// (relErrorElapsedMs, relErrorSpp), not when it was read.
struct ConvergencePoint {
  double elapsedMs = 0;  // render time since the restart
  uint64_t spp = 0;
  double relError = 0;
  uint64_t passes = 0;  // passes when the point was recorded
};

// log(rel_error) = intercept + slope * log(elapsed_ms - offsetMs), natural logarithms.
// offsetMs is the first pass's time: it holds one-off costs (the driver's JIT of a new program,
// the visibility raster) that are no sampling work, and seconds of it would bend the line for as
// long again.
struct LogLogFit {
  double slope = 0;
  double intercept = 0;
  size_t pointsUsed = 0;
  double offsetMs = 0;
};

class ConvergenceSeries {
 public:
  // At most this many points are kept: beyond it the series is thinned to one point per bin of
  // kMaxPoints/2 equal bins in log(elapsed) between its first and last point (the first and last
  // points always stay). Early points, sparse in log-time, survive; the dense late ones are
  // thinned, so the curve keeps its shape over every decade at any length.
  static constexpr size_t kMaxPoints = 2000;

  // Feeds a stats snapshot (after a pass or a frame read). An accumulation restart (spp, passes
  // or elapsed time going back, or a new scene version with no passes yet) clears the series;
  // a rel_error measured at a new relErrorSpp adds a point. Snapshots may repeat.
  void observe(const FrameStats& stats);

  const std::vector<ConvergencePoint>& points() const { return points_; }
  // Render time of the first pass since the restart (0 until seen).
  double firstPassMs() const { return firstPassMs_; }
  void clear();

 private:
  std::vector<ConvergencePoint> points_;
  uint64_t lastSpp_ = 0, lastPasses_ = 0, lastVersion_ = 0, lastErrorSpp_ = 0;
  double lastElapsed_ = 0;
  double firstPassMs_ = 0;
};

// Keeps at most `maxPoints` (>= 2) of `points`, one per bin of maxPoints-1 equal bins in
// log(elapsed) (the last point of each bin), plus the first point.
std::vector<ConvergencePoint> thinLogTime(const std::vector<ConvergencePoint>& points, size_t maxPoints);

// Least squares of log(rel_error) on log(t), t = elapsed_ms - offsetMs, over the points after
// the first 10% of the series' time (t >= 0.1 * the last t), or the last 3 when fewer are
// there; points with rel_error or t <= 0 are left out. nullopt with fewer than 3 usable points
// or no spread in time.
std::optional<LogLogFit> fitLogLog(const std::vector<ConvergencePoint>& points, double offsetMs = 0);

// Elapsed ms (offset included) at which the fitted line reaches `targetError`; nullopt unless
// the slope is negative and the answer finite.
std::optional<double> predictMs(const LogLogFit& fit, double targetError);

}  // namespace brdfa::server
