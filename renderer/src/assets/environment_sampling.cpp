#include "assets/environment_sampling.h"

#include <algorithm>
#include <bit>
#include <cmath>

namespace brdfa {

namespace {

double luminance(const float* rgb) { return 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]; }

// Signed solid angle from the face centre to (s, t) (Driscoll 2012; see cubeTexelSolidAngle).
double areaElement(double s, double t) { return std::atan2(s * t, std::sqrt(s * s + t * t + 1.0)); }

double rectSolidAngle(double s0, double s1, double t0, double t1) {
  return areaElement(s0, t0) - areaElement(s0, t1) - areaElement(s1, t0) + areaElement(s1, t1);
}

}  // namespace

EnvironmentDistribution buildEnvironmentDistribution(const EnvironmentData& env, uint32_t maxCellsPerEdge) {
  const uint32_t F = std::max<uint32_t>(env.faceSize, 1);
  // D is a power of two, so the kernels split a cell index with shifts (integer division is
  // scalar code on a CPU device's SIMD lanes); cells then cover whole or fractional texel ranges.
  uint32_t D = 1;
  while (D * 2 <= std::min(F, std::max<uint32_t>(maxCellsPerEdge, 1))) D *= 2;
  const size_t cells = size_t(6) * D * D;

  // Luminance of each texel, blurred by the tent of bilinear filtering (clamped at face edges).
  std::vector<double> lum(size_t(6) * F * F), blurred(lum.size()), tmp(lum.size());
  for (size_t i = 0; i < lum.size(); ++i) lum[i] = std::max(0.0, luminance(&env.texels[4 * i]));
  auto at = [F](int face, int x, int y) { return (size_t(face) * F + y) * F + x; };
  const double k0 = 0.75, k1 = 0.125;
  for (int f = 0; f < 6; ++f)
    for (int y = 0; y < int(F); ++y)
      for (int x = 0; x < int(F); ++x) {
        const int xl = std::max(x - 1, 0), xr = std::min(x + 1, int(F) - 1);
        tmp[at(f, x, y)] = k0 * lum[at(f, x, y)] + k1 * (lum[at(f, xl, y)] + lum[at(f, xr, y)]);
      }
  for (int f = 0; f < 6; ++f)
    for (int y = 0; y < int(F); ++y)
      for (int x = 0; x < int(F); ++x) {
        const int yu = std::max(y - 1, 0), yd = std::min(y + 1, int(F) - 1);
        blurred[at(f, x, y)] = k0 * tmp[at(f, x, y)] + k1 * (tmp[at(f, x, yu)] + tmp[at(f, x, yd)]);
      }

  // Cell weights: mean blurred luminance of the cell's texels times the cell's solid angle.
  std::vector<double> weight(cells);
  double total = 0;
  for (uint32_t f = 0; f < 6; ++f)
    for (uint32_t cy = 0; cy < D; ++cy)
      for (uint32_t cx = 0; cx < D; ++cx) {
        // The texels whose centres fall in the cell (at least one: D <= F).
        const uint32_t x0 = cx * F / D, y0 = cy * F / D;
        const uint32_t x1 = std::max((cx + 1) * F / D, x0 + 1), y1 = std::max((cy + 1) * F / D, y0 + 1);
        double sum = 0;
        for (uint32_t y = y0; y < y1; ++y)
          for (uint32_t x = x0; x < x1; ++x) sum += blurred[at(int(f), int(x), int(y))];
        const double mean = sum / double((x1 - x0) * (y1 - y0));
        const double s0 = 2.0 * cx / D - 1.0, t0 = 2.0 * cy / D - 1.0;
        const double w = mean * rectSolidAngle(s0, s0 + 2.0 / D, t0, t0 + 2.0 / D);
        weight[(size_t(f) * D + cy) * D + cx] = w;
        total += w;
      }
  // guard: the floor keeps every cell reachable (seams, where filtering mixes in the next
  // face); a black map (total 0) becomes uniform over the sphere.
  // The floor is a uniform density over the sphere (in proportion to each cell's solid angle)
  // holding 1e-4 of the map's weight.
  const double floor = total > 0 ? 1e-4 * total : 1.0;
  total = 0;
  for (size_t c = 0; c < cells; ++c) {
    const uint32_t cx = c % D, cy = (c / D) % D;
    const double s0 = 2.0 * cx / D - 1.0, t0 = 2.0 * cy / D - 1.0;
    weight[c] += floor * rectSolidAngle(s0, s0 + 2.0 / D, t0, t0 + 2.0 / D) / (4.0 * M_PI);
    total += weight[c];
  }

  // Vose's alias method: O(n), exact up to rounding.
  std::vector<double> p(cells), scaled(cells);
  std::vector<uint32_t> alias(cells);
  std::vector<uint32_t> small, large;
  for (size_t c = 0; c < cells; ++c) {
    p[c] = weight[c] / total;
    scaled[c] = p[c] * double(cells);
    alias[c] = uint32_t(c);
    (scaled[c] < 1.0 ? small : large).push_back(uint32_t(c));
  }
  std::vector<double> q(cells, 1.0);
  while (!small.empty() && !large.empty()) {
    const uint32_t s = small.back(), l = large.back();
    small.pop_back();
    q[s] = scaled[s];
    alias[s] = l;
    scaled[l] = (scaled[l] + scaled[s]) - 1.0;
    if (scaled[l] < 1.0) {
      large.pop_back();
      small.push_back(l);
    }
  }
  // What remains is 1 up to rounding.
  for (uint32_t c : small) q[c] = 1.0;
  for (uint32_t c : large) q[c] = 1.0;

  EnvironmentDistribution out;
  out.cellsPerEdge = D;
  const double areaScale = double(D) * D / 4.0;  // cell area in (s, t) is (2/D)^2
  double effective = 0;
  for (size_t c = 0; c < cells; ++c) {
    const uint32_t cx = c % D, cy = (c / D) % D;
    const double s0 = 2.0 * cx / D - 1.0, t0 = 2.0 * cy / D - 1.0;
    const double omega = rectSolidAngle(s0, s0 + 2.0 / D, t0, t0 + 2.0 / D);
    effective += p[c] * p[c] / omega;  // (p/omega)^2 * omega, the cell's mean density squared
  }
  out.effectiveDensity = effective;
  // q in 13 bits: a cell that keeps everything aliases itself; any other keeps at least 1/8192
  // (guard: a q rounded to 0 would make a cell with no other way in unreachable). The table
  // then realises slightly different probabilities than p, and the densities are those.
  constexpr uint32_t kOne = 1u << EnvironmentDistribution::kAliasShift;
  out.table.assign(2 * (cells + 1), 0u);
  out.table[0] = uint32_t(std::lround(std::log2(double(D))));
  out.table[1] = std::bit_cast<uint32_t>(float(effective));
  for (size_t c = 0; c < cells; ++c) {
    const bool keepsAll = alias[c] == c || q[c] >= 1.0 - 0.5 / kOne;
    const uint32_t k = keepsAll ? 0u : uint32_t(std::clamp<long>(std::lround(q[c] * kOne), 1, kOne - 1));
    out.table[2 * (c + 1)] = (keepsAll ? uint32_t(c) : alias[c]) << EnvironmentDistribution::kAliasShift | k;
  }
  const std::vector<double> realised = out.realisedCellProbabilities();
  for (size_t c = 0; c < cells; ++c)
    out.table[2 * (c + 1) + 1] = std::bit_cast<uint32_t>(float(realised[c] * areaScale));
  return out;
}

std::vector<uint32_t> EnvironmentDistribution::constantHeader() {
  return {0u, std::bit_cast<uint32_t>(float(1.0 / (4.0 * M_PI)))};
}

float EnvironmentDistribution::density(size_t cell) const { return std::bit_cast<float>(table[2 * (cell + 1) + 1]); }

double EnvironmentDistribution::pdf(const float dir[3]) const {
  int face;
  float s, t;
  cubeFaceCoords(dir, face, s, t);
  const uint32_t D = cellsPerEdge;
  const uint32_t cx = std::min(uint32_t(std::max(0.0f, (s + 1.0f) * 0.5f * float(D))), D - 1);
  const uint32_t cy = std::min(uint32_t(std::max(0.0f, (t + 1.0f) * 0.5f * float(D))), D - 1);
  const size_t c = (size_t(face) * D + cy) * D + cx;
  const double major = std::max({std::abs(dir[0]), std::abs(dir[1]), std::abs(dir[2])});
  return density(c) / (major * major * major);
}

std::vector<double> EnvironmentDistribution::realisedCellProbabilities() const {
  const size_t cells = table.size() / 2 - 1;
  const double one = double(1u << kAliasShift);
  std::vector<double> p(cells, 0.0);
  for (size_t c = 0; c < cells; ++c) {
    const uint32_t k = keepThreshold(c), a = aliasOf(c);
    if (a == c) {
      p[c] += 1.0 / double(cells);
      continue;
    }
    p[c] += (double(k) / one) / double(cells);
    p[a] += (1.0 - double(k) / one) / double(cells);
  }
  return p;
}

}  // namespace brdfa
