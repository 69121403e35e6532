#pragma once
/// \file
/// Dual-antenna GNSS heading factor. The receiver measures the heading (clockwise from the local
/// north at the vessel) of the antenna baseline. With u_n = R_n_w R_w_b b_b the baseline in the
/// local-level ENU frame n at the fix (EarthModel::LocalLevel; w's own north differs from it by
/// the meridian convergence, 0.19 deg 20 km east of the origin at 47 deg N):
///   r = wrap( atan2(u_n.e, u_n.n) - z ) / sigma
/// Only the horizontal projection of the baseline matters.
///
/// The keyframe the fix is tied to is up to half a keyframe period away from the fix time; the
/// caller turns the baseline by the body's rotation over that offset, b_b = Exp(omega_b dt) b,
/// as the position factor moves the antenna by v dt (a 3 deg/s turn and 50 ms give 0.15 deg,
/// close to a receiver's 0.2 deg sigma). Parameter block: q_w_b[4].

#include <ceres/autodiff_cost_function.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>

#include "skerry/core/constant_product.h"
#include "skerry/core/so3.h"

namespace skerry {

class GnssHeadingFactor {
 public:
  /// `baseline_b`: baseline direction in the keyframe's body frame at the fix time; `R_n_w`:
  /// local level at the fix from w.
  GnssHeadingFactor(double heading_rad,
                    double sigma_rad,
                    const Eigen::Vector3d& baseline_b,
                    const Eigen::Matrix3d& R_n_w);

  template <typename T>
  bool operator()(const T* q_ptr, T* residual) const {
    using std::atan2;
    const Eigen::Map<const Eigen::Quaternion<T>> q(q_ptr);
    const Eigen::Matrix<T, 3, 1> u_n =
        ConstantTimes<T>(R_n_w_, Eigen::Matrix<T, 3, 1>(q * baseline_b_.cast<T>()));
    const T heading = atan2(u_n.x(), u_n.y());
    residual[0] = WrapAngle<T>(heading - T(heading_rad_)) * T(sqrt_info_);
    return true;
  }

  static std::unique_ptr<ceres::CostFunction> Create(double heading_rad,
                                                     double sigma_rad,
                                                     const Eigen::Vector3d& baseline_b,
                                                     const Eigen::Matrix3d& R_n_w);

 private:
  double heading_rad_;
  double sqrt_info_;
  Eigen::Vector3d baseline_b_;
  Eigen::Matrix3d R_n_w_;
};

}  // namespace skerry
