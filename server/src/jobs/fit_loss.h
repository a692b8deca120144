// What a fit compares and how (POST /api/jobs/fit, fit_job.h): a model BRDF against a target at
// the centres of MERL bins, with a documented loss, and the residual over one slice of bins.
//
// The bins: MERL's grid (brdfa/measured.h) thinned to every theta_h bin, every 3rd theta_d bin
// and every 15th phi_d bin (90 x 30 x 12 = 32,400), each at its centre with phi_h = 0, less the
// bins with L or V within kFitHorizonCos of the horizon and, for a measured target, the bins
// without data. Every theta_h bin is kept: the square-root binning puts the specular peak there.
//
// The losses, over the kept bins b and channels c (f_m: the model, f_t: the target, in 1/sr):
//   log:      mean (ln(1 + cos_L f_m) - ln(1 + cos_L f_t))^2
//             (the cosine-weighted log error of Löw et al., "BRDF Models for Accurate and
//             Efficient Rendering of Glossy Surfaces", TOG 2012: peaks and floors count alike);
//   relative: mean cos_L cos_V (f_m - f_t)^2 / (f_t^2 + delta^2), delta = kFitRelativeFloor
//             (relative error, with grazing bins down-weighted by their projected solid angle).
// A model value that is not finite costs kFitPenalty per term, so the optimiser moves away.
#pragma once

#include <optional>
#include <string_view>
#include <vector>

#include "brdfa/measured.h"
#include "brdfa/renderer.h"

namespace brdfa::server {

enum class FitLoss { Log, Relative };
inline constexpr char kFitLossChoices[] = "\"log\" or \"relative\"";
const char* fitLossName(FitLoss loss);  // "log", "relative"
bool fitLossFromName(std::string_view name, FitLoss& out);

inline constexpr double kFitHorizonCos = 1e-3;
inline constexpr double kFitRelativeFloor = 1e-3;  // 1/sr
inline constexpr double kFitPenalty = 1e6;
inline constexpr int kFitThetaDStride = 3;
inline constexpr int kFitPhiDStride = 15;
// The residual slice: every theta_h and theta_d bin at this phi_d bin (its centre: 90.5 deg).
inline constexpr int kResidualPhiDBin = 90;

// Bins and the directions at their centres (phi_h = 0), in the renderer's analysis frame.
struct FitBins {
  std::vector<MerlBin> bins;
  std::vector<DirectionPair> pairs;
  std::vector<Vec3> target;  // f_r of the target at each pair, 1/sr (filled by the callers below)
};

// The fit grid above, or the residual slice (every theta_h and theta_d bin at kResidualPhiDBin),
// less the bins near the horizon.
FitBins fitGridBins();
FitBins residualSliceBins();

// Keeps the bins where `table` has data, with its values as the target.
FitBins withMeasuredTarget(FitBins bins, const MeasuredTable& table);
// Keeps the bins where `values` (a target BRDF there) are finite and >= 0 in every channel.
FitBins withEvaluatedTarget(FitBins bins, const std::vector<Vec3>& values);

// One channel's signed error term, whose square the loss averages.
double fitTerm(FitLoss loss, const DirectionPair& pair, double model, double target);
// The loss of `model` (values at bins.pairs) against bins.target.
double fitLossValue(FitLoss loss, const FitBins& bins, const std::vector<Vec3>& model);

// The residual over the slice: per bin the mean of the three channels' terms; nullopt where
// the bin is not in `slice` (left out).
struct ResidualSlice {
  std::vector<std::optional<double>> values;  // kMerlThetaDBins rows of kMerlThetaHBins
  double maxAbs = 0;
};
ResidualSlice residualSlice(FitLoss loss, const FitBins& slice, const std::vector<Vec3>& model);
// The slice on a diverging map (blue: model below target, red: above, white: equal; scaled by
// maxAbs), bins left out transparent, as PNG bytes.
std::vector<uint8_t> residualPng(const ResidualSlice& slice);

}  // namespace brdfa::server
