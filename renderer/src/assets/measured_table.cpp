#include "brdfa/measured.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>

namespace brdfa {

// The file's numbers are little-endian, as MERL wrote them; read in place on such a host.
static_assert(std::endian::native == std::endian::little, "MERL files are read on little-endian hosts only");

namespace {

using D3 = std::array<double, 3>;
constexpr double kPi = 3.14159265358979323846;
constexpr double kHalfPi = kPi / 2;

D3 normalized(const D3& v) {
  const double n = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  // L = -V (opposite directions) has no half vector: any unit vector stands for it.
  if (!(n > 0)) return {0, 0, 1};
  return {v[0] / n, v[1] / n, v[2] / n};
}

// Rotations about +z and +y by `a` (right-handed), as MERL's rotate_vector does them.
D3 rotateZ(const D3& v, double a) {
  const double c = std::cos(a), s = std::sin(a);
  return {c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]};
}
D3 rotateY(const D3& v, double a) {
  const double c = std::cos(a), s = std::sin(a);
  return {c * v[0] + s * v[2], v[1], -s * v[0] + c * v[2]};
}

double clampedAcos(double x) { return std::acos(std::clamp(x, -1.0, 1.0)); }

// Continuous bin coordinates: bin i's centre at i (theta_h on the square-root scale).
double thetaHCoord(double thetaH) { return kMerlThetaHBins * std::sqrt(std::max(thetaH, 0.0) / kHalfPi) - 0.5; }
double thetaDCoord(double thetaD) { return thetaD / kHalfPi * kMerlThetaDBins - 0.5; }
double phiDCoord(double phiD) { return phiD / kPi * kMerlPhiDBins - 0.5; }

Vec3 binValue(const MeasuredTable& table, size_t bin) {
  if (!table.valid(bin)) return {0, 0, 0};
  return {table.rgb[3 * bin], table.rgb[3 * bin + 1], table.rgb[3 * bin + 2]};
}

std::string channelName(int c) { return c == 0 ? "red" : c == 1 ? "green" : "blue"; }

}  // namespace

size_t merlIndex(const MerlBin& b) {
  return size_t(b.phiD) + size_t(kMerlPhiDBins) * b.thetaD + size_t(kMerlPhiDBins) * kMerlThetaDBins * b.thetaH;
}

bool hasMerlHeader(std::string_view bytes) {
  if (bytes.size() < 3 * sizeof(int32_t)) return false;
  int32_t dims[3];
  std::memcpy(dims, bytes.data(), sizeof dims);
  return dims[0] == kMerlThetaHBins && dims[1] == kMerlThetaDBins && dims[2] == kMerlPhiDBins;
}

Result<MeasuredTable> readMerl(std::string_view bytes) {
  if (bytes.size() >= 3 * sizeof(int32_t) && !hasMerlHeader(bytes)) {
    int32_t dims[3];
    std::memcpy(dims, bytes.data(), sizeof dims);
    return makeError(ErrorCode::InvalidArgument, "not a MERL table: its header gives " + std::to_string(dims[0]) +
                                                     " x " + std::to_string(dims[1]) + " x " + std::to_string(dims[2]) +
                                                     " bins, not 90 x 90 x 180");
  }
  if (bytes.size() != kMerlFileBytes)
    return makeError(ErrorCode::InvalidArgument,
                     "a MERL table is " + std::to_string(kMerlFileBytes) + " bytes (a 12-byte header and 3 x " +
                         std::to_string(kMerlBins) + " float64), this file is " + std::to_string(bytes.size()) +
                         (bytes.size() < kMerlFileBytes ? " bytes (truncated)" : " bytes (bytes after the table)"));
  MeasuredTable t;
  t.rgb.assign(3 * kMerlBins, -1.0f);
  const char* values = bytes.data() + 3 * sizeof(int32_t);
  std::vector<bool> missing(kMerlBins, false);
  for (int c = 0; c < 3; ++c) {
    for (size_t i = 0; i < kMerlBins; ++i) {
      double v;
      std::memcpy(&v, values + (size_t(c) * kMerlBins + i) * sizeof(double), sizeof v);
      if (!std::isfinite(v)) {
        const MerlBin b{int(i / (kMerlPhiDBins * kMerlThetaDBins)), int(i / kMerlPhiDBins % kMerlThetaDBins),
                        int(i % kMerlPhiDBins)};
        return makeError(ErrorCode::InvalidArgument,
                         "the MERL table holds " + std::string(std::isnan(v) ? "NaN" : "an infinite value") +
                             " in the " + channelName(c) + " channel of bin (theta_h " + std::to_string(b.thetaH) +
                             ", theta_d " + std::to_string(b.thetaD) + ", phi_d " + std::to_string(b.phiD) + ")");
      }
      if (v < 0) missing[i] = true;
      t.rgb[3 * i + c] = static_cast<float>(v * kMerlScale[c]);
    }
  }
  for (size_t i = 0; i < kMerlBins; ++i) {
    // A negative value in any channel marks the whole bin as without data.
    if (missing[i])
      t.rgb[3 * i] = t.rgb[3 * i + 1] = t.rgb[3 * i + 2] = -1.0f;
    else
      ++t.validBins;
  }
  if (t.validBins == 0) return makeError(ErrorCode::InvalidArgument, "the MERL table has no bin with data");
  const MerlLobe lobe = fitMerlLobe(t);
  t.lobeAlpha = lobe.alpha;
  t.lobeWeight = lobe.weight;
  return t;
}

MerlLobe fitMerlLobe(const MeasuredTable& t) {
  // The profile over theta_h at the smallest theta_d with data, phi_d averaged.
  std::vector<double> profile(kMerlThetaHBins, -1.0);
  for (int d = 0; d < kMerlThetaDBins && profile[0] < 0; ++d)
    for (int h = 0; h < kMerlThetaHBins; ++h) {
      double sum = 0;
      int n = 0;
      for (int p = 0; p < kMerlPhiDBins; ++p) {
        const size_t bin = merlIndex(MerlBin{h, d, p});
        if (t.valid(bin)) sum += t.rgb[3 * bin + 1], ++n;
      }
      profile[h] = n > 0 ? sum / n : -1.0;
    }
  MerlLobe lobe;
  const double peak = profile[0];
  double floor = peak;
  for (double v : profile)
    if (v >= 0) floor = std::min(floor, v);
  // A flat profile (a diffuse table, or no data at the peak): mostly the cosine.
  if (!(peak > 0) || !(peak > 1.01 * floor)) return MerlLobe{0.3f, 0.1f};
  const double half = floor + 0.5 * (peak - floor);
  double thetaHalf = kHalfPi * 0.5;
  for (int h = 1; h < kMerlThetaHBins; ++h) {
    if (profile[h] < 0 || profile[h] > half) continue;
    // Between the centres of bins h - 1 and h, linearly in value.
    const double a = merlBinCentre(MerlBin{h - 1, 0, 0}).thetaH, b = merlBinCentre(MerlBin{h, 0, 0}).thetaH;
    const double fa = profile[h - 1] >= 0 ? profile[h - 1] : peak;
    const double s = fa > profile[h] ? (fa - half) / (fa - profile[h]) : 1.0;
    thetaHalf = a + std::clamp(s, 0.0, 1.0) * (b - a);
    break;
  }
  // GGX's D = 1 / (pi cos^4 (a^2 + tan^2)^2) (times a^2) falls to half its peak where
  // cos^2 (a^2 + tan^2) = sqrt(2) a^2, i.e. a^2 = tan^2 / (sqrt(2) - 1 + sqrt(2) tan^2).
  const double q = std::sqrt(2.0), t2 = std::tan(thetaHalf) * std::tan(thetaHalf);
  const double alpha = std::sqrt(t2 / ((q - 1) + q * t2));
  lobe.alpha = static_cast<float>(std::clamp(alpha, 0.005, 1.0));
  const double spec = 4 * kPi * double(lobe.alpha) * lobe.alpha * (peak - floor), diffuse = kPi * floor;
  lobe.weight = static_cast<float>(std::clamp(spec / (spec + diffuse), 0.1, 0.9));
  return lobe;
}

std::string writeMerl(const std::vector<double>& planar) {
  std::string out(kMerlFileBytes, '\0');
  const int32_t dims[3] = {kMerlThetaHBins, kMerlThetaDBins, kMerlPhiDBins};
  std::memcpy(out.data(), dims, sizeof dims);
  const size_t n = std::min(planar.size(), 3 * kMerlBins);
  std::memcpy(out.data() + sizeof dims, planar.data(), n * sizeof(double));
  return out;
}

HalfDiff halfDiffFromDirections(const D3& L, const D3& V) {
  const D3 h = normalized({L[0] + V[0], L[1] + V[1], L[2] + V[2]});
  HalfDiff hd;
  hd.thetaH = clampedAcos(h[2]);
  const double phiH = std::atan2(h[1], h[0]);
  // L in the frame where the half vector is +z (MERL: about the normal by -phi_h, then about
  // the bitangent by -theta_h).
  const D3 d = rotateY(rotateZ(normalized(L), -phiH), -hd.thetaH);
  hd.thetaD = clampedAcos(d[2]);
  double phiD = std::atan2(d[1], d[0]);
  // phi_d and phi_d + pi are one bin (swapping L and V adds pi): folded into [0, pi).
  if (phiD < 0) phiD += kPi;
  if (phiD >= kPi) phiD -= kPi;
  hd.phiD = phiD;
  return hd;
}

HalfDiff halfDiffFromDirections(const Vec3& L, const Vec3& V) {
  return halfDiffFromDirections(D3{L[0], L[1], L[2]}, D3{V[0], V[1], V[2]});
}

void directionsFromHalfDiff(const HalfDiff& hd, D3& L, D3& V) {
  const D3 d{std::sin(hd.thetaD) * std::cos(hd.phiD), std::sin(hd.thetaD) * std::sin(hd.phiD), std::cos(hd.thetaD)};
  L = rotateY(d, hd.thetaH);
  const D3 h{std::sin(hd.thetaH), 0.0, std::cos(hd.thetaH)};
  const double hl = h[0] * L[0] + h[1] * L[1] + h[2] * L[2];
  V = {2 * hl * h[0] - L[0], 2 * hl * h[1] - L[1], 2 * hl * h[2] - L[2]};
}

MerlBin merlBinOf(const HalfDiff& hd) {
  MerlBin b;
  // theta_h: MERL's square-root mapping, int(sqrt(theta_h / (pi/2) * 90 * 90)).
  b.thetaH = hd.thetaH <= 0 ? 0 : int(std::sqrt(hd.thetaH / kHalfPi * kMerlThetaHBins * kMerlThetaHBins));
  b.thetaD = int(hd.thetaD / kHalfPi * kMerlThetaDBins);
  b.phiD = int(hd.phiD / kPi * kMerlPhiDBins);
  b.thetaH = std::clamp(b.thetaH, 0, kMerlThetaHBins - 1);
  b.thetaD = std::clamp(b.thetaD, 0, kMerlThetaDBins - 1);
  b.phiD = std::clamp(b.phiD, 0, kMerlPhiDBins - 1);
  return b;
}

HalfDiff merlBinCentre(const MerlBin& b) {
  const double u = (b.thetaH + 0.5) / kMerlThetaHBins;
  return HalfDiff{u * u * kHalfPi, (b.thetaD + 0.5) / kMerlThetaDBins * kHalfPi, (b.phiD + 0.5) / kMerlPhiDBins * kPi};
}

Vec3 lookupMerlNearest(const MeasuredTable& table, const HalfDiff& hd) {
  return binValue(table, merlIndex(merlBinOf(hd)));
}

Vec3 lookupMerlInterpolated(const MeasuredTable& table, const HalfDiff& hd) {
  // Corner indices and weights per axis: clamped at the theta edges, periodic in phi_d.
  auto clampedAxis = [](double x, int bins, int i[2], double w[2]) {
    x = std::clamp(x, 0.0, double(bins - 1));
    i[0] = std::min(int(std::floor(x)), bins - 1);
    i[1] = std::min(i[0] + 1, bins - 1);
    w[1] = x - i[0];
    w[0] = 1 - w[1];
  };
  int ih[2], id[2], ip[2];
  double wh[2], wd[2], wp[2];
  clampedAxis(thetaHCoord(hd.thetaH), kMerlThetaHBins, ih, wh);
  clampedAxis(thetaDCoord(hd.thetaD), kMerlThetaDBins, id, wd);
  const double xp = phiDCoord(hd.phiD);
  const double fp = std::floor(xp);
  ip[0] = ((int(fp) % kMerlPhiDBins) + kMerlPhiDBins) % kMerlPhiDBins;
  ip[1] = (ip[0] + 1) % kMerlPhiDBins;
  wp[1] = xp - fp;
  wp[0] = 1 - wp[1];
  double sum[3] = {0, 0, 0}, weight = 0;
  for (int a = 0; a < 2; ++a)
    for (int b = 0; b < 2; ++b)
      for (int c = 0; c < 2; ++c) {
        const double w = wh[a] * wd[b] * wp[c];
        const size_t bin = merlIndex(MerlBin{ih[a], id[b], ip[c]});
        // A bin without data is left out; the others' weights are renormalised below.
        if (w <= 0 || !table.valid(bin)) continue;
        for (int k = 0; k < 3; ++k) sum[k] += w * table.rgb[3 * bin + k];
        weight += w;
      }
  if (!(weight > 0)) return {0, 0, 0};
  return {float(sum[0] / weight), float(sum[1] / weight), float(sum[2] / weight)};
}

Vec3 lookupMerlInterpolated(const MeasuredTable& table, const Vec3& L, const Vec3& V) {
  return lookupMerlInterpolated(table, halfDiffFromDirections(L, V));
}

std::string measuredBrdfText() {
  return "analytic\n"
         "# A measured BRDF: a MERL table (brdfa/measured.h), looked up by trilinear interpolation\n"
         "# between bin centres in Rusinkiewicz's half/difference angles.\n"
         "# claims: reciprocity, non-negativity\n"
         "::begin parameters\n"
         "::end parameters\n"
         "::begin shader\n"
         "#include \"terms/measured_merl.glsl\"\n"
         "\n"
         "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return measuredMERL(L, V, N, X, Y); }\n"
         "::end shader\n"
         "::begin sample\n"
         "// A GGX lobe fitted to the table, mixed with the cosine (terms/measured_merl.glsl).\n"
         "float pdfBRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y) { return pdfMeasuredMERL(L, V, N); }\n"
         "\n"
         "vec3 sampleBRDF(vec2 u, vec3 V, vec3 N, vec3 X, vec3 Y, out vec3 L, out float pdf)\n"
         "{\n"
         "    return sampleMeasuredMERL(u, V, N, X, Y, L, pdf);\n"
         "}\n"
         "::end sample\n";
}

Result<BrdfDefinition> measuredBrdf(const std::string& tableName) {
  BRDFA_TRY_ASSIGN(BrdfDefinition brdf, parseBrdf(measuredBrdfText()));
  brdf.measuredTable = tableName;
  return brdf;
}

}  // namespace brdfa
