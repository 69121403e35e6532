// ConstantTimes / TimesConstant against Eigen's own products, on doubles and on ceres::Jet (value
// and every derivative), for random matrices and quaternions.

#include "skerry/core/constant_product.h"

#include <ceres/jet.h>
#include <gtest/gtest.h>

#include <random>

namespace skerry {
namespace {

using Jet = ceres::Jet<double, 5>;

template <int N>
Eigen::Matrix<Jet, N, 1> RandomJetVector(std::mt19937* rng) {
  std::normal_distribution<double> n;
  Eigen::Matrix<Jet, N, 1> x;
  for (int i = 0; i < N; ++i) {
    x(i).a = n(*rng);
    for (int k = 0; k < 5; ++k) x(i).v[k] = n(*rng);
  }
  return x;
}

void ExpectJetNear(const Jet& a, const Jet& b) {
  EXPECT_NEAR(a.a, b.a, 1e-12);
  for (int k = 0; k < 5; ++k) EXPECT_NEAR(a.v[k], b.v[k], 1e-12);
}

TEST(ConstantProduct, MatrixTimesVectorMatchesEigen) {
  std::mt19937 rng(3);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Matrix<double, 4, 3> A = Eigen::Matrix<double, 4, 3>::Random();
    const Eigen::Vector3d x = Eigen::Vector3d::Random();
    EXPECT_TRUE(ConstantTimes<double>(A, x).isApprox(A * x, 1e-14));
    const Eigen::Matrix<Jet, 3, 1> xj = RandomJetVector<3>(&rng);
    const Eigen::Matrix<Jet, 4, 1> got = ConstantTimes<Jet>(A, xj);
    const Eigen::Matrix<Jet, 4, 1> want = A.cast<Jet>() * xj;
    for (int i = 0; i < 4; ++i) ExpectJetNear(got(i), want(i));
  }
}

TEST(ConstantProduct, LowerTriangularSkipsOnlyZeros) {
  Eigen::Matrix3d L = Eigen::Matrix3d::Random().triangularView<Eigen::Lower>();
  const Eigen::Vector3d x = Eigen::Vector3d::Random();
  EXPECT_TRUE(ConstantTimes<double>(L, x, true).isApprox(L * x, 1e-14));
  // A full matrix told it is lower-triangular ignores its upper part: the flag is a promise.
  const Eigen::Matrix3d F = Eigen::Matrix3d::Random();
  EXPECT_TRUE(ConstantTimes<double>(F, x, true)
                  .isApprox(Eigen::Matrix3d(F.triangularView<Eigen::Lower>()) * x, 1e-14));
}

TEST(ConstantProduct, QuaternionProductsMatchEigen) {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    const Eigen::Quaterniond a = Eigen::Quaterniond::UnitRandom();
    const Eigen::Quaterniond b = Eigen::Quaterniond::UnitRandom();
    EXPECT_TRUE(ConstantTimes<double>(a, b).coeffs().isApprox((a * b).coeffs(), 1e-14));
    EXPECT_TRUE(TimesConstant<double>(a, b).coeffs().isApprox((a * b).coeffs(), 1e-14));
    const Eigen::Quaternion<Jet> bj(RandomJetVector<4>(&rng));
    const Eigen::Quaternion<Jet> left = ConstantTimes<Jet>(a, bj);
    const Eigen::Quaternion<Jet> right = TimesConstant<Jet>(bj, a);
    const Eigen::Quaternion<Jet> want_left = a.cast<Jet>() * bj;
    const Eigen::Quaternion<Jet> want_right = bj * a.cast<Jet>();
    for (int i = 0; i < 4; ++i) {
      ExpectJetNear(left.coeffs()(i), want_left.coeffs()(i));
      ExpectJetNear(right.coeffs()(i), want_right.coeffs()(i));
    }
  }
}

}  // namespace
}  // namespace skerry
