// Renderer::checkEnvironmentSampler (renderer.h says what it checks).
#include <algorithm>
#include <cmath>

#include "analysis/check_kernel.h"
#include "analysis/chi_square.h"
#include "analysis/device_checks.h"
#include "assets/environment_maps.h"

namespace brdfa {

namespace {

constexpr uint32_t kDraws = 1u << 20;
constexpr int kZBins = 20, kPhiBins = 40;  // equal-area bins in (cos theta, phi)
constexpr int kBlock = 4;                  // cells per block edge for the cell chi-square
constexpr int kSub = 8;                    // sub-cells per cell edge for the position chi-square
constexpr double kPi = 3.14159265358979323846;

// Any BRDF serves: the check program needs one to assemble, and never calls it.
constexpr const char* kCarrier = R"(analytic
::begin shader
vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return vec3(0.0); }
::end shader
)";

}  // namespace

namespace analysis {

Result<EnvironmentSamplerReport> checkEnvironmentSampler(const CheckDevice& device, const std::string& name) {
  auto env = device.assets.environment(name);
  if (!env) return env.takeError();
  const std::shared_ptr<const EnvironmentDistribution> dist = (*env)->distribution;
  if (!dist)
    return makeError(ErrorCode::NotFound, "environment '" + name +
                                              "' is constant: it has no table and is sampled "
                                              "uniformly over the sphere");
  auto carrier = parseBrdf(kCarrier);
  if (!carrier) return carrier.takeError();
  std::vector<float> draws;
  auto ran = runCheckKernel(
      device, carrier.value(), "check_environment.comp.glsl", kDraws, 2 * kDraws, {{}},
      [&](const float* out) { draws.assign(out, out + 8 * size_t(kDraws)); }, {}, env->get());
  if (!ran) return ran.takeError();

  const uint32_t D = dist->cellsPerEdge;
  const uint32_t blocksPerEdge = (D + kBlock - 1) / kBlock;
  const std::vector<double> cellP = dist->realisedCellProbabilities();
  std::vector<double> blockObserved(size_t(6) * blocksPerEdge * blocksPerEdge, 0.0),
      blockExpected(blockObserved.size(), 0.0);
  for (size_t c = 0; c < cellP.size(); ++c) {
    const uint32_t face = uint32_t(c / (size_t(D) * D)), in = uint32_t(c % (size_t(D) * D));
    const uint32_t bx = (in % D) / kBlock, by = (in / D) / kBlock;
    blockExpected[(size_t(face) * blocksPerEdge + by) * blocksPerEdge + bx] += cellP[c] * kDraws;
  }
  std::vector<double> subObserved(kSub * kSub, 0.0);
  // Solid-angle estimates per equal-area bin: sums of 1/pdf and of its square.
  std::vector<double> inv(kZBins * kPhiBins, 0.0), inv2(inv.size(), 0.0), binCount(inv.size(), 0.0);
  std::vector<double> binMin(inv.size(), INFINITY), binMax(inv.size(), 0.0);

  EnvironmentSamplerReport report;
  report.samples = kDraws;
  uint64_t mismatched = 0;
  for (uint32_t k = 0; k < kDraws; ++k) {
    const float* a = &draws[8 * size_t(k)];
    const float* b = a + 4;
    const float dir[3] = {a[0], a[1], a[2]};
    const double pdf = a[3];
    report.maxLengthError = std::max(
        report.maxLengthError,
        std::abs(std::sqrt(double(dir[0]) * dir[0] + double(dir[1]) * dir[1] + double(dir[2]) * dir[2]) - 1.0));
    const double device = b[0], host = dist->pdf(dir);
    const double mismatch = std::max(std::abs(device - pdf), std::abs(host - pdf)) / pdf;
    report.maxPdfMismatch = std::max(report.maxPdfMismatch, std::abs(device - pdf) / pdf);
    report.hostPdfMismatch = std::max(report.hostPdfMismatch, std::abs(host - pdf) / pdf);
    if (!(mismatch < 1e-3)) ++mismatched;

    int face;
    float s, t;
    cubeFaceCoords(dir, face, s, t);
    const double fs = (double(s) + 1.0) * 0.5 * D, ft = (double(t) + 1.0) * 0.5 * D;
    const uint32_t cx = std::min(uint32_t(std::max(fs, 0.0)), D - 1), cy = std::min(uint32_t(std::max(ft, 0.0)), D - 1);
    blockObserved[(size_t(face) * blocksPerEdge + cy / kBlock) * blocksPerEdge + cx / kBlock] += 1;
    const int sx = std::min(int((fs - cx) * kSub), kSub - 1), sy = std::min(int((ft - cy) * kSub), kSub - 1);
    subObserved[size_t(std::max(sy, 0)) * kSub + std::max(sx, 0)] += 1;

    const double z = std::clamp(double(dir[1]), -1.0, 1.0);  // +Y up: bins in latitude
    const double phi = std::atan2(double(dir[2]), double(dir[0])) + kPi;
    const int zb = std::min(int((z + 1.0) * 0.5 * kZBins), kZBins - 1);
    const int pb = std::min(int(phi / (2 * kPi) * kPhiBins), kPhiBins - 1);
    const size_t bin = size_t(zb) * kPhiBins + pb;
    inv[bin] += 1.0 / pdf;
    inv2[bin] += 1.0 / (pdf * pdf);
    binCount[bin] += 1;
    binMin[bin] = std::min(binMin[bin], pdf);
    binMax[bin] = std::max(binMax[bin], pdf);
  }
  report.pdfMismatchFraction = double(mismatched) / kDraws;
  ChiSquareResult cells = chiSquareTest(blockObserved, blockExpected);
  report.cellChi2PValue = cells.pValue;
  if (!cells.failure.empty()) report.failure = "cells: " + cells.failure;
  ChiSquareResult positions =
      chiSquareTest(subObserved, std::vector<double>(subObserved.size(), double(kDraws) / subObserved.size()));
  report.positionChi2PValue = positions.pValue;
  if (!positions.failure.empty()) report.failure += "positions: " + positions.failure;
  // E[1_bin / pdf] over all draws = the bin's solid angle 4 pi / bins; its standard error from
  // the draws' second moment. That error estimate is only reliable where 1/pdf has no heavy
  // tail inside the bin: bins whose draws' densities span more than a factor 8 (a bright cell
  // beside cells held up by the floor alone) are left out, as are bins with under 64 draws.
  const double binOmega = 4.0 * kPi / (kZBins * kPhiBins);
  for (size_t bin = 0; bin < inv.size(); ++bin) {
    if (binCount[bin] < 64 || binMax[bin] > 8.0 * binMin[bin]) continue;
    ++report.solidAngleBins;
    const double mean = inv[bin] / kDraws, second = inv2[bin] / kDraws;
    const double se = std::sqrt(std::max(second - mean * mean, 0.0) / kDraws);
    if (se > 0) report.maxSolidAngleZ = std::max(report.maxSolidAngleZ, std::abs(mean - binOmega) / se);
  }
  return report;
}

}  // namespace analysis

}  // namespace brdfa
