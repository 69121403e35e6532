#include "skerry/core/heading.h"

#include <gtest/gtest.h>

#include <cmath>

#include "skerry/core/geodesy.h"

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

// Away from the origin, north is the local meridian's: checked against north and east found by
// differencing GeographicLib's geodetic -> ENU conversion along the meridian and the parallel at
// the place (not through EarthModel::LocalLevel), and against the convergence of the meridians,
// dlon sin(lat), 20 km east and west of an origin at 47 deg N (0.19 deg) and 60 deg S.
TEST(HeadingTest, AwayFromTheOriginHeadingIsFromTheLocalNorth) {
  for (const double lat0 : {47.0, -60.0}) {
    const GeoOrigin origin{lat0, 9.0, 400.0};
    const EarthModel earth(origin);
    const LocalFrame frame(origin);
    for (const Eigen::Vector3d& p_w :
         {Eigen::Vector3d(20000.0, 0.0, 0.0), Eigen::Vector3d(-20000.0, 3000.0, 0.0),
          Eigen::Vector3d(5000.0, -15000.0, 10.0)}) {
      SCOPED_TRACE(::testing::Message() << lat0 << " at " << p_w.transpose());
      const Eigen::Vector3d llh = frame.ToGeodetic(p_w);
      constexpr double kStep = 1e-6;  // deg
      const Eigen::Vector3d north = (frame.ToEnu(llh.x() + kStep, llh.y(), llh.z()) -
                                     frame.ToEnu(llh.x() - kStep, llh.y(), llh.z()))
                                        .normalized();
      const Eigen::Vector3d east = (frame.ToEnu(llh.x(), llh.y() + kStep, llh.z()) -
                                    frame.ToEnu(llh.x(), llh.y() - kStep, llh.z()))
                                       .normalized();
      for (const double yaw : {0.0, 1.0, M_PI / 2.0, -2.5}) {
        const Eigen::Vector3d x_w(std::cos(yaw), std::sin(yaw), 0.0);
        double expected = std::atan2(x_w.dot(east), x_w.dot(north)) * 180.0 / M_PI;
        if (expected < 0.0) expected += 360.0;
        const Eigen::Quaterniond q(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
        EXPECT_NEAR(HeadingDegAt(earth, p_w, q), expected, 1e-5) << yaw;
      }
      // w's north seen from the place: east of the local north by the convergence east of the
      // origin in the north, west of it in the south.
      const double convergence = std::remainder(
          HeadingDegAt(earth, p_w,
                       Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2.0, Eigen::Vector3d::UnitZ()))),
          360.0);
      const double dlon = llh.y() - origin.lon_deg;
      EXPECT_NEAR(convergence, dlon * std::sin(llh.x() * M_PI / 180.0), 0.01 * std::abs(dlon));
      EXPECT_GT(std::abs(convergence), 0.02);
    }
  }
  // At the origin, and on a flat Earth, w's north.
  const EarthModel earth(GeoOrigin{47.0, 9.0, 0.0});
  const Eigen::Quaterniond q(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()));
  EXPECT_NEAR(HeadingDegAt(earth, Eigen::Vector3d::Zero(), q), HeadingDeg(q), 1e-9);
  EXPECT_EQ(HeadingDegAt(EarthModel::Flat(), Eigen::Vector3d(20000.0, 0.0, 0.0), q), HeadingDeg(q));
}

}  // namespace
}  // namespace skerry
