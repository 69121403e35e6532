#pragma once
/// \file
/// A pinhole camera with OpenCV's distortion model, in the optical frame c: x right, y down,
/// z forward (OpenCV's). A dataset's T_b_c maps points from c to the body (FLU).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <optional>
#include <vector>

#include "skerry/core/sensor_config.h"

namespace skerry::skyline {

class CameraModel {
 public:
  /// Throws std::invalid_argument (naming the camera) for a size or focal length <= 0, a
  /// principal point outside the image, or a distortion vector not of 0, 4, 5 or 8 values.
  explicit CameraModel(const CameraConfig& config);

  /// Pixel (u right, v down; pixel centres at integers) of a point in the optical frame, with
  /// distortion (OpenCV's model: Brown-Conrady radial k1..k3 with the rational k4..k6 and
  /// tangential p1, p2; cv::projectPoints' equations). nullopt behind the camera (z <= 0).
  std::optional<Eigen::Vector2d> Project(const Eigen::Vector3d& p_c) const;
  /// The undistorted normalised coordinates (x/z, y/z) of a pixel: the distortion inverted by
  /// Newton's method on the model's own Jacobian (converges to 1e-12 where the model is
  /// invertible). nullopt where it does not converge (far outside the calibrated field).
  std::optional<Eigen::Vector2d> Undistort(const Eigen::Vector2d& px) const;
  /// Unit ray in the optical frame through a pixel; nullopt as Undistort.
  std::optional<Eigen::Vector3d> Ray(const Eigen::Vector2d& px) const;

  /// Distorted pixel of normalised coordinates, and its 2x2 Jacobian d(pixel)/d(x, y).
  Eigen::Vector2d Distort(const Eigen::Vector2d& xy, Eigen::Matrix2d* jacobian = nullptr) const;

  int width() const { return width_; }
  int height() const { return height_; }
  double fx() const { return fx_; }
  double fy() const { return fy_; }
  double cx() const { return cx_; }
  double cy() const { return cy_; }
  const std::array<double, 8>& distortion() const { return k_; }
  bool InImage(const Eigen::Vector2d& px) const;
  /// Horizontal field of view (rad) through the principal point, distortion included.
  double HorizontalFov() const;
  /// The configuration it was made from.
  const CameraConfig& config() const { return config_; }

 private:
  CameraConfig config_;
  int width_ = 0, height_ = 0;
  double fx_ = 0, fy_ = 0, cx_ = 0, cy_ = 0;
  /// k1, k2, p1, p2, k3, k4, k5, k6 (zeros where not given).
  std::array<double, 8> k_{};
};

/// R_b_c of a camera looking horizontally along the body direction `yaw_left_deg` from the bow
/// (0: forward, 90: port, 180: aft, -90: starboard), image rows level: optical z along that
/// direction, optical x to its right, optical y down.
Eigen::Quaterniond LevelCameraRotation(double yaw_left_deg);

/// A camera configuration from a horizontal field of view (deg) for a sensor of width x height
/// pixels, principal point at the centre, square pixels, no distortion.
CameraConfig PinholeFromFov(const std::string& name,
                            int width_px,
                            int height_px,
                            double horizontal_fov_deg);

}  // namespace skerry::skyline
