#pragma once
/// \file
/// A horizontal pose in the local ENU frame `w`: where a levelled sensor frame `l` (the sensor's
/// frame with its roll and pitch removed, scan_preparation.h) sits and which way it faces.
/// p_w = R(yaw) p_l + t for the horizontal components; yaw is counter-clockwise about up from
/// east (people see the heading, clockwise from north: HeadingDeg).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

#include "skerry/core/heading.h"

namespace skerry::lidar_aerial {

struct PlanarPose {
  Eigen::Vector2d t = Eigen::Vector2d::Zero();
  double yaw = 0.0;  ///< rad

  Eigen::Matrix2d R() const {
    const double c = std::cos(yaw), s = std::sin(yaw);
    return (Eigen::Matrix2d() << c, -s, s, c).finished();
  }
  Eigen::Vector2d Apply(const Eigen::Vector2d& p_l) const { return R() * p_l + t; }
};

/// Yaw wrapped to (-pi, pi].
inline double WrapAngle(double a) {
  a = std::remainder(a, 2.0 * M_PI);
  return a <= -M_PI ? a + 2.0 * M_PI : a;
}

/// The yaw of a body attitude: its x axis counter-clockwise from east, pi/2 minus its heading.
inline double YawOf(const Eigen::Quaterniond& q_w_b) {
  return WrapAngle(M_PI / 2.0 - HeadingRad(q_w_b));
}

}  // namespace skerry::lidar_aerial
