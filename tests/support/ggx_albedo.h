// An independent quadrature of GGX's directional albedo, shared by the tests that check the
// renderer and the analysis endpoints against it (it shares no code with shaders/brdfs/ggx.brdf).
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

namespace brdfa::testsupport {

inline constexpr double kGgxPi = 3.14159265358979323846;

// Directional albedo E(mu) = integral of f(L, V) (N.L) dL of single-scattering GGX with F = 1
// and the height-correlated Smith G2 = 1 / (1 + Lambda(V) + Lambda(L)) (Heitz 2014, eqs. 72 and
// 99; Lambda = (-1 + sqrt(1 + alpha^2 tan^2)) / 2, eq. 86), by the midpoint rule.
// Over the half vector h (dL = 4 (V.h) dh, Walter 2007 eq. 14), f (N.L) dL = D G2 (V.h) / mu dh;
// with tan^2(theta_h) = alpha^2 xi / (1 - xi) (the CDF of D(h) cos(theta_h), Walter 2007 eq. 35)
// D(h) dh = dxi dphi / (2 pi cos(theta_h)), so
//   E(mu) = integral over xi in (0,1), phi in (0, 2 pi) of G2 (V.h) / (mu cos(theta_h)) dxi dphi / (2 pi),
// over h with V.h > 0 (h = normalize(L + V) always has it) and L = 2 (V.h) h - V above the
// horizon. V = (sqrt(1 - mu^2), 0, mu): the integrand is even in phi, so phi runs over (0, pi).
// The midpoint rule runs in u with xi = sin^2(pi u / 2) (tan(theta_h) = alpha tan(pi u / 2),
// dxi = pi sin(pi u / 2) cos(pi u / 2) du), which spreads the points over the lobe's tail, where
// the horizon cuts it, as well as its peak (uniform in xi, the tail beyond 45 degrees got about
// alpha^2 of them).
inline double ggxAlbedo(double mu, double alpha, int nXi, int nPhi) {
  const double a2 = alpha * alpha;
  auto lambda = [a2](double c) {
    const double t2 = (1.0 - c * c) / (c * c);
    return 0.5 * (-1.0 + std::sqrt(1.0 + a2 * t2));
  };
  const double sv = std::sqrt(std::max(0.0, 1.0 - mu * mu));
  const double lambdaV = lambda(mu);
  std::vector<double> cosPhi(nPhi);
  for (int j = 0; j < nPhi; ++j) cosPhi[j] = std::cos(kGgxPi * (j + 0.5) / nPhi);
  double sum = 0;
  for (int i = 0; i < nXi; ++i) {
    const double u = (i + 0.5) / nXi;
    const double su = std::sin(0.5 * kGgxPi * u), cu = std::cos(0.5 * kGgxPi * u);
    const double t2 = a2 * (su * su) / (cu * cu);
    const double ct = 1.0 / std::sqrt(1.0 + t2), st = std::sqrt(t2) * ct;
    double row = 0;
    for (int j = 0; j < nPhi; ++j) {
      const double vh = sv * st * cosPhi[j] + mu * ct;
      if (vh <= 0) continue;
      const double nl = 2.0 * vh * ct - mu;
      if (nl <= 0) continue;
      row += vh / (1.0 + lambdaV + lambda(nl));
    }
    sum += row / ct * kGgxPi * su * cu;
  }
  // du = 1 / nXi, dphi = pi / nPhi, times 2 (phi in (pi, 2 pi)) / (2 pi).
  return sum / (mu * double(nXi) * double(nPhi));
}

}  // namespace brdfa::testsupport
