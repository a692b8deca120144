// The chi-square math of the sampler check (renderer/src/analysis/chi_square.h) against closed forms and
// published table values, and the pooling rules of pbrt-v4's Chi2Test.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "analysis/chi_square.h"

namespace brdfa {
namespace {

// Closed forms of the chi-square survival function Q(k/2, x/2):
//  k = 1: erfc(sqrt(x/2));  k = 2: exp(-x/2);
//  k even: exp(-x/2) sum_{j < k/2} (x/2)^j / j!;
//  k odd:  erfc(sqrt(x/2)) + exp(-x/2) sum_{j=1}^{(k-1)/2} (x/2)^(j-1/2) / Gamma(j + 1/2).
// (From Q(a + 1, y) = Q(a, y) + y^a e^-y / Gamma(a + 1).)
double survivalClosedForm(int k, double x) {
  const double y = 0.5 * x;
  if (k % 2 == 0) {
    double term = 1, sum = 0;
    for (int j = 0; j < k / 2; ++j) {
      sum += term;
      term *= y / (j + 1);
    }
    return std::exp(-y) * sum;
  }
  double sum = std::erfc(std::sqrt(y));
  for (int j = 1; j <= (k - 1) / 2; ++j) sum += std::exp((j - 0.5) * std::log(y) - y - std::lgamma(j + 0.5));
  return sum;
}

TEST(ChiSquare, SurvivalMatchesClosedFormsOnBothSidesOfTheSeriesSwitch) {
  // The switch is at x/2 = k/2 + 1; the points straddle it for every k, and k = 199 is the
  // largest dof the sampler check produces (200 cells).
  for (int k : {1, 2, 3, 10, 11, 50, 199})
    for (double x : {0.01, 0.5, 1.0, 2.0, 3.0, 5.0, 9.0, 15.0, 30.0, 60.0, 150.0, 200.0, 203.0, 260.0, 400.0}) {
      const double want = survivalClosedForm(k, x);
      const double got = chiSquareSurvival(x, k);
      EXPECT_NEAR(got, want, 1e-12 + 1e-10 * want) << "dof " << k << " at " << x;
      EXPECT_NEAR(regularizedGammaP(0.5 * k, 0.5 * x), 1.0 - want, 1e-12) << "dof " << k << " at " << x;
    }
}

TEST(ChiSquare, CdfMatchesTableValues) {
  // Critical values of the chi-square distribution (NIST/SEMATECH e-Handbook, table 1.3.6.7.4,
  // here to more digits): CDF(x) = 0.95 / 0.99 / 0.5.
  EXPECT_NEAR(regularizedGammaP(0.5, 0.5 * 3.841458820694124), 0.95, 1e-12);
  EXPECT_NEAR(regularizedGammaP(0.5, 0.5 * 6.634896601021214), 0.99, 1e-12);
  EXPECT_NEAR(regularizedGammaP(1.0, 0.5 * 5.991464547107979), 0.95, 1e-12);
  EXPECT_NEAR(regularizedGammaP(1.0, 0.5 * 9.210340371976184), 0.99, 1e-12);
  EXPECT_NEAR(regularizedGammaP(5.0, 0.5 * 18.307038053275146), 0.95, 1e-12);
  EXPECT_NEAR(regularizedGammaP(5.0, 0.5 * 23.209251158954356), 0.99, 1e-12);
  EXPECT_NEAR(regularizedGammaP(5.0, 0.5 * 9.341817765591966), 0.50, 1e-12);
  // dof 1 at 1: erf(1/sqrt(2)), the one-sigma probability.
  EXPECT_NEAR(regularizedGammaP(0.5, 0.5), 0.6826894921370859, 1e-13);
}

TEST(ChiSquare, TinyTailProbabilitiesKeepTheirDigits) {
  // 1 - P would round these to 0: Q is computed directly.
  EXPECT_NEAR(chiSquareSurvival(100.0, 2) / std::exp(-50.0), 1.0, 1e-10);
  EXPECT_NEAR(chiSquareSurvival(1000.0, 10) / survivalClosedForm(10, 1000.0), 1.0, 1e-9);  // ~1e-208
  EXPECT_NEAR(chiSquareSurvival(600.0, 199) / survivalClosedForm(199, 600.0), 1.0, 1e-9);
}

TEST(ChiSquare, EdgeArguments) {
  EXPECT_EQ(regularizedGammaP(2.0, 0.0), 0.0);
  EXPECT_EQ(regularizedGammaQ(2.0, 0.0), 1.0);
  EXPECT_EQ(regularizedGammaP(2.0, INFINITY), 1.0);
  EXPECT_EQ(regularizedGammaQ(2.0, INFINITY), 0.0);
  EXPECT_TRUE(std::isnan(regularizedGammaP(0.0, 1.0)));
  EXPECT_TRUE(std::isnan(regularizedGammaQ(-1.0, 1.0)));
  EXPECT_TRUE(std::isnan(regularizedGammaP(1.0, NAN)));
}

TEST(ChiSquare, SidakCorrection) {
  EXPECT_DOUBLE_EQ(sidakSignificance(0.01, 1), 0.01);
  EXPECT_NEAR(sidakSignificance(0.01, 4), 1.0 - std::pow(0.99, 0.25), 1e-15);
  EXPECT_NEAR(sidakSignificance(0.01, 4), 0.0025094, 1e-7);
  // The corrected level over n tests gives back the family-wise level.
  EXPECT_NEAR(1.0 - std::pow(1.0 - sidakSignificance(0.05, 24), 24), 0.05, 1e-14);
}

TEST(ChiSquare, TestStatisticAndPooling) {
  // A perfect fit: statistic 0, p-value 1, dof = cells - 1.
  ChiSquareResult exact = chiSquareTest({10, 20, 30, 40}, {10, 20, 30, 40});
  EXPECT_TRUE(exact.failure.empty());
  EXPECT_EQ(exact.dof, 3);
  EXPECT_DOUBLE_EQ(exact.statistic, 0.0);
  EXPECT_DOUBLE_EQ(exact.pValue, 1.0);

  // Cells 0-2 (expected 1, 2, 1.5) are pooled into one of expected 4.5 < 5, which then also
  // takes the next smallest cell (expected 10) to reach 5: cells {0,1,2,3} -> one pooled cell
  // (observed 3 + 2 + 0 + 12 = 17, expected 14.5), plus cells 4 and 5 -> dof 2.
  ChiSquareResult pooled = chiSquareTest({3, 2, 0, 12, 25, 38}, {1, 2, 1.5, 10, 20, 40});
  EXPECT_TRUE(pooled.failure.empty()) << pooled.failure;
  EXPECT_EQ(pooled.pooledCells, 4);
  EXPECT_EQ(pooled.dof, 2);
  const double want = 2.5 * 2.5 / 14.5 + 25.0 / 20.0 + 4.0 / 40.0;
  EXPECT_NEAR(pooled.statistic, want, 1e-12);
  EXPECT_NEAR(pooled.pValue, std::exp(-0.5 * want), 1e-12);

  // A sample where nothing is expected fails outright; an empty expected-0 cell is fine.
  ChiSquareResult impossible = chiSquareTest({1, 50, 50}, {0, 50, 50});
  EXPECT_FALSE(impossible.failure.empty());
  EXPECT_EQ(impossible.pValue, 0.0);
  EXPECT_TRUE(chiSquareTest({0, 50, 50, 50}, {0, 50, 50, 50}).failure.empty());

  // Bad expected counts and too few cells fail.
  EXPECT_FALSE(chiSquareTest({1, 2}, {NAN, 2}).failure.empty());
  EXPECT_FALSE(chiSquareTest({1, 2}, {-1, 2}).failure.empty());
  EXPECT_FALSE(chiSquareTest({100}, {100}).failure.empty());

  // A clear misfit: tiny p-value.
  ChiSquareResult misfit = chiSquareTest({1000, 0, 0, 0}, {250, 250, 250, 250});
  EXPECT_LT(misfit.pValue, 1e-100);
}

}  // namespace
}  // namespace brdfa
