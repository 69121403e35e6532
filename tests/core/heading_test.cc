#include "skerry/core/heading.h"

#include <gtest/gtest.h>

#include <cmath>

namespace skerry {
namespace {

// Body whose x axis points along `x_w` (level), built from the axes directly, not via
// QuaternionFromRollPitchHeading.
Eigen::Quaterniond LevelBodyPointing(const Eigen::Vector3d& x_w) {
  Eigen::Matrix3d R;
  R.col(0) = x_w;
  R.col(2) = Eigen::Vector3d::UnitZ();
  R.col(1) = R.col(2).cross(R.col(0));
  return Eigen::Quaterniond(R);
}

TEST(HeadingTest, CompassPoints) {
  EXPECT_NEAR(HeadingDeg(LevelBodyPointing(Eigen::Vector3d::UnitY())), 0.0, 1e-12);   // north
  EXPECT_NEAR(HeadingDeg(LevelBodyPointing(Eigen::Vector3d::UnitX())), 90.0, 1e-12);  // east
  EXPECT_NEAR(HeadingDeg(LevelBodyPointing(-Eigen::Vector3d::UnitY())), 180.0, 1e-12);
  EXPECT_NEAR(HeadingDeg(LevelBodyPointing(-Eigen::Vector3d::UnitX())), 270.0, 1e-12);
  EXPECT_NEAR(HeadingRad(LevelBodyPointing(-Eigen::Vector3d::UnitX())), -M_PI / 2.0, 1e-12);
  // Identity: body x = world x = east.
  EXPECT_NEAR(HeadingDeg(Eigen::Quaterniond::Identity()), 90.0, 1e-12);
}

TEST(HeadingTest, RangeIsHalfOpen) {
  const double h = HeadingRad(LevelBodyPointing(-Eigen::Vector3d::UnitY()));
  EXPECT_NEAR(std::fabs(h), M_PI, 1e-12);
  EXPECT_GT(h, 0.0);  // (-pi, pi]: south is +pi
  const double d = HeadingDeg(LevelBodyPointing(Eigen::Vector3d(-1e-17, 1.0, 0.0).normalized()));
  EXPECT_GE(d, 0.0);
  EXPECT_LT(d, 360.0);
}

TEST(HeadingTest, FromRollPitchHeading) {
  for (double heading_deg : {0.0, 30.0, 90.0, 179.0, 250.0, 359.0}) {
    const Eigen::Quaterniond q =
        QuaternionFromRollPitchHeading(0.1, -0.2, heading_deg * M_PI / 180.0);
    EXPECT_NEAR(HeadingDeg(q), heading_deg, 1e-9);
  }
  // Level, heading north: body x = north, body y (left) = west, z up.
  const Eigen::Matrix3d R = QuaternionFromRollPitchHeading(0, 0, 0).toRotationMatrix();
  EXPECT_LT((R.col(0) - Eigen::Vector3d::UnitY()).norm(), 1e-12);
  EXPECT_LT((R.col(1) + Eigen::Vector3d::UnitX()).norm(), 1e-12);
  // Positive pitch is a right-handed rotation about body y (left): the nose goes down.
  const Eigen::Vector3d nose = QuaternionFromRollPitchHeading(0, 0.3, 0) * Eigen::Vector3d::UnitX();
  EXPECT_LT(nose.z(), 0.0);
  // Positive roll about x (forward): the left side (y) goes up.
  const Eigen::Vector3d left = QuaternionFromRollPitchHeading(0.3, 0, 0) * Eigen::Vector3d::UnitY();
  EXPECT_GT(left.z(), 0.0);
}

}  // namespace
}  // namespace skerry
