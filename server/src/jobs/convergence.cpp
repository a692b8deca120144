#include "jobs/convergence.h"

#include <algorithm>
#include <cmath>

namespace brdfa::server {

namespace {

// Elapsed times are > 0 after the first pass; the floor only keeps log() finite.
double logTime(double ms) { return std::log(std::max(ms, 1e-3)); }

}  // namespace

void ConvergenceSeries::clear() {
  points_.clear();
  lastSpp_ = lastPasses_ = lastErrorSpp_ = 0;
  lastElapsed_ = 0;
  firstPassMs_ = 0;
}

void ConvergenceSeries::observe(const FrameStats& s) {
  const bool restarted = s.spp < lastSpp_ || s.passes < lastPasses_ || s.elapsedMs < lastElapsed_ ||
                         (s.sceneVersion != lastVersion_ && s.passes == 0);
  if (restarted) clear();
  lastSpp_ = s.spp;
  lastPasses_ = s.passes;
  lastElapsed_ = s.elapsedMs;
  lastVersion_ = s.sceneVersion;
  if (s.passes == 1) firstPassMs_ = s.elapsedMs;
  if (s.relErrorSpp == 0 || s.relErrorSpp == lastErrorSpp_ || s.relErrorSpp > s.spp) return;
  lastErrorSpp_ = s.relErrorSpp;
  if (!s.relError || !std::isfinite(*s.relError)) return;
  points_.push_back(ConvergencePoint{s.relErrorElapsedMs, s.relErrorSpp, *s.relError, s.passes});
  if (points_.size() > kMaxPoints) points_ = thinLogTime(points_, kMaxPoints / 2);
}

std::vector<ConvergencePoint> thinLogTime(const std::vector<ConvergencePoint>& points, size_t maxPoints) {
  maxPoints = std::max<size_t>(maxPoints, 2);
  if (points.size() <= maxPoints) return points;
  const double l0 = logTime(points.front().elapsedMs);
  const double l1 = logTime(points.back().elapsedMs);
  std::vector<ConvergencePoint> out{points.front()};
  if (!(l1 > l0)) {
    out.push_back(points.back());
    return out;
  }
  const size_t bins = maxPoints - 1;
  size_t lastBin = SIZE_MAX;
  for (size_t i = 1; i < points.size(); ++i) {
    const double u = (logTime(points[i].elapsedMs) - l0) / (l1 - l0);
    const size_t bin = std::min(bins - 1, static_cast<size_t>(std::max(0.0, u) * static_cast<double>(bins)));
    // Points come in time order: a point of the bin just seen replaces it (the last one stays).
    if (bin == lastBin && out.size() > 1)
      out.back() = points[i];
    else
      out.push_back(points[i]);
    lastBin = bin;
  }
  return out;
}

std::optional<LogLogFit> fitLogLog(const std::vector<ConvergencePoint>& points, double offsetMs) {
  std::vector<const ConvergencePoint*> usable;
  for (const ConvergencePoint& p : points)
    if (p.relError > 0 && p.elapsedMs - offsetMs > 0 && std::isfinite(p.relError)) usable.push_back(&p);
  if (usable.size() < 3) return std::nullopt;
  auto t = [&](size_t i) { return usable[i]->elapsedMs - offsetMs; };
  const double cut = 0.1 * t(usable.size() - 1);
  size_t first = 0;
  while (first < usable.size() && t(first) < cut) ++first;
  first = std::min(first, usable.size() - 3);
  const double n = static_cast<double>(usable.size() - first);
  double sx = 0, sy = 0;
  for (size_t i = first; i < usable.size(); ++i) {
    sx += std::log(t(i));
    sy += std::log(usable[i]->relError);
  }
  const double mx = sx / n, my = sy / n;
  double sxx = 0, sxy = 0;
  for (size_t i = first; i < usable.size(); ++i) {
    const double dx = std::log(t(i)) - mx;
    sxx += dx * dx;
    sxy += dx * (std::log(usable[i]->relError) - my);
  }
  if (!(sxx > 1e-12)) return std::nullopt;
  LogLogFit fit;
  fit.slope = sxy / sxx;
  fit.intercept = my - fit.slope * mx;
  fit.pointsUsed = usable.size() - first;
  fit.offsetMs = offsetMs;
  if (!std::isfinite(fit.slope) || !std::isfinite(fit.intercept)) return std::nullopt;
  return fit;
}

std::optional<double> predictMs(const LogLogFit& fit, double targetError) {
  if (!(fit.slope < 0) || !(targetError > 0)) return std::nullopt;
  const double ms = fit.offsetMs + std::exp((std::log(targetError) - fit.intercept) / fit.slope);
  if (!std::isfinite(ms)) return std::nullopt;
  return ms;
}

}  // namespace brdfa::server
