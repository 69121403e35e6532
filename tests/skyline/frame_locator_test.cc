#include "skerry/skyline/frame_locator.h"

#include <gtest/gtest.h>

#include "skyline/skyline_test_scene.h"

namespace skerry::skyline {
namespace {

constexpr double kDeg = M_PI / 180.0;

Eigen::Matrix3d Level(double roll_deg, double pitch_deg) {
  // A forward camera on a body rolled and pitched, heading north... then with heading removed:
  // R_w_c = Rz(-heading) * Level.
  const Eigen::Quaterniond q_w_b(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(pitch_deg * kDeg, Eigen::Vector3d::UnitY()) *
                                 Eigen::AngleAxisd(roll_deg * kDeg, Eigen::Vector3d::UnitX()));
  return (q_w_b * LevelCameraRotation(0.0)).toRotationMatrix();
}

// From one frame, with the prior 600 m off and no heading: position and heading recovered.
TEST(FrameLocator, GlobalSearchFindsPositionAndHeadingFromOneFrame) {
  const auto horizon = std::make_shared<HorizonPredictor>(testing::MountainRing());
  CameraConfig config = PinholeFromFov("camera", 1920, 1080, 70.0);
  const CameraModel camera(config);
  const Eigen::Matrix3d level = Level(1.5, -1.0);
  const double heading = 217.0 * kDeg;
  const Eigen::Matrix3d r_w_c = Eigen::AngleAxisd(-heading, Eigen::Vector3d::UnitZ()) * level;
  const Eigen::Vector3d p_w_c(-350.0, 420.0, 5.0);
  const auto samples = testing::SyntheticSkyline(*horizon, camera, r_w_c, p_w_c, 8);
  FrameLocatorOptions o;
  o.search_radius_m = 1000.0;
  const Eigen::Vector3d prior(150.0, 800.0, 5.0);  // 630 m off
  const FrameLocation loc = LocateFrame(horizon, camera, samples, level, prior, o);
  ASSERT_TRUE(loc.ok) << loc.reason;
  EXPECT_LT((loc.p_w_c - p_w_c).head<2>().norm(), 1.0) << loc.p_w_c.transpose();
  EXPECT_LT(Eigen::Quaterniond(r_w_c).angularDistance(loc.q_w_c), 0.02 * kDeg);
  EXPECT_LT(loc.rms_px, 0.2);
  EXPECT_LT(loc.ambiguity, 0.5);
  EXPECT_TRUE(loc.covariance.allFinite());
  std::printf("located in %.2f s, %d candidates, ambiguity %.3g, sigma %.2f m\n", loc.seconds,
              loc.candidates_refined, loc.ambiguity, std::sqrt(loc.covariance(3, 3)));
}

TEST(FrameLocator, TooFewSamplesIsAReasonNotACrash) {
  const auto horizon = std::make_shared<HorizonPredictor>(testing::MountainRing(201, 100.0));
  const CameraModel camera(PinholeFromFov("camera", 1920, 1080, 70.0));
  const FrameLocation loc = LocateFrame(horizon, camera, {{Eigen::Vector2d(5, 5), 1.0}},
                                        Level(0, 0), Eigen::Vector3d(0, 0, 5), {});
  EXPECT_FALSE(loc.ok);
  EXPECT_FALSE(loc.reason.empty());
}

}  // namespace
}  // namespace skerry::skyline
