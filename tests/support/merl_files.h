// Measured BRDF files in MERL's layout, made from known functions, for the tests and the bench:
// real MERL files cannot be fetched here, and a table made from an analytic BRDF has a truth
// to compare against. Each bin holds the function at the bin's centre (brdfa::merlBinCentre).
#pragma once

#include <array>
#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include "brdfa/measured.h"

namespace brdfa::testsupport {

using Dir = std::array<double, 3>;
using Rgb = std::array<double, 3>;

// f_r(L, V) in 1/sr per channel, in the local frame (normal +z); any negative channel: no data.
using MerlSource = std::function<Rgb(const Dir& L, const Dir& V)>;

// The stored values (3 x kMerlBins, planar, MERL's scale undone) of `f` at every bin centre.
inline std::vector<double> merlPlanar(const MerlSource& f) {
  std::vector<double> planar(3 * kMerlBins);
  for (int h = 0; h < kMerlThetaHBins; ++h)
    for (int d = 0; d < kMerlThetaDBins; ++d)
      for (int p = 0; p < kMerlPhiDBins; ++p) {
        const MerlBin bin{h, d, p};
        Dir L, V;
        directionsFromHalfDiff(merlBinCentre(bin), L, V);
        const Rgb v = f(L, V);
        const bool missing = v[0] < 0 || v[1] < 0 || v[2] < 0;
        const size_t i = merlIndex(bin);
        for (int c = 0; c < 3; ++c) planar[c * kMerlBins + i] = missing ? -1.0 : v[c] / kMerlScale[c];
      }
  return planar;
}

inline std::string merlFile(const MerlSource& f) { return writeMerl(merlPlanar(f)); }

// A Lambertian of albedo `rho`: rho / pi everywhere (also below the horizon: a constant table).
inline std::string lambertMerl(const Rgb& rho) {
  return merlFile([rho](const Dir&, const Dir&) { return Rgb{rho[0] / M_PI, rho[1] / M_PI, rho[2] / M_PI}; });
}

// shaders/brdfs/ggx.brdf in double precision: D_GGX * V_SmithGGXCorrelated * F_Schlick(V.H);
// 0 below the horizon.
inline Rgb ggxValue(const Dir& L, const Dir& V, double alpha, const Rgb& f0) {
  const double nl = L[2], nv = V[2];
  if (nl <= 0 || nv <= 0) return {0, 0, 0};
  Dir h{L[0] + V[0], L[1] + V[1], L[2] + V[2]};
  const double len = std::sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
  const double nh = h[2] / len;
  const double vh = (V[0] * h[0] + V[1] * h[1] + V[2] * h[2]) / len;
  const double a2 = alpha * alpha;
  const double d = nh * nh * (a2 - 1) + 1;
  const double D = a2 / (M_PI * d * d);
  const double lv = nl * std::sqrt(nv * nv * (1 - a2) + a2), ll = nv * std::sqrt(nl * nl * (1 - a2) + a2);
  const double Vis = 0.5 / (lv + ll);
  const double m = std::clamp(1.0 - vh, 0.0, 1.0);
  const double s = m * m * m * m * m;
  return {D * Vis * (f0[0] + (1 - f0[0]) * s), D * Vis * (f0[1] + (1 - f0[1]) * s),
          D * Vis * (f0[2] + (1 - f0[2]) * s)};
}

// GGX as ggx.brdf computes it; bin centres with L or V below the horizon hold no data, as a
// gonioreflectometer measures none there.
inline std::string ggxMerl(double alpha, const Rgb& f0) {
  return merlFile([alpha, f0](const Dir& L, const Dir& V) {
    if (L[2] <= 0 || V[2] <= 0) return Rgb{-1, -1, -1};
    return ggxValue(L, V, alpha, f0);
  });
}

// Each bin's stored value is its own index in the red channel, index + 1/4 in green and
// index + 1/2 in blue: reading a bin back names the bin and the channel order.
inline std::vector<double> indexPlanar() {
  std::vector<double> planar(3 * kMerlBins);
  for (size_t i = 0; i < kMerlBins; ++i)
    for (int c = 0; c < 3; ++c) planar[c * kMerlBins + i] = double(i) + 0.25 * c;
  return planar;
}

}  // namespace brdfa::testsupport
