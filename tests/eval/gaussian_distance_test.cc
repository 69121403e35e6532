// Hellinger, Bhattacharyya and COVDIFF between Gaussians against closed forms (1e-9) and a
// Monte-Carlo estimate of the Bhattacharyya coefficient (within sampling error).

#include "skerry/eval/gaussian_distance.h"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <cmath>
#include <random>

namespace skerry {
namespace {

/// HED^2 of two 1-D Gaussians, written independently of the implementation:
/// 1 - sqrt(2 s1 s2 / (s1^2 + s2^2)) exp(-d^2 / (4 (s1^2 + s2^2))).
double Hed2OneD(double d, double s1, double s2) {
  return 1.0 - std::sqrt(2.0 * s1 * s2 / (s1 * s1 + s2 * s2)) *
                   std::exp(-d * d / (4.0 * (s1 * s1 + s2 * s2)));
}

Eigen::MatrixXd RandomSpd(int n, std::mt19937_64& rng, double scale) {
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::MatrixXd a(n, n);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) a(i, j) = g(rng);
  }
  return scale * (a * a.transpose() + 0.5 * Eigen::MatrixXd::Identity(n, n));
}

Eigen::VectorXd M(std::initializer_list<double> v) {
  Eigen::VectorXd x(v.size());
  int i = 0;
  for (double e : v) x(i++) = e;
  return x;
}

TEST(GaussianDistance, OneDimensionalClosedForm) {
  for (const auto& [d, s1, s2] : std::vector<std::tuple<double, double, double>>{
           {0.0, 1.0, 1.0}, {1.0, 1.0, 1.0}, {0.3, 0.5, 2.0}, {-4.0, 0.1, 0.2}, {2.0, 3.0, 0.7}}) {
    const GaussianDistance g = CompareGaussians(M({d}), M({s1 * s1}), M({s2 * s2}));
    ASSERT_TRUE(g.valid);
    EXPECT_NEAR(g.hellinger_sq, Hed2OneD(d, s1, s2), 1e-9) << d << " " << s1 << " " << s2;
    EXPECT_NEAR(g.hellinger, std::sqrt(Hed2OneD(d, s1, s2)), 1e-9);
    EXPECT_NEAR(g.covdiff, std::sqrt(Hed2OneD(0.0, s1, s2)), 1e-9);
    // The mean part: two Gaussians of the average variance, (s1^2 + s2^2) / 2 each.
    const double s_bar = std::sqrt(0.5 * (s1 * s1 + s2 * s2));
    EXPECT_NEAR(g.meandiff, std::sqrt(Hed2OneD(d, s_bar, s_bar)), 1e-9);
    EXPECT_NEAR(1.0 - g.hellinger_sq,
                (1.0 - g.meandiff * g.meandiff) * (1.0 - g.covdiff * g.covdiff), 1e-12);
    const double v = s1 * s1 + s2 * s2;
    EXPECT_NEAR(g.bhattacharyya, d * d / (4.0 * v) + 0.5 * std::log(v / (2.0 * s1 * s2)), 1e-9);
  }
}

TEST(GaussianDistance, DiagonalIsAProductOfOneDimensionalCoefficients) {
  const Eigen::VectorXd d = M({0.5, -1.0, 0.0, 2.0});
  const Eigen::VectorXd s1 = M({1.0, 0.3, 2.0, 1.5}), s2 = M({0.8, 0.3, 1.0, 4.0});
  double bc = 1.0;
  for (int i = 0; i < 4; ++i) bc *= 1.0 - Hed2OneD(d(i), s1(i), s2(i));
  const GaussianDistance g = CompareGaussians(d, s1.array().square().matrix().asDiagonal(),
                                              s2.array().square().matrix().asDiagonal());
  ASSERT_TRUE(g.valid);
  EXPECT_NEAR(g.hellinger_sq, 1.0 - bc, 1e-9);
}

TEST(GaussianDistance, FullCovarianceAgreesWithExplicitDeterminants) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> g(0.0, 1.0);
  for (int n : {2, 3, 6}) {
    for (int trial = 0; trial < 5; ++trial) {
      const Eigen::MatrixXd p1 = RandomSpd(n, rng, 0.5), p2 = RandomSpd(n, rng, 2.0);
      Eigen::VectorXd d(n);
      for (int i = 0; i < n; ++i) d(i) = g(rng);
      // Independent path: long double, explicit determinants and inverse (fine at these sizes).
      using MatL = Eigen::Matrix<long double, Eigen::Dynamic, Eigen::Dynamic>;
      const MatL l1 = p1.cast<long double>(), l2 = p2.cast<long double>();
      const MatL lbar = (l1 + l2) / 2.0L;
      const Eigen::Matrix<long double, Eigen::Dynamic, 1> ld = d.cast<long double>();
      const long double maha = ld.dot(lbar.inverse() * ld);
      const long double bc = std::pow(l1.determinant(), 0.25L) * std::pow(l2.determinant(), 0.25L) /
                             std::sqrt(lbar.determinant()) * std::exp(-maha / 8.0L);
      const GaussianDistance r = CompareGaussians(d, p1, p2);
      ASSERT_TRUE(r.valid);
      EXPECT_NEAR(r.hellinger_sq, static_cast<double>(1.0L - bc), 1e-9) << "n=" << n;
      EXPECT_NEAR(r.bhattacharyya, static_cast<double>(-std::log(bc)), 1e-9) << "n=" << n;
      // Symmetric in the two Gaussians (Delta changes sign).
      const GaussianDistance s = CompareGaussians(-d, p2, p1);
      EXPECT_NEAR(s.hellinger_sq, r.hellinger_sq, 1e-12);
    }
  }
}

TEST(GaussianDistance, IdenticalEqualAndFarApart) {
  std::mt19937_64 rng(3);
  const Eigen::MatrixXd p = RandomSpd(15, rng, 1e-3);
  const GaussianDistance same = CompareGaussians(Eigen::VectorXd::Zero(15), p, p);
  ASSERT_TRUE(same.valid);
  EXPECT_EQ(same.hellinger, 0.0);
  EXPECT_EQ(same.covdiff, 0.0);
  EXPECT_EQ(same.bhattacharyya, 0.0);
  // Equal covariances, different means: COVDIFF stays 0.
  const GaussianDistance shifted = CompareGaussians(Eigen::VectorXd::Constant(15, 0.01), p, p);
  EXPECT_EQ(shifted.covdiff, 0.0);
  EXPECT_GT(shifted.hellinger, 0.0);
  // Very far apart: HED -> 1 without NaN or overflow; tiny 15-D determinants are fine.
  const GaussianDistance far = CompareGaussians(Eigen::VectorXd::Constant(15, 1e6), p, 1e-6 * p);
  ASSERT_TRUE(far.valid);
  EXPECT_EQ(far.hellinger, 1.0);
  EXPECT_TRUE(std::isfinite(far.bhattacharyya));
  // Nearly identical: -expm1 keeps the small value instead of rounding it to 0.
  const GaussianDistance near = CompareGaussians(M({1e-9}), M({1.0}), M({1.0}));
  EXPECT_NEAR(near.hellinger_sq, 1e-18 / 8.0, 1e-30);
}

TEST(GaussianDistance, InvalidCovariancesAreReportedNotPropagated) {
  const Eigen::VectorXd d = M({0.0, 0.0});
  Eigen::MatrixXd good = Eigen::MatrixXd::Identity(2, 2);
  Eigen::MatrixXd indefinite(2, 2);
  indefinite << 1.0, 2.0, 2.0, 1.0;
  Eigen::MatrixXd nan = good;
  nan(0, 0) = std::nan("");
  Eigen::MatrixXd asym = good;
  asym(0, 1) = 0.5;
  for (const Eigen::MatrixXd& bad :
       {indefinite, nan, asym, Eigen::MatrixXd(Eigen::MatrixXd::Zero(2, 2))}) {
    const GaussianDistance g = CompareGaussians(d, good, bad);
    EXPECT_FALSE(g.valid);
    EXPECT_EQ(g.hellinger, 0.0);
    EXPECT_FALSE(CompareGaussians(d, bad, good).valid);
  }
  EXPECT_FALSE(CompareGaussians(M({0.0, 0.0, 0.0}), good, good).valid);  // size mismatch
}

/// BC = integral sqrt(p1 p2) = E_{x~p1}[ sqrt(p2(x) / p1(x)) ]: the sample mean over draws from
/// p1 must agree with exp(-D_B) within 4 standard errors.
void MonteCarloCheck(int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0.0, 1.0);
  const Eigen::MatrixXd p1 = RandomSpd(n, rng, 0.3), p2 = RandomSpd(n, rng, 0.5);
  Eigen::VectorXd mu2(n);
  for (int i = 0; i < n; ++i) mu2(i) = 0.4 * g(rng);
  const Eigen::LLT<Eigen::MatrixXd> l1(p1), l2(p2);
  const double logdet1 = 2.0 * l1.matrixL().toDenseMatrix().diagonal().array().log().sum();
  const double logdet2 = 2.0 * l2.matrixL().toDenseMatrix().diagonal().array().log().sum();
  const int samples = 200000;
  double sum = 0.0, sum_sq = 0.0;
  Eigen::VectorXd z(n);
  for (int s = 0; s < samples; ++s) {
    for (int i = 0; i < n; ++i) z(i) = g(rng);
    const Eigen::VectorXd x = l1.matrixL() * z;  // x ~ N(0, P1)
    const Eigen::VectorXd r2 = x - mu2;
    const double log_p1 = -0.5 * z.squaredNorm() - 0.5 * logdet1;
    const double log_p2 = -0.5 * r2.dot(l2.solve(r2)) - 0.5 * logdet2;
    const double w = std::exp(0.5 * (log_p2 - log_p1));
    sum += w;
    sum_sq += w * w;
  }
  const double mean = sum / samples;
  const double std_err = std::sqrt((sum_sq / samples - mean * mean) / samples);
  const GaussianDistance d = CompareGaussians(mu2, p1, p2);
  ASSERT_TRUE(d.valid);
  const double bc = 1.0 - d.hellinger_sq;
  EXPECT_GT(bc, 0.05);
  EXPECT_LT(bc, 0.95);
  EXPECT_NEAR(mean, bc, 4.0 * std_err) << "n=" << n << " std_err=" << std_err;
  EXPECT_LT(std_err, 0.01);  // the check has teeth
}

TEST(GaussianDistance, MonteCarloBhattacharyyaCoefficient3D) { MonteCarloCheck(3, 11); }
TEST(GaussianDistance, MonteCarloBhattacharyyaCoefficient6D) { MonteCarloCheck(6, 12); }

}  // namespace
}  // namespace skerry
