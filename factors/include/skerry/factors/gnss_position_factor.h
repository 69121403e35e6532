#pragma once
/// \file
/// GNSS antenna position factor with lever arm (cf. GTSAM GPSFactorArm):
///   r = sqrt_info * ( p_w_b + v_w dt + R_w_b l_b + b_w - z_w )
/// where l_b is the antenna position in the body, z_w the fix in local ENU, b_w the slowly varying
/// GNSS position bias (drift, m, ENU; see gnss_drift_factor.h; a constant-zero block when the
/// drift is not modelled) and dt = t_fix - t_keyframe (|dt| is at most half a keyframe period;
/// the constant-velocity term moves the keyframe to the fix time, and the caller turns the lever
/// arm by the body's rotation over dt, l_b = Exp(omega_b dt) l).
///
/// The receiver's sigmas are along the local east, north and up at the fix (frame n,
/// EarthModel::LocalLevel), which turn away from w's axes with distance from the origin (3 mrad
/// at 20 km): sqrt_info = diag(1/sigma_e, 1/sigma_n, 1/sigma_u) R_n_w, whitened once.
/// Parameter blocks: q_w_b[4], p_w_b[3], v_w[3], b_w[3]. Tangent Jacobians (left rotation
/// perturbation): J_theta = -sqrt_info [R l]x, J_p = sqrt_info, J_v = dt sqrt_info, J_b =
/// sqrt_info.

#include <ceres/autodiff_cost_function.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>

#include "skerry/core/constant_product.h"

namespace skerry {

class GnssPositionFactor {
 public:
  GnssPositionFactor(const Eigen::Vector3d& z_w,
                     const Eigen::Vector3d& sigma_enu_m,
                     const Eigen::Vector3d& lever_arm_b,
                     double dt_s,
                     const Eigen::Matrix3d& R_n_w = Eigen::Matrix3d::Identity());

  template <typename T>
  bool operator()(
      const T* q_ptr, const T* p_ptr, const T* v_ptr, const T* b_ptr, T* residual_ptr) const {
    using Vec3 = Eigen::Matrix<T, 3, 1>;
    const Eigen::Map<const Eigen::Quaternion<T>> q(q_ptr);
    const Eigen::Map<const Vec3> p(p_ptr), v(v_ptr), b(b_ptr);
    Eigen::Map<Vec3> r(residual_ptr);
    r = ConstantTimes<T>(sqrt_info_,
                         Vec3(p + v * T(dt_s_) + q * lever_arm_b_.cast<T>() + b - z_w_.cast<T>()));
    return true;
  }

  static std::unique_ptr<ceres::CostFunction> Create(
      const Eigen::Vector3d& z_w,
      const Eigen::Vector3d& sigma_enu_m,
      const Eigen::Vector3d& lever_arm_b,
      double dt_s,
      const Eigen::Matrix3d& R_n_w = Eigen::Matrix3d::Identity());

 private:
  Eigen::Vector3d z_w_;
  Eigen::Matrix3d sqrt_info_;
  Eigen::Vector3d lever_arm_b_;
  double dt_s_;
};

}  // namespace skerry
