// SO(3) helpers of core/so3.h, tested against closed forms and numeric differences.

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "factors/test_utils.h"
#include "skerry/core/so3.h"

namespace skerry {
namespace {

constexpr double kPi = 3.14159265358979323846;

TEST(So3Test, HatIsCrossProduct) {
  const Eigen::Vector3d a(0.3, -1.2, 2.0), b(-0.7, 0.4, 1.1);
  EXPECT_LT((Hat(a) * b - a.cross(b)).norm(), 1e-15);
}

TEST(So3Test, ExpMatchesAngleAxis) {
  std::mt19937 rng(1);
  for (int k = 0; k < 100; ++k) {
    const Eigen::Vector3d phi = test::RandomVector(&rng, 1.0);
    const Eigen::Matrix3d R_ref =
        Eigen::AngleAxisd(phi.norm(), phi.normalized()).toRotationMatrix();
    EXPECT_LT((ExpSO3(phi) - R_ref).norm(), 1e-14) << phi.transpose();
    EXPECT_NEAR(ExpQ(phi).norm(), 1.0, 1e-15);
  }
}

TEST(So3Test, ExpLogRoundTrip) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> angle(0.0, kPi - 1e-3);
  for (int k = 0; k < 200; ++k) {
    const Eigen::Vector3d axis = test::RandomVector(&rng, 1.0).normalized();
    const Eigen::Vector3d phi = angle(rng) * axis;
    EXPECT_LT((LogQ(ExpQ(phi)) - phi).norm(), 1e-12) << phi.transpose();
    EXPECT_LT((LogSO3(ExpSO3(phi)) - phi).norm(), 1e-12) << phi.transpose();
    // Log of a quaternion with w < 0 represents the same rotation.
    Eigen::Quaterniond q = ExpQ(phi);
    q.coeffs() = -q.coeffs();
    EXPECT_LT((LogQ(q) - phi).norm(), 1e-12) << phi.transpose();
  }
  // And Exp(Log(q)) == q up to sign for random rotations.
  for (int k = 0; k < 100; ++k) {
    const Eigen::Quaterniond q = test::RandomQuaternion(&rng);
    EXPECT_LT(test::AngleBetween(ExpQ(LogQ(q)), q), 1e-12);
    EXPECT_LE(LogQ(q).norm(), kPi + 1e-12);
  }
}

TEST(So3Test, LogNearPi) {
  const Eigen::Vector3d axis = Eigen::Vector3d(1.0, -2.0, 0.5).normalized();
  for (double eps : {1e-3, 1e-6, 1e-9, 0.0}) {
    const double angle = kPi - eps;
    const Eigen::Vector3d phi = LogQ(ExpQ(Eigen::Vector3d(angle * axis)));
    EXPECT_NEAR(phi.norm(), angle, 1e-9) << eps;
    // At exactly pi the axis sign is ambiguous; otherwise it must be preserved.
    EXPECT_NEAR(std::abs(phi.normalized().dot(axis)), 1.0, 1e-9) << eps;
    if (eps > 0.0) {
      EXPECT_GT(phi.dot(axis), 0.0) << eps;
    }
    // Rotation-matrix path: Log(Exp(phi)) reproduces the rotation.
    const Eigen::Matrix3d R = ExpSO3(angle * axis);
    EXPECT_LT((ExpSO3(LogSO3(R)) - R).norm(), 1e-8) << eps;
  }
  // Slightly beyond pi wraps to the other side: angle 2 pi - (pi + e) about -axis.
  const Eigen::Vector3d phi = LogQ(ExpQ(Eigen::Vector3d((kPi + 0.01) * axis)));
  EXPECT_LT((phi + (kPi - 0.01) * axis).norm(), 1e-12);
}

// The Taylor branches must join the closed forms continuously: evaluate just inside and just
// outside each threshold and compare with the exact (long double) formula.
TEST(So3Test, SmallAngleBranchContinuity) {
  const Eigen::Vector3d axis = Eigen::Vector3d(0.2, 0.9, -0.4).normalized();
  for (double theta : {1e-12, 0.99e-8, 1.01e-8, 1e-7, 0.99e-5, 1.01e-5, 1e-4, 1e-3}) {
    const Eigen::Vector3d phi = theta * axis;
    const long double th = theta;
    const Eigen::Quaterniond q = ExpQ(phi);
    EXPECT_NEAR(q.w(), static_cast<double>(std::cos(th / 2)), 3e-16) << theta;
    const double im_exact = static_cast<double>(std::sin(th / 2) / th);
    EXPECT_LT((q.vec() - im_exact * phi).norm(), 1e-15 * theta) << theta;
    // Log back: relative accuracy.
    EXPECT_LT((LogQ(q) - phi).norm(), 1e-12 * theta) << theta;
    // Right Jacobian: compare with a long-double closed form.
    const Eigen::Matrix3d W = Hat(phi);
    const double c1 = static_cast<double>((1 - std::cos(th)) / (th * th));
    const double c2 = static_cast<double>((th - std::sin(th)) / (th * th * th));
    const Eigen::Matrix3d Jr_exact = Eigen::Matrix3d::Identity() - c1 * W + c2 * W * W;
    // Closed forms in long double lose accuracy themselves for tiny theta; only compare where
    // they are reliable (theta >= 1e-5) and require I - W/2 otherwise.
    // Just above the 1e-5 threshold core's double closed form itself cancels: 1 - cos(theta) has
    // an absolute error ~1e-16, i.e. ~1e-16/theta ~ 1e-11 on the W coefficient term, so 1e-10.
    if (theta >= 1e-5) {
      EXPECT_LT((RightJacobianSO3(phi) - Jr_exact).norm(), 1e-10) << theta;
    }
    EXPECT_LT((RightJacobianSO3(phi) - (Eigen::Matrix3d::Identity() - 0.5 * W)).norm(),
              theta * theta)
        << theta;
    EXPECT_LT((RightJacobianInverseSO3(phi) - (Eigen::Matrix3d::Identity() + 0.5 * W)).norm(),
              theta * theta)
        << theta;
  }
}

// Jr(phi) defined by Exp(phi + d) = Exp(phi) Exp(Jr(phi) d) + O(d^2): numeric check via
// Jr = d/dd Log(Exp(phi)^T Exp(phi + d)) at d = 0.
TEST(So3Test, RightJacobianMatchesNumericExp) {
  std::mt19937 rng(3);
  std::vector<Eigen::Vector3d> phis = {
      Eigen::Vector3d(1e-7, -2e-7, 3e-8), Eigen::Vector3d(3e-6, 1e-6, -2e-6),
      Eigen::Vector3d(0.3, -0.2, 0.1), Eigen::Vector3d(0.0, 0.0, 2.9)};
  // Stay inside the ball |phi| < pi where Log(Exp(phi)) == phi (the inverse check needs it).
  for (int k = 0; k < 20; ++k) {
    const Eigen::Vector3d axis = test::RandomVector(&rng, 1.0).normalized();
    phis.push_back(std::uniform_real_distribution<double>(0.0, 3.0)(rng) * axis);
  }
  for (const Eigen::Vector3d& phi : phis) {
    const Eigen::Quaterniond q0 = ExpQ(phi);
    auto f = [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
      return LogQ<double>(q0.conjugate() * ExpQ<double>(phi + Eigen::Vector3d(d)));
    };
    test::TestJacobian("Jr", RightJacobianSO3(phi), f, Eigen::VectorXd::Zero(3), 1e-8);
    // Inverse: Log(Exp(phi) Exp(d)) = phi + Jr^-1 d.
    auto g = [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
      return LogQ<double>(q0 * ExpQ<double>(Eigen::Vector3d(d)));
    };
    test::TestJacobian("Jr^-1", RightJacobianInverseSO3(phi), g, Eigen::VectorXd::Zero(3), 1e-8);
  }
}

TEST(So3Test, RightJacobianInverseTimesRightJacobianIsIdentity) {
  std::mt19937 rng(4);
  for (int k = 0; k < 100; ++k) {
    const Eigen::Vector3d axis = test::RandomVector(&rng, 1.0).normalized();
    const double angle = std::uniform_real_distribution<double>(1e-9, 3.0)(rng);
    const Eigen::Vector3d phi = angle * axis;
    const Eigen::Matrix3d P = RightJacobianInverseSO3(phi) * RightJacobianSO3(phi);
    EXPECT_LT((P - Eigen::Matrix3d::Identity()).norm(), 1e-12) << phi.transpose();
  }
}

TEST(So3Test, WrapAngle) {
  EXPECT_NEAR(WrapAngle(3.0 * kPi / 2.0), -kPi / 2.0, 1e-15);
  EXPECT_NEAR(WrapAngle(-3.0 * kPi / 2.0), kPi / 2.0, 1e-15);
  EXPECT_NEAR(WrapAngle(0.25 + 4.0 * kPi), 0.25, 1e-14);
}

}  // namespace
}  // namespace skerry
