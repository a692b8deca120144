// Renderer::checkSampler: numeric checks of a BRDF's sampler on the device (SamplerCheckReport
// in renderer.h; shaders/kernels/check_sampler.comp.glsl).
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>

#include "analysis/check_kernel.h"
#include "analysis/chi_square.h"
#include "analysis/device_checks.h"
#include "programs/brdf_features.h"

namespace brdfa {

namespace {

// check_sampler.comp.glsl: per configuration kSamplerChunks invocations of kChunkSamples draws,
// each writing 128 cells + 3 summary vec4 + the chi-square histogram of 10 x 20 cells (four
// counts to a vec4); then, with pdfBRDF, one invocation per 4 chi-square cells and
// configuration computing their probabilities.
constexpr uint32_t kSamplerChunks = 8, kChunkSamples = 2048, kCells = 128, kSummaryVec4s = 3;
constexpr uint32_t kChi2Cells = 10 * 20, kChi2Vec4s = kChi2Cells / 4;
constexpr uint32_t kSamplerStride = kCells + kSummaryVec4s + kChi2Vec4s;
constexpr double kChi2Significance = 0.01;  // pbrt-v4's CHI2_SLEVEL, before the Sidak correction
constexpr double kChi2MinExpected = 5.0;    // pbrt-v4's CHI2_MINFREQ: smaller cells are pooled
constexpr double kZLimit = 5.0;             // SamplerCheckReport::passed's default
constexpr double kPi = 3.14159265358979323846;
constexpr double kPerConfig = double(kSamplerChunks) * kChunkSamples;  // draws per configuration
constexpr double kCellSolidAngle = 2.0 * kPi / kCells;

using D3 = std::array<double, 3>;
D3 add(const D3& a, const D3& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
D3 scaled(const D3& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
double dot(const D3& a, const D3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
D3 cross(const D3& a, const D3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
D3 normalized(const D3& a) { return scaled(a, 1.0 / std::sqrt(dot(a, a))); }
Vec3 toFloat(const D3& a) { return {float(a[0]), float(a[1]), float(a[2])}; }

// The configurations of checkSampler: shading normals of every kind a mesh gives the integrator
// (exactly on an axis; within 1e-3 rad of each axis, where frame constructions that branch on
// a component of N switch; a few degrees from +-z, inside the usual |N.z| > 0.999 branch;
// arbitrary), each with X, Y orthonormal around N (built in double, turned by a different angle
// about N per normal; one frame left-handed, as mirrored UVs give), and views at 0, 30, 60, 80
// and 89 degrees from N at azimuths that vary with the normal and the angle (eight in all).
std::vector<SamplerCheckConfig> samplerConfigs() {
  struct Normal {
    std::string label;
    D3 n;
  };
  const double e = 1e-3;
  std::vector<Normal> normals = {{"+z", {0, 0, 1}}, {"-z", {0, 0, -1}}};
  const char* axisNames[3] = {"x", "y", "z"};
  for (int axis = 0; axis < 3; ++axis)
    for (double sign : {1.0, -1.0}) {
      // Offset towards both other axes (weights 1 and 0.7): a frame code that branches on one
      // component and forgets to orthogonalise against the other is caught either way.
      D3 a{0, 0, 0}, d{0, 0, 0};
      a[axis] = sign;
      d[(axis + 1) % 3] = 1.0;
      d[(axis + 2) % 3] = 0.7;
      d = normalized(d);
      normals.push_back({std::string("near ") + (sign > 0 ? "+" : "-") + axisNames[axis] + " (1e-3 rad)",
                         normalized(add(scaled(a, std::cos(e)), scaled(d, std::sin(e))))});
    }
  auto tilted = [](double deg, double azimuthDeg, double zSign) {
    double t = deg * kPi / 180, p = azimuthDeg * kPi / 180;
    return D3{std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), zSign * std::cos(t)};
  };
  normals.push_back({"2 deg from +z", tilted(2.0, 30.0, 1.0)});
  normals.push_back({"1.5 deg from -z", tilted(1.5, 200.0, -1.0)});
  normals.push_back({"arbitrary", normalized({1, 2, 3})});
  normals.push_back({"arbitrary", normalized({-0.8, 0.1, -0.6})});
  normals.push_back({"arbitrary, left-handed X, Y", normalized({0.2, -0.9, 0.4})});

  const double viewDegs[] = {0, 30, 60, 80, 89};
  std::vector<SamplerCheckConfig> configs;
  for (size_t i = 0; i < normals.size(); ++i) {
    const D3 n = normals[i].n;
    D3 x{1, 0, 0}, y{0, 1, 0};
    if (i != 0) {  // +z keeps the frame of the original check (X = +x, Y = +y)
      // The axis least aligned with N, made orthogonal to it, then turned about N.
      int least = 0;
      for (int k = 1; k < 3; ++k)
        if (std::fabs(n[k]) < std::fabs(n[least])) least = k;
      D3 h{0, 0, 0};
      h[least] = 1;
      D3 x0 = normalized(add(h, scaled(n, -dot(h, n))));
      D3 y0 = cross(n, x0);
      double psi = (25.0 * double(i)) * kPi / 180;
      x = add(scaled(x0, std::cos(psi)), scaled(y0, std::sin(psi)));
      y = cross(n, x);
      // Mirrored tangent frames (negative handedness) give the integrator Y = -(N x X).
      if (normals[i].label.find("left-handed") != std::string::npos) y = scaled(y, -1.0);
    }
    for (size_t k = 0; k < std::size(viewDegs); ++k) {
      SamplerCheckConfig c;
      c.normalLabel = normals[i].label;
      c.viewDeg = viewDegs[k];
      c.viewAzimuthDeg = viewDegs[k] == 0 ? 0 : 45.0 * double((i + 3 * k) % 8);
      double t = c.viewDeg * kPi / 180, p = c.viewAzimuthDeg * kPi / 180;
      D3 v = add(scaled(n, std::cos(t)), scaled(add(scaled(x, std::cos(p)), scaled(y, std::sin(p))), std::sin(t)));
      c.normal = toFloat(n);
      c.tangent = toFloat(x);
      c.bitangent = toFloat(y);
      c.view = toFloat(v);
      configs.push_back(c);
    }
  }
  return configs;
}

std::string formatG(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

// z-score of a mean estimated from n samples with the given sums against `expected`.
double zScore(double sum, double sumSq, double n, double expected) {
  double mean = sum / n;
  double var = std::max(sumSq / n - mean * mean, 0.0) / std::max(n - 1.0, 1.0);
  double diff = mean - expected;
  if (var <= 0) return diff == 0 ? 0 : INFINITY;
  return std::fabs(diff) / std::sqrt(var);
}

// One configuration's results from the kernel's output `out` (the `ci`-th configuration; the
// chi-square probabilities follow `samplingInvocations` invocations' output): its measures and
// the check nearest to its limit. Counts its samples and tested cells in `report`.
SamplerConfigResult measureConfig(const float* out, uint32_t ci, uint32_t samplingInvocations,
                                  const SamplerCheckConfig& config, SamplerCheckReport& report) {
  const double perConfig = kPerConfig;
  const double cellSolidAngle = kCellSolidAngle;
  SamplerConfigResult r;
  r.config = config;
  std::vector<double> cells(3 * kCells, 0.0);
  std::vector<double> observed(kChi2Cells, 0.0);
  double albedo[4] = {0, 0, 0, 0};  // sampled sum, sum of squares; cosine sum, sum of squares
  for (uint32_t chunk = 0; chunk < kSamplerChunks; ++chunk) {
    const float* base = out + 4 * size_t((ci * kSamplerChunks + chunk) * kSamplerStride);
    for (uint32_t c = 0; c < kCells; ++c)
      for (int k = 0; k < 3; ++k) cells[3 * c + k] += base[4 * c + k];
    const float* summary = base + 4 * kCells;
    r.rejected += static_cast<uint64_t>(summary[0]);
    r.maxValueMismatch = std::max(r.maxValueMismatch, double(summary[1]));
    albedo[0] += summary[2];
    albedo[1] += summary[3];
    albedo[2] += summary[4];
    albedo[3] += summary[5];
    r.maxPdfMismatch = std::max(r.maxPdfMismatch, double(summary[6]));
    r.maxLengthError = std::max(r.maxLengthError, double(summary[8]));
    r.pdfBelowHorizon += static_cast<uint64_t>(summary[9]);
    const float* histogram = summary + 4 * kSummaryVec4s;
    for (uint32_t c = 0; c < kChi2Cells; ++c) observed[c] += histogram[c];
  }
  report.samples += static_cast<uint64_t>(perConfig);
  // Cells of the two rows next to the horizon (cos theta < 1/4) are left out, and at views
  // beyond 45 degrees also the third (cos theta < 3/8); views beyond 70 degrees are left out
  // of this test. Where the horizon cuts a lobe, or a half-vector sampler reaches those
  // directions only through the far tail of its distribution (grazing views), 1/pdf is so
  // heavy-tailed that finite-sample means and their error bars are unreliable (correct
  // samplers read far low there, with large z at grazing views). The chi-square test (with
  // pdfBRDF) and the albedo comparison still cover those directions.
  const uint32_t firstRow = r.config.viewDeg > 45 ? 3 : 2;
  const bool cellTest = r.config.viewDeg <= 70;
  for (uint32_t c = 0; cellTest && c < kCells; ++c) {
    if (cells[3 * c] < 100) continue;  // too few samples to say anything
    if (c / 16 < firstRow) continue;
    ++report.cellsTested;
    r.maxCellZ = std::max(r.maxCellZ, zScore(cells[3 * c + 1], cells[3 * c + 2], perConfig, cellSolidAngle));
  }
  // Two independent estimates of one albedo: z of their difference.
  auto meanVar = [&](double sum, double sumSq) {
    double mean = sum / perConfig;
    return std::pair<double, double>(mean, std::max(sumSq / perConfig - mean * mean, 0.0) / (perConfig - 1));
  };
  auto [ms, vs] = meanVar(albedo[0], albedo[1]);
  auto [mc, vc] = meanVar(albedo[2], albedo[3]);
  double sd = std::sqrt(vs + vc);
  r.albedoZ = sd > 0 ? std::fabs(ms - mc) / sd : (ms == mc ? 0.0 : INFINITY);

  if (report.chi2Run) {
    // Expected counts: each cell's probability under pdfBRDF times every draw of the
    // configuration, rejected ones included (a sampler that rejects more than its pdf says
    // comes up short in every cell). The cells cover the upper hemisphere only; the mass
    // pdfBRDF puts below it is what the rejected draws should carry, and is not a cell.
    const float* probability = out + 4 * size_t(samplingInvocations * kSamplerStride + ci * kChi2Vec4s);
    std::vector<double> expected(kChi2Cells);
    for (uint32_t c = 0; c < kChi2Cells; ++c) expected[c] = double(probability[c]) * perConfig;
    ChiSquareResult chi2 = chiSquareTest(observed, expected, kChi2MinExpected);
    r.chi2Failure = chi2.failure;
    r.chi2PValue = chi2.pValue;  // 0 on failure, never NaN
  }

  // This configuration's check nearest to its limit (severity = value / limit).
  auto consider = [&](const char* check, double value, double severity) {
    if (!(severity <= 1e300)) severity = 1e300;  // NaN or inf: as bad as it gets
    if (r.worstCheck.empty() || severity > r.worstSeverity) {
      r.worstCheck = check;
      r.worstValue = value;
      r.worstSeverity = severity;
    }
  };
  consider("value", r.maxValueMismatch, r.maxValueMismatch / SamplerCheckReport::kValueLimit);
  consider("cell z", r.maxCellZ, r.maxCellZ / kZLimit);
  consider("albedo z", r.albedoZ, r.albedoZ / kZLimit);
  consider("length", r.maxLengthError, r.maxLengthError / SamplerCheckReport::kLengthLimit);
  consider("pdf below horizon", double(r.pdfBelowHorizon), r.pdfBelowHorizon > 0 ? 1.0 + r.pdfBelowHorizon : 0.0);
  if (report.chi2Run) {
    consider("pdf mismatch", r.maxPdfMismatch, r.maxPdfMismatch / SamplerCheckReport::kPdfLimit);
    double sev = r.chi2PValue >= 1 ? 0.0 : std::log(r.chi2PValue) / std::log(report.chi2Threshold);
    consider("chi2", r.chi2PValue, sev);
  }
  return r;
}

// Adds one configuration's results to the report's totals and its worst configuration.
void addConfig(SamplerCheckReport& report, SamplerConfigResult r) {
  report.rejected += r.rejected;
  report.maxValueMismatch = std::max(report.maxValueMismatch, r.maxValueMismatch);
  report.maxCellZ = std::max(report.maxCellZ, r.maxCellZ);
  report.maxAlbedoZ = std::max(report.maxAlbedoZ, r.albedoZ);
  report.maxLengthError = std::max(report.maxLengthError, r.maxLengthError);
  report.pdfBelowHorizon += r.pdfBelowHorizon;
  if (report.chi2Run) {
    report.maxPdfMismatch = std::max(report.maxPdfMismatch, r.maxPdfMismatch);
    if (!r.chi2Failure.empty() && report.chi2Failure.empty())
      report.chi2Failure = r.config.describe() + ": " + r.chi2Failure;
    report.minChi2PValue = std::min(report.minChi2PValue, r.chi2PValue);
    report.chi2PValues.push_back(r.chi2PValue);
  }
  if (report.configs.empty() || r.worstSeverity > report.worstSeverity) {
    report.worstConfig = report.configs.size();
    report.worstCheck = r.worstCheck;
    report.worstValue = r.worstValue;
    report.worstSeverity = r.worstSeverity;
  }
  report.configs.push_back(std::move(r));
}

// "<configuration>: <check> <value> (limit <limit>)" for the report's worst configuration.
std::string describeWorst(const SamplerCheckReport& report) {
  const SamplerConfigResult& w = report.configs[report.worstConfig];
  std::string limit;
  if (w.worstCheck == "value")
    limit = formatG(SamplerCheckReport::kValueLimit);
  else if (w.worstCheck == "cell z" || w.worstCheck == "albedo z")
    limit = formatG(kZLimit);
  else if (w.worstCheck == "length")
    limit = formatG(SamplerCheckReport::kLengthLimit);
  else if (w.worstCheck == "pdf mismatch")
    limit = formatG(SamplerCheckReport::kPdfLimit);
  else if (w.worstCheck == "chi2")
    limit = "p >= " + formatG(report.chi2Threshold);
  else
    limit = "0";
  std::string worst =
      w.config.describe() + ": " + w.worstCheck + " " + formatG(w.worstValue) + " (limit " + limit + ")";
  if (w.worstCheck == "chi2" && !w.chi2Failure.empty()) worst += ", " + w.chi2Failure;
  return worst;
}

}  // namespace

std::string SamplerCheckConfig::describe() const {
  char buf[160];
  std::snprintf(buf, sizeof buf, "normal %s (%.6g, %.6g, %.6g), view %g deg at azimuth %g deg", normalLabel.c_str(),
                normal[0], normal[1], normal[2], viewDeg, viewAzimuthDeg);
  return buf;
}

namespace analysis {

Result<SamplerCheckReport> checkSampler(const CheckDevice& device, const BrdfDefinition& brdf) {
  if (!brdf.hasSampler()) return makeError(ErrorCode::InvalidArgument, "the BRDF has no '::begin sample' section");
  const auto t0 = std::chrono::steady_clock::now();
  SamplerCheckReport report;
  const std::vector<SamplerCheckConfig> configs = samplerConfigs();
  const uint32_t nConfigs = static_cast<uint32_t>(configs.size());
  // The same detection decides BRDFA_HAS_PDF in ProgramCache::assembleCheckProgram.
  report.chi2Run = detectFeatures(brdf).samplerPdf;
  if (report.chi2Run) report.chi2Threshold = sidakSignificance(kChi2Significance, int(nConfigs));
  const uint32_t samplingInvocations = nConfigs * kSamplerChunks;
  const uint32_t expectedInvocations = nConfigs * kChi2Vec4s;
  const uint32_t invocations = samplingInvocations + (report.chi2Run ? expectedInvocations : 0);
  const uint32_t outputVec4s = samplingInvocations * kSamplerStride + expectedInvocations;
  report.configurations = nConfigs;
  report.samplesPerConfiguration = static_cast<uint64_t>(kPerConfig);

  // The kernel's input (check_sampler.comp.glsl): a header of counts, then N, X, Y, V per configuration.
  std::vector<float> input(4 + 16 * size_t(nConfigs), 0.0f);
  const uint32_t header[3] = {nConfigs, kSamplerChunks, kChunkSamples};
  std::memcpy(input.data(), header, sizeof header);
  for (uint32_t c = 0; c < nConfigs; ++c) {
    const Vec3* vectors[4] = {&configs[c].normal, &configs[c].tangent, &configs[c].bitangent, &configs[c].view};
    for (int k = 0; k < 4; ++k)
      for (int j = 0; j < 3; ++j) input[4 + 16 * c + 4 * k + j] = (*vectors[k])[j];
  }

  auto ran = runCheckKernel(
      device, brdf, "check_sampler.comp.glsl", invocations, outputVec4s, {{}},
      [&](const float* out) {
        for (uint32_t ci = 0; ci < nConfigs; ++ci)
          addConfig(report, measureConfig(out, ci, samplingInvocations, configs[ci], report));
      },
      input);
  if (!ran) return ran.takeError();
  if (!report.configs.empty()) report.worst = describeWorst(report);
  report.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return report;
}

}  // namespace analysis

}  // namespace brdfa
