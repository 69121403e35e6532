#include "skerry/skyline/camera_model.h"

#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>
#include <random>

namespace skerry::skyline {
namespace {

CameraConfig Distorted(int n) {
  CameraConfig c = PinholeFromFov("camera", 1920, 1080, 70.0);
  c.cx += 7.3;
  c.cy -= 4.1;
  c.fy = c.fx * 1.002;
  const std::vector<double> all = {-0.12, 0.05, 0.0011, -0.0007, -0.01, 0.02, -0.004, 0.001};
  c.distortion.assign(all.begin(), all.begin() + n);
  return c;
}

// OpenCV's own projection is the independent reference for every coefficient count.
TEST(CameraModel, ProjectMatchesOpenCv) {
  for (int n : {0, 4, 5, 8}) {
    const CameraConfig c = Distorted(n);
    const CameraModel camera(c);
    const cv::Matx33d k(c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1);
    std::mt19937 rng(n);
    std::uniform_real_distribution<double> u(-0.6, 0.6);
    for (int i = 0; i < 200; ++i) {
      const Eigen::Vector3d p(u(rng), 0.8 * u(rng), 1.0 + std::abs(u(rng)));
      std::vector<cv::Point3d> in{{p.x(), p.y(), p.z()}};
      std::vector<cv::Point2d> out;
      cv::projectPoints(in, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), k, c.distortion, out);
      const auto px = camera.Project(p);
      ASSERT_TRUE(px);
      EXPECT_NEAR(px->x(), out[0].x, 1e-9) << n;
      EXPECT_NEAR(px->y(), out[0].y, 1e-9) << n;
    }
    EXPECT_FALSE(camera.Project({0.1, 0.1, -1.0}));
  }
}

TEST(CameraModel, RayInvertsProjectAndJacobianMatchesNumeric) {
  const CameraModel camera(Distorted(8));
  for (double u = 0; u < 1920; u += 97.3) {
    for (double v = 0; v < 1080; v += 71.9) {
      const auto ray = camera.Ray({u, v});
      ASSERT_TRUE(ray);
      EXPECT_NEAR(ray->norm(), 1.0, 1e-12);
      const auto px = camera.Project(*ray);
      ASSERT_TRUE(px);
      EXPECT_NEAR(px->x(), u, 1e-7);
      EXPECT_NEAR(px->y(), v, 1e-7);
      const Eigen::Vector2d xy = ray->head<2>() / ray->z();
      Eigen::Matrix2d j;
      camera.Distort(xy, &j);
      for (int k = 0; k < 2; ++k) {
        const double h = 1e-6;
        const Eigen::Vector2d d = Eigen::Vector2d::Unit(k) * h;
        const Eigen::Vector2d num = (camera.Distort(xy + d) - camera.Distort(xy - d)) / (2 * h);
        EXPECT_NEAR((j.col(k) - num).norm(), 0.0, 1e-5);
      }
    }
  }
}

TEST(CameraModel, FieldOfViewAndLevelRotation) {
  const CameraModel camera(PinholeFromFov("camera", 1920, 1080, 70.0));
  EXPECT_NEAR(camera.HorizontalFov() * 180.0 / M_PI, 70.0, 1e-9);
  // A level forward camera sees the bow along its optical axis and port to its left (u < cx).
  const Eigen::Matrix3d r_b_c = LevelCameraRotation(0.0).toRotationMatrix();
  EXPECT_TRUE((r_b_c * Eigen::Vector3d::UnitZ()).isApprox(Eigen::Vector3d::UnitX()));
  EXPECT_TRUE((r_b_c * Eigen::Vector3d::UnitY()).isApprox(-Eigen::Vector3d::UnitZ()));
  const Eigen::Vector3d port_c = r_b_c.transpose() * Eigen::Vector3d(10, 3, 0);
  EXPECT_LT(camera.Project(port_c)->x(), camera.cx());
  const Eigen::Matrix3d r_port = LevelCameraRotation(90.0).toRotationMatrix();
  EXPECT_TRUE((r_port * Eigen::Vector3d::UnitZ()).isApprox(Eigen::Vector3d::UnitY()));
}

TEST(CameraModel, RejectsBadConfigurations) {
  CameraConfig c = PinholeFromFov("cam_x", 1920, 1080, 70.0);
  c.distortion = {0.1, 0.2, 0.3};
  EXPECT_THROW(CameraModel{c}, std::invalid_argument);
  c = PinholeFromFov("cam_x", 0, 1080, 70.0);
  EXPECT_THROW(CameraModel{c}, std::invalid_argument);
  c = PinholeFromFov("cam_x", 1920, 1080, 70.0);
  c.fx = std::nan("");
  EXPECT_THROW(CameraModel{c}, std::invalid_argument);
  c = PinholeFromFov("cam_x", 1920, 1080, 70.0);
  c.cx = 5000;
  EXPECT_THROW(CameraModel{c}, std::invalid_argument);
}

}  // namespace
}  // namespace skerry::skyline
