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

double PassSizer::predict(uint32_t samples) const {
  if (points_.empty()) return -1;
  for (const Point& p : points_)
    if (p.samples == samples) return p.ms;
  if (points_.size() >= 2) {
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
    if (det > 0) {
      const double perSample = (n * sxy - sx * sy) / det;
      const double fixed = (sy - perSample * sx) / n;
      // guard: noise can tilt the line (a count measured under load); a pass costs at least
      // what its samples do, and more samples never cost less.
      if (perSample > 0) return std::max(fixed, 0.0) + perSample * samples;
    }
  }
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
  for (uint32_t samples = cap; samples > 1; --samples)
    if (predict(samples) <= targetMs) return samples;
  return 1;
}

}  // namespace brdfa
