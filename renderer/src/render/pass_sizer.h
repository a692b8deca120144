// Picks a progressive pass's samples per pixel from a frame-time target (RenderView::
// renderPass(frameTargetMs)): a stream frame follows each pass, and a pass of
// samples_per_frame samples can take longer than the frame interval the stream aims at.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace brdfa {

class PassSizer {
 public:
  // Forgets what passes cost (a restart: the camera, the programs or the parameters changed).
  void reset() { points_.clear(); }

  // A complete pass of `samples` samples per pixel took `ms` (device and host, as the caller
  // waited for it). Kept as a running mean per sample count, newer passes weighing more. The
  // caller leaves out passes whose time is not a pass's like the others (the first after a
  // restart, and those split for a prompt interruption).
  void record(uint32_t samples, double ms);

  // The predicted time of a pass of `samples`: its running mean when measured, else the line
  // through the measured counts (a fixed part plus a part per sample), else proportional to
  // the one count measured. Negative when nothing is measured.
  double predict(uint32_t samples) const;

  // The most samples in [floor, cap] whose predicted time is at most targetMs, where floor is
  // the most samples that take no longer than the pass's fixed part (by the line; at least 1),
  // so that about half of every pass or more goes to samples; floor when none fits. With one
  // count measured: half of it if it missed the target (to measure a second), else `cap`.
  // `cap` with nothing measured, and when floor samples would take over twice the target (the
  // frame rate is out of reach: smaller passes would only lose throughput). A wrong guess is
  // measured and corrected by the next choice.
  uint32_t fit(double targetMs, uint32_t cap) const;

 private:
  // The least-squares line ms = fixed + perSample * samples through the measured counts;
  // false with fewer than two counts or a line that does not rise.
  bool line(double& fixed, double& perSample) const;
  struct Point {
    uint32_t samples;
    double ms;
  };
  std::vector<Point> points_;  // at most kMaxPoints counts, the most recent last
  static constexpr size_t kMaxPoints = 8;
};

}  // namespace brdfa
