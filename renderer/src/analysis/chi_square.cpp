#include "analysis/chi_square.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

namespace brdfa {

namespace {

constexpr double kEps = 1e-15;          // relative size of the last term / factor kept
constexpr int kMaxIterations = 100000;  // the series needs ~sqrt(a) * 10 terms near x = a; far more than enough
constexpr double kTiny = 1e-300;        // Lentz's stand-in for a zero denominator

// log(x^a e^-x / Gamma(a)), the common prefactor of both expansions.
double logPrefactor(double a, double x) { return a * std::log(x) - x - std::lgamma(a); }

// P(a, x) by its series: x^a e^-x / Gamma(a + 1) * sum_n x^n / ((a+1)...(a+n)) (NR 6.2.5).
// Converges for all x; used for x < a + 1, where it needs few terms and P is not close to 1.
double gammaSeries(double a, double x) {
  double term = 1.0 / a, sum = term, ap = a;
  for (int n = 0; n < kMaxIterations; ++n) {
    ap += 1.0;
    term *= x / ap;
    sum += term;
    if (std::fabs(term) < std::fabs(sum) * kEps) break;
  }
  return std::min(1.0, sum * std::exp(logPrefactor(a, x)));
}

// Q(a, x) by its continued fraction, evaluated with the modified Lentz method (NR 6.2.7);
// used for x >= a + 1, where it converges fast and Q may be tiny.
double gammaContinuedFraction(double a, double x) {
  double b = x + 1.0 - a, c = 1.0 / kTiny, d = 1.0 / b, h = d;
  for (int i = 1; i < kMaxIterations; ++i) {
    double an = -i * (i - a);
    b += 2.0;
    d = an * d + b;
    if (std::fabs(d) < kTiny) d = kTiny;
    c = b + an / c;
    if (std::fabs(c) < kTiny) c = kTiny;
    d = 1.0 / d;
    double delta = d * c;
    h *= delta;
    if (std::fabs(delta - 1.0) < kEps) break;
  }
  return std::min(1.0, std::exp(logPrefactor(a, x)) * h);
}

}  // namespace

double regularizedGammaP(double a, double x) {
  if (std::isnan(a) || std::isnan(x) || a <= 0) return std::numeric_limits<double>::quiet_NaN();
  if (x <= 0) return 0.0;
  if (std::isinf(x)) return 1.0;
  return x < a + 1.0 ? gammaSeries(a, x) : 1.0 - gammaContinuedFraction(a, x);
}

double regularizedGammaQ(double a, double x) {
  if (std::isnan(a) || std::isnan(x) || a <= 0) return std::numeric_limits<double>::quiet_NaN();
  if (x <= 0) return 1.0;
  if (std::isinf(x)) return 0.0;
  return x < a + 1.0 ? 1.0 - gammaSeries(a, x) : gammaContinuedFraction(a, x);
}

double chiSquareSurvival(double chi2, double dof) { return regularizedGammaQ(0.5 * dof, 0.5 * chi2); }

double sidakSignificance(double alpha, int tests) {
  return tests <= 1 ? alpha : 1.0 - std::pow(1.0 - alpha, 1.0 / tests);
}

ChiSquareResult chiSquareTest(const std::vector<double>& observed, const std::vector<double>& expected,
                              double minExpected) {
  ChiSquareResult r;
  auto fail = [&](std::string why) {
    r.pValue = 0;
    r.failure = std::move(why);
    return r;
  };
  if (observed.size() != expected.size()) return fail("observed and expected tables differ in size");
  std::vector<size_t> order(expected.size());
  std::iota(order.begin(), order.end(), size_t(0));
  for (size_t i : order)
    if (!std::isfinite(expected[i]) || expected[i] < 0)
      return fail("cell " + std::to_string(i) + " has expected count " + std::to_string(expected[i]));
  std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return expected[a] < expected[b]; });

  // pbrt-v4 Chi2Test: cells below minExpected, and then further cells (smallest first) until the
  // pool itself reaches minExpected, are merged into one.
  double pooledObserved = 0, pooledExpected = 0;
  for (size_t i : order) {
    const double o = observed[i], e = expected[i];
    if (e == 0) {
      if (o > 0)
        return fail(std::to_string(o) + " samples in cell " + std::to_string(i) + ", whose expected count is 0");
    } else if (e < minExpected || (pooledExpected > 0 && pooledExpected < minExpected)) {
      pooledObserved += o;
      pooledExpected += e;
      ++r.pooledCells;
    } else {
      r.statistic += (o - e) * (o - e) / e;
      ++r.dof;
    }
  }
  if (pooledExpected > 0) {
    r.statistic += (pooledObserved - pooledExpected) * (pooledObserved - pooledExpected) / pooledExpected;
    ++r.dof;
  }
  r.dof -= 1;  // the expected counts have no fitted parameters: only the total is shared
  if (r.dof < 1) return fail("only " + std::to_string(r.dof) + " degrees of freedom after pooling");
  r.pValue = chiSquareSurvival(r.statistic, r.dof);
  if (!std::isfinite(r.pValue)) return fail("the statistic " + std::to_string(r.statistic) + " has no p-value");
  return r;
}

}  // namespace brdfa
