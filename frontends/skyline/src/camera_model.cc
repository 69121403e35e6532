#include "skerry/skyline/camera_model.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace skerry::skyline {

CameraModel::CameraModel(const CameraConfig& config) : config_(config) {
  const std::string who = "camera '" + config.name + "': ";
  if (config.width_px <= 0 || config.height_px <= 0) {
    throw std::invalid_argument(who + "width_px and height_px must be > 0");
  }
  if (!(config.fx > 0) || !(config.fy > 0) || !std::isfinite(config.fx) ||
      !std::isfinite(config.fy)) {
    throw std::invalid_argument(who + "fx and fy must be finite and > 0");
  }
  if (!(config.cx >= 0 && config.cx <= config.width_px) ||
      !(config.cy >= 0 && config.cy <= config.height_px)) {
    throw std::invalid_argument(who + "principal point (cx, cy) outside the image");
  }
  const size_t n = config.distortion.size();
  if (n != 0 && n != 4 && n != 5 && n != 8) {
    throw std::invalid_argument(who + "distortion must have 0, 4, 5 or 8 coefficients, has " +
                                std::to_string(n));
  }
  for (size_t i = 0; i < n; ++i) {
    if (!std::isfinite(config.distortion[i])) {
      throw std::invalid_argument(who + "distortion[" + std::to_string(i) + "] is not finite");
    }
    k_[i] = config.distortion[i];
  }
  width_ = config.width_px;
  height_ = config.height_px;
  fx_ = config.fx;
  fy_ = config.fy;
  cx_ = config.cx;
  cy_ = config.cy;
}

// OpenCV's camera model (docs of cv::projectPoints / calib3d):
//   r2 = x^2 + y^2, radial = (1 + k1 r2 + k2 r4 + k3 r6) / (1 + k4 r2 + k5 r4 + k6 r6)
//   x' = x radial + 2 p1 x y + p2 (r2 + 2 x^2),  y' = y radial + p1 (r2 + 2 y^2) + 2 p2 x y
//   u = fx x' + cx,  v = fy y' + cy
Eigen::Vector2d CameraModel::Distort(const Eigen::Vector2d& xy, Eigen::Matrix2d* jacobian) const {
  const double x = xy.x(), y = xy.y();
  const double k1 = k_[0], k2 = k_[1], p1 = k_[2], p2 = k_[3], k3 = k_[4], k4 = k_[5], k5 = k_[6],
               k6 = k_[7];
  const double r2 = x * x + y * y, r4 = r2 * r2, r6 = r4 * r2;
  const double num = 1 + k1 * r2 + k2 * r4 + k3 * r6;
  const double den = 1 + k4 * r2 + k5 * r4 + k6 * r6;
  const double radial = num / den;
  const double xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x);
  const double yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y;
  if (jacobian) {
    const double dnum = k1 + 2 * k2 * r2 + 3 * k3 * r4;  // d num / d r2
    const double dden = k4 + 2 * k5 * r2 + 3 * k6 * r4;
    const double dradial = (dnum * den - num * dden) / (den * den);  // d radial / d r2
    const double drx = dradial * 2 * x, dry = dradial * 2 * y;
    Eigen::Matrix2d j;
    j(0, 0) = radial + x * drx + 2 * p1 * y + 6 * p2 * x;
    j(0, 1) = x * dry + 2 * p1 * x + 2 * p2 * y;
    j(1, 0) = y * drx + 2 * p1 * x + 2 * p2 * y;
    j(1, 1) = radial + y * dry + 6 * p1 * y + 2 * p2 * x;
    j.row(0) *= fx_;
    j.row(1) *= fy_;
    *jacobian = j;
  }
  return {fx_ * xd + cx_, fy_ * yd + cy_};
}

std::optional<Eigen::Vector2d> CameraModel::Project(const Eigen::Vector3d& p_c) const {
  if (!(p_c.z() > 0)) return std::nullopt;
  return Distort(p_c.head<2>() / p_c.z());
}

std::optional<Eigen::Vector2d> CameraModel::Undistort(const Eigen::Vector2d& px) const {
  Eigen::Vector2d xy((px.x() - cx_) / fx_, (px.y() - cy_) / fy_);
  for (int it = 0; it < 50; ++it) {
    Eigen::Matrix2d j;
    const Eigen::Vector2d e = Distort(xy, &j) - px;
    if (e.norm() < 1e-10) return xy;
    const Eigen::Vector2d step = j.partialPivLu().solve(e);
    if (!step.allFinite()) return std::nullopt;
    xy -= step;
  }
  if ((Distort(xy) - px).norm() < 1e-6) return xy;
  return std::nullopt;
}

std::optional<Eigen::Vector3d> CameraModel::Ray(const Eigen::Vector2d& px) const {
  const auto xy = Undistort(px);
  if (!xy) return std::nullopt;
  return Eigen::Vector3d(xy->x(), xy->y(), 1.0).normalized();
}

bool CameraModel::InImage(const Eigen::Vector2d& px) const {
  return px.x() >= -0.5 && px.y() >= -0.5 && px.x() <= width_ - 0.5 && px.y() <= height_ - 0.5;
}

double CameraModel::HorizontalFov() const {
  const auto left = Undistort({-0.5, cy_});
  const auto right = Undistort({width_ - 0.5, cy_});
  if (!left || !right) return 2.0 * std::atan2(0.5 * width_, fx_);
  return std::atan(right->x()) - std::atan(left->x());
}

Eigen::Quaterniond LevelCameraRotation(double yaw_left_deg) {
  // Forward camera: optical z = body x, optical x = -body y, optical y = -body z.
  Eigen::Matrix3d r_b_c;
  r_b_c << 0, 0, 1,  //
      -1, 0, 0,      //
      0, -1, 0;
  const Eigen::AngleAxisd yaw(yaw_left_deg * M_PI / 180.0, Eigen::Vector3d::UnitZ());
  return Eigen::Quaterniond(yaw.toRotationMatrix() * r_b_c).normalized();
}

CameraConfig PinholeFromFov(const std::string& name,
                            int width_px,
                            int height_px,
                            double horizontal_fov_deg) {
  CameraConfig c;
  c.name = name;
  c.width_px = width_px;
  c.height_px = height_px;
  c.fx = c.fy = 0.5 * width_px / std::tan(0.5 * horizontal_fov_deg * M_PI / 180.0);
  c.cx = 0.5 * width_px - 0.5;
  c.cy = 0.5 * height_px - 0.5;
  return c;
}

}  // namespace skerry::skyline
