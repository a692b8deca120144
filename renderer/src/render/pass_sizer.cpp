#include "pass_sizer.h"

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
  if (points_.empty() || cap <= 1) return std::max<uint32_t>(cap, 1);
  // Out of reach: even one sample misses the frame (a large image on a CPU device). Smaller
  // passes would only spend more of the time on their fixed part.
  if (predict(1) > targetMs) return cap;
  // Never so few samples that the pass's fixed part outweighs them: at least half of a pass
  // goes to samples, whatever the target.
  uint32_t floor = 1;
  double fixed = 0, perSample = 0;
  if (line(fixed, perSample)) floor = static_cast<uint32_t>(std::min<double>(std::ceil(fixed / perSample), cap));
  for (uint32_t samples = cap; samples > floor; --samples)
    if (predict(samples) <= targetMs) return samples;
  return std::max<uint32_t>(floor, 1);
}

}  // namespace brdfa
