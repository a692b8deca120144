// Pearson's chi-square goodness-of-fit test, as pbrt-v4 runs it on BxDF samplers
// (src/pbrt/bxdfs_test.cpp, Chi2Test; after W. Jakob's Mitsuba test), and the regularized
// incomplete gamma function it needs.
//
// What this file promises:
//  - regularizedGammaP(a, x) = P(a, x) = gamma(a, x) / Gamma(a), the regularized lower incomplete
//    gamma function, and regularizedGammaQ(a, x) = Q(a, x) = 1 - P(a, x), both to about 1e-12
//    relative accuracy for a > 0, x >= 0 (series for x < a + 1, continued fraction otherwise:
//    Numerical Recipes 3rd ed., sec. 6.2). Q is computed directly where it is small, so tail
//    probabilities far below 1e-16 keep their digits (1 - P would round them to 0).
//    a <= 0 or a NaN argument gives NaN; x <= 0 gives P = 0, Q = 1; x = +inf gives P = 1, Q = 0.
//  - chiSquareSurvival(chi2, dof) = 1 - CDF of the chi-square distribution with `dof` degrees of
//    freedom at `chi2` = Q(dof / 2, chi2 / 2): the p-value of a chi-square statistic.
//  - chiSquareTest(observed, expected): pools the cells whose expected count is below
//    `minExpected` (sorted by expected count, smallest first, until the pool reaches it; pbrt's
//    rule), sums (O - E)^2 / E, dof = cells after pooling - 1, and returns the p-value. A cell
//    with expected count 0 that holds any observation, a negative or non-finite expected count,
//    or fewer than 1 degree of freedom after pooling make the test fail (p-value 0, `failure`
//    says why). The counts need not sum to the same total: the caller decides what they cover.
//  - sidakSignificance(alpha, tests): the per-test significance 1 - (1 - alpha)^(1/tests) that
//    keeps the chance of any false failure among `tests` independent tests at alpha.
#pragma once

#include <string>
#include <vector>

namespace brdfa {

double regularizedGammaP(double a, double x);
double regularizedGammaQ(double a, double x);
double chiSquareSurvival(double chi2, double dof);
double sidakSignificance(double alpha, int tests);

struct ChiSquareResult {
  double statistic = 0;
  int dof = 0;
  double pValue = 0;
  int pooledCells = 0;  // cells merged into the pool (0 when none was needed)
  std::string failure;  // non-empty when the test failed before a p-value (pValue is then 0)
};

ChiSquareResult chiSquareTest(const std::vector<double>& observed, const std::vector<double>& expected,
                              double minExpected = 5.0);

}  // namespace brdfa
