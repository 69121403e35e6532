#pragma once
/// \file
/// GNSS antenna position factor with lever arm (cf. GTSAM GPSFactorArm):
///   r = sqrt_info * ( p_w_b + v_w dt + R_w_b l_b + b_w - z_w )
/// where l_b is the antenna position in the body, z_w the fix in local ENU, b_w the slowly varying
/// GNSS position bias (drift, m, ENU; see gnss_drift_factor.h; a constant-zero block when the
/// drift is not modelled) and dt = t_fix -
/// t_keyframe (|dt| is at most half a keyframe period; the constant-velocity term moves the
/// keyframe to the fix time). sqrt_info = diag(1/sigma_e, 1/sigma_n, 1/sigma_u), whitened once.
/// Parameter blocks: q_w_b[4], p_w_b[3], v_w[3], b_w[3]. Tangent Jacobians (left rotation
/// perturbation): J_theta = -sqrt_info [R l]x, J_p = sqrt_info, J_v = dt sqrt_info, J_b =
/// sqrt_info.

#include <ceres/autodiff_cost_function.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>

namespace skerry {

class GnssPositionFactor {
 public:
  GnssPositionFactor(const Eigen::Vector3d& z_w,
                     const Eigen::Vector3d& sigma_enu_m,
                     const Eigen::Vector3d& lever_arm_b,
                     double dt_s);

  template <typename T>
  bool operator()(
      const T* q_ptr, const T* p_ptr, const T* v_ptr, const T* b_ptr, T* residual_ptr) const {
    using Vec3 = Eigen::Matrix<T, 3, 1>;
    const Eigen::Map<const Eigen::Quaternion<T>> q(q_ptr);
    const Eigen::Map<const Vec3> p(p_ptr), v(v_ptr), b(b_ptr);
    Eigen::Map<Vec3> r(residual_ptr);
    r = sqrt_info_.cast<T>().asDiagonal() *
        (p + v * T(dt_s_) + q * lever_arm_b_.cast<T>() + b - z_w_.cast<T>());
    return true;
  }

  /// Predicted antenna position (m, ENU) for a state, without the GNSS bias.
  Eigen::Vector3d Predict(const Eigen::Quaterniond& q_w_b,
                          const Eigen::Vector3d& p_w_b,
                          const Eigen::Vector3d& v_w) const;

  static std::unique_ptr<ceres::CostFunction> Create(const Eigen::Vector3d& z_w,
                                                     const Eigen::Vector3d& sigma_enu_m,
                                                     const Eigen::Vector3d& lever_arm_b,
                                                     double dt_s);

 private:
  Eigen::Vector3d z_w_;
  Eigen::Vector3d sqrt_info_;
  Eigen::Vector3d lever_arm_b_;
  double dt_s_;
};

}  // namespace skerry
