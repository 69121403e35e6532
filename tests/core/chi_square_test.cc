#include "skerry/core/chi_square.h"

#include <gtest/gtest.h>

#include <cmath>

namespace skerry {
namespace {

TEST(ChiSquareTest, KnownQuantiles) {
  // Reference values (e.g. NIST/SEMATECH e-Handbook table, R qchisq).
  EXPECT_NEAR(ChiSquareQuantile(0.95, 3), 7.814727903, 1e-8);
  EXPECT_NEAR(ChiSquareQuantile(0.999, 1), 10.827566170, 1e-6);
  EXPECT_NEAR(ChiSquareQuantile(0.95, 1), 3.841458821, 1e-8);
  EXPECT_NEAR(ChiSquareQuantile(0.05, 2), 0.102586589, 1e-8);
  EXPECT_NEAR(ChiSquareQuantile(0.025, 6), 1.237344246, 1e-8);
  EXPECT_NEAR(ChiSquareQuantile(0.975, 6), 14.449375335, 1e-8);
  EXPECT_NEAR(ChiSquareQuantile(0.5, 2), 2.0 * std::log(2.0), 1e-12);
}

TEST(ChiSquareTest, CdfKnownValues) {
  EXPECT_NEAR(ChiSquareCdf(7.814727903, 3), 0.95, 1e-9);
  EXPECT_NEAR(ChiSquareCdf(2.0, 2), 1.0 - std::exp(-1.0), 1e-14);  // chi2(2) is exponential
  EXPECT_EQ(ChiSquareCdf(0.0, 4), 0.0);
  EXPECT_EQ(ChiSquareCdf(-1.0, 4), 0.0);
  // chi2(1): P(X <= x) = erf(sqrt(x/2)).
  for (double x : {0.01, 0.5, 1.0, 3.0, 20.0}) {
    EXPECT_NEAR(ChiSquareCdf(x, 1), std::erf(std::sqrt(x / 2.0)), 1e-13) << x;
  }
}

// Large dof (ANEES over many epochs): compare with the Wilson-Hilferty cube-root normal
// approximation, accurate to ~1e-5 relative at this size.
TEST(ChiSquareTest, LargeDofMatchesWilsonHilferty) {
  const double k = 3000.0;
  for (const auto& [p, z] : {std::pair{0.025, -1.959963985}, std::pair{0.975, 1.959963985},
                             std::pair{0.5, 0.0}, std::pair{0.999, 3.090232306}}) {
    const double c = 2.0 / (9.0 * k);
    const double wh = k * std::pow(1.0 - c + z * std::sqrt(c), 3);
    EXPECT_NEAR(ChiSquareQuantile(p, k) / wh, 1.0, 5e-5) << p;
  }
  // And the round trip through the CDF, also for 6 x 5000 = 30000 dof.
  for (double dof : {3000.0, 30000.0}) {
    for (double p : {0.025, 0.975}) {
      EXPECT_NEAR(ChiSquareCdf(ChiSquareQuantile(p, dof), dof), p, 1e-10);
    }
  }
}

TEST(ChiSquareTest, QuantileInvertsCdfEverywhere) {
  for (double dof : {0.5, 1.0, 2.0, 3.0, 7.0, 50.0, 300.0}) {
    for (double p : {1e-6, 0.01, 0.3, 0.5, 0.9, 0.999999}) {
      const double x = ChiSquareQuantile(p, dof);
      EXPECT_NEAR(ChiSquareCdf(x, dof), p, 1e-10 + 1e-9 * p) << dof << " " << p;
    }
  }
}

}  // namespace
}  // namespace skerry
