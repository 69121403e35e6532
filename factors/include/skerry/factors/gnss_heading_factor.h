#pragma once
/// \file
/// Dual-antenna GNSS heading factor. The receiver measures the heading (clockwise from north) of
/// the antenna baseline; with u_w = R_w_b b_b (b_b: baseline direction in the body):
///   r = wrap( atan2(u_e, u_n) - z ) / sigma
/// Only the horizontal projection of the baseline matters. Parameter block: q_w_b[4].

#include <ceres/autodiff_cost_function.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>

#include "skerry/core/so3.h"

namespace skerry {

class GnssHeadingFactor {
 public:
  GnssHeadingFactor(double heading_rad, double sigma_rad, const Eigen::Vector3d& baseline_b);

  template <typename T>
  bool operator()(const T* q_ptr, T* residual) const {
    using std::atan2;
    const Eigen::Map<const Eigen::Quaternion<T>> q(q_ptr);
    const Eigen::Matrix<T, 3, 1> u = q * baseline_b_.cast<T>();
    const T heading = atan2(u.x(), u.y());
    residual[0] = WrapAngle<T>(heading - T(heading_rad_)) * T(sqrt_info_);
    return true;
  }

  static std::unique_ptr<ceres::CostFunction> Create(double heading_rad,
                                                     double sigma_rad,
                                                     const Eigen::Vector3d& baseline_b);

 private:
  double heading_rad_;
  double sqrt_info_;
  Eigen::Vector3d baseline_b_;
};

}  // namespace skerry
