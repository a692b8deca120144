#include "jobs/fit_loss.h"

#include <algorithm>
#include <cmath>

#include "brdfa/image_codec.h"

namespace brdfa::server {

namespace {

// Appends `bin` with the directions at its centre unless L or V lies near the horizon.
void addBin(FitBins& out, const MerlBin& bin) {
  std::array<double, 3> L{}, V{};
  directionsFromHalfDiff(merlBinCentre(bin), L, V);
  if (L[2] <= kFitHorizonCos || V[2] <= kFitHorizonCos) return;
  DirectionPair pair;
  pair.light = Vec3{float(L[0]), float(L[1]), float(L[2])};
  pair.view = Vec3{float(V[0]), float(V[1]), float(V[2])};
  out.bins.push_back(bin);
  out.pairs.push_back(pair);
}

// Keeps the bins i for which keep(in, i) holds, in order.
template <class Keep>
FitBins keepBins(FitBins in, Keep keep) {
  FitBins out;
  for (size_t i = 0; i < in.bins.size(); ++i) {
    if (!keep(in, i)) continue;
    out.bins.push_back(in.bins[i]);
    out.pairs.push_back(in.pairs[i]);
    out.target.push_back(in.target[i]);
  }
  return out;
}

}  // namespace

const char* fitLossName(FitLoss loss) { return loss == FitLoss::Relative ? "relative" : "log"; }

bool fitLossFromName(std::string_view name, FitLoss& out) {
  if (name == "log")
    out = FitLoss::Log;
  else if (name == "relative")
    out = FitLoss::Relative;
  else
    return false;
  return true;
}

FitBins fitGridBins() {
  FitBins out;
  for (int h = 0; h < kMerlThetaHBins; ++h)
    for (int d = kFitThetaDStride / 2; d < kMerlThetaDBins; d += kFitThetaDStride)
      for (int p = kFitPhiDStride / 2; p < kMerlPhiDBins; p += kFitPhiDStride) addBin(out, MerlBin{h, d, p});
  return out;
}

FitBins residualSliceBins() {
  FitBins out;
  for (int d = 0; d < kMerlThetaDBins; ++d)
    for (int h = 0; h < kMerlThetaHBins; ++h) addBin(out, MerlBin{h, d, kResidualPhiDBin});
  return out;
}

FitBins withMeasuredTarget(FitBins bins, const MeasuredTable& table) {
  bins.target.clear();
  for (const MerlBin& b : bins.bins) {
    const float* v = &table.rgb[3 * merlIndex(b)];
    bins.target.push_back(Vec3{v[0], v[1], v[2]});
  }
  return keepBins(std::move(bins), [&](const FitBins& in, size_t i) { return table.valid(merlIndex(in.bins[i])); });
}

FitBins withEvaluatedTarget(FitBins bins, const std::vector<Vec3>& values) {
  bins.target = values;
  bins.target.resize(bins.bins.size(), Vec3{-1, -1, -1});
  return keepBins(std::move(bins), [](const FitBins& in, size_t i) {
    const Vec3& v = in.target[i];
    return std::isfinite(v[0]) && std::isfinite(v[1]) && std::isfinite(v[2]) && v[0] >= 0 && v[1] >= 0 && v[2] >= 0;
  });
}

double fitTerm(FitLoss loss, const DirectionPair& pair, double model, double target) {
  if (!std::isfinite(model)) return kFitPenalty;
  const double cosL = pair.light[2], cosV = pair.view[2];
  if (loss == FitLoss::Log) {
    // A negative model value has no logarithm: it counts as 0, its nearest meaningful value.
    return std::log1p(cosL * std::max(model, 0.0)) - std::log1p(cosL * target);
  }
  return std::sqrt(cosL * cosV) * (model - target) / std::hypot(target, kFitRelativeFloor);
}

double fitLossValue(FitLoss loss, const FitBins& bins, const std::vector<Vec3>& model) {
  if (bins.bins.empty() || model.size() < bins.bins.size()) return kFitPenalty;
  double sum = 0;
  for (size_t i = 0; i < bins.bins.size(); ++i)
    for (int c = 0; c < 3; ++c) {
      const double t = fitTerm(loss, bins.pairs[i], model[i][c], bins.target[i][c]);
      sum += t * t;
    }
  return sum / (3.0 * double(bins.bins.size()));
}

ResidualSlice residualSlice(FitLoss loss, const FitBins& slice, const std::vector<Vec3>& model) {
  ResidualSlice out;
  out.values.assign(size_t(kMerlThetaDBins) * kMerlThetaHBins, std::nullopt);
  for (size_t i = 0; i < slice.bins.size() && i < model.size(); ++i) {
    double mean = 0;
    for (int c = 0; c < 3; ++c) mean += fitTerm(loss, slice.pairs[i], model[i][c], slice.target[i][c]) / 3.0;
    out.values[size_t(slice.bins[i].thetaD) * kMerlThetaHBins + slice.bins[i].thetaH] = mean;
    out.maxAbs = std::max(out.maxAbs, std::fabs(mean));
  }
  return out;
}

std::vector<uint8_t> residualPng(const ResidualSlice& slice) {
  std::vector<uint8_t> rgba(slice.values.size() * 4, 0);
  const double scale = slice.maxAbs > 0 ? 1.0 / slice.maxAbs : 0.0;
  for (size_t i = 0; i < slice.values.size(); ++i) {
    if (!slice.values[i]) continue;  // left out: transparent
    const double t = std::clamp(*slice.values[i] * scale, -1.0, 1.0);
    // White at 0, towards red (model above target) or blue (below).
    const auto fade = [&](double x) { return uint8_t(std::lround(255.0 * (1.0 - std::fabs(t)) + x * std::fabs(t))); };
    rgba[4 * i + 0] = t > 0 ? fade(178) : fade(33);
    rgba[4 * i + 1] = t > 0 ? fade(24) : fade(102);
    rgba[4 * i + 2] = t > 0 ? fade(43) : fade(172);
    rgba[4 * i + 3] = 255;
  }
  return encodePng(rgba.data(), kMerlThetaHBins, kMerlThetaDBins);
}

}  // namespace brdfa::server
