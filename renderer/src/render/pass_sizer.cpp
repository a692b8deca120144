#include "render/pass_sizer.h"

#include <algorithm>
#include <cmath>

namespace brdfa {

void PassSizer::record(uint32_t samples, double ms) {
  if (samples == 0 || !(ms >= 0)) return;  // guard: a NaN or negative time teaches nothing
  auto it = std::find_if(points_.begin(), points_.end(), [&](const Point& p) { return p.samples == samples; });
  if (it != points_.end()) {
    // Half the weight on the newest: the load of a shared CPU moves pass times from one
    // second to the next, and the sizing should follow it within a few passes.
    Point p{samples, 0.5 * (it->ms + ms)};
    points_.erase(it);
    points_.push_back(p);
    return;
  }
  if (points_.size() == kMaxPoints) points_.erase(points_.begin());
  points_.push_back({samples, ms});
}

bool PassSizer::line(double& fixed, double& perSample) const {
  if (points_.size() < 2) return false;
  // Least squares over the measured counts: ms = fixed + perSample * samples.
  double n = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
  for (const Point& p : points_) {
    n += 1;
    sx += p.samples;
    sy += p.ms;
    sxx += double(p.samples) * p.samples;
    sxy += p.samples * p.ms;
  }
  const double det = n * sxx - sx * sx;
  if (!(det > 0)) return false;
  perSample = (n * sxy - sx * sy) / det;
  fixed = std::max((sy - perSample * sx) / n, 0.0);
  // guard: noise can tilt the line (a count measured under load); more samples never cost less.
  return perSample > 0;
}

double PassSizer::predict(uint32_t samples) const {
  if (points_.empty()) return -1;
  for (const Point& p : points_)
    if (p.samples == samples) return p.ms;
  double fixed = 0, perSample = 0;
  if (line(fixed, perSample)) return fixed + perSample * samples;
  // One count measured (or a useless line): in proportion to the nearest measured count,
  // which overestimates larger passes (their fixed part is counted again) and so grows them
  // with care.
  const Point* nearest = &points_.back();
  for (const Point& p : points_)
    if (std::abs(double(p.samples) - samples) < std::abs(double(nearest->samples) - samples)) nearest = &p;
  return nearest->ms * samples / nearest->samples;
}

uint32_t PassSizer::fit(double targetMs, uint32_t cap) const {
  if (cap <= 1) return 1;
  double fixed = 0, perSample = 0;
  if (!line(fixed, perSample)) {
    // One count measured (or a line that does not rise): nothing tells a pass's fixed part
    // from its samples. Where that count missed the target, half as many once measure a
    // second count; sized from one count alone, a pass that missed could be followed by
    // passes of the same size forever.
    if (points_.size() == 1 && points_[0].ms > targetMs && points_[0].samples > 1)
      return std::min(cap, points_[0].samples / 2);
    return cap;
  }
  // Never fewer samples than fit in the pass's fixed part's time: about half of a pass or more
  // goes to samples. Rounded down: the line is measured under noise, and a floor one too high
  // makes small passes larger than the frame rate allows.
  const uint32_t floor = static_cast<uint32_t>(std::clamp(std::floor(fixed / perSample), 1.0, double(cap)));
  // Out of reach: even that many would take twice the frame (a large image on a CPU device);
  // smaller passes would only spend more of the time on their fixed part.
  if (predict(floor) > 2 * targetMs) return cap;
  for (uint32_t samples = cap; samples > floor; --samples)
    if (predict(samples) <= targetMs) return samples;
  return floor;
}

}  // namespace brdfa
