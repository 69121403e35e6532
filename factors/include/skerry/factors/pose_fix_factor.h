#pragma once
/// \file
/// Pose-fix factor: a measured position (horizontal or 3-D) of a sensor frame s on the vessel and,
/// optionally, the heading of its x axis, with a full covariance (PoseFix). With the keyframe's
/// q_w_b, p_w_b and the sensor's extrinsic q_b_s, p_b_s (constant, or calibrated):
///   p_w_s = p_w_b + R_w_b p_b_s                          (the measured point, lever arm p_b_s)
///   u_n   = R_n_w R_w_b R_b_s e_x                        (s's x axis in the local level at the
///   fix) e     = [ (p_w_s - z_p)_{e,n[,u]} ; wrap(atan2(u_n.e, u_n.n) - z_psi) ] r     = L^-1 e,
///   L L^T = the measured components' covariance (Cholesky, whitened once here)
/// The position error and the heading are taken in the local level at the fix, as GNSS fixes are
/// (gnss_position_factor.h, gnss_heading_factor.h; R_n_w = EarthModel::LocalLevel(z_p)^T): the
/// covariance's east, north and up are the local ones there, and a horizontal fix 20 km from the
/// origin must not take in 3 mrad of the vertical error (the w axes' tilt there). The position
/// residual is GTSAM's GPSFactorArm p + R l - z, rotated and restricted to the measured axes. Only
/// the horizontal projection of e_x matters. Parameter blocks: q_w_b[4], p_w_b[3], q_b_s[4],
/// p_b_s[3].

#include <ceres/autodiff_cost_function.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <vector>

#include "skerry/core/constant_product.h"
#include "skerry/core/measurements.h"
#include "skerry/core/so3.h"

namespace skerry {

class PoseFixFactor {
 public:
  /// `fix`: with p_w and heading in radians through fix.heading_deg; `R_n_w`: the local level at
  /// the fix from w. Throws std::invalid_argument when the measured covariance is not positive
  /// definite or not finite.
  PoseFixFactor(const PoseFix& fix, const Eigen::Matrix3d& R_n_w);

  template <typename T>
  bool operator()(const T* q_w_b_ptr,
                  const T* p_w_b_ptr,
                  const T* q_b_s_ptr,
                  const T* p_b_s_ptr,
                  T* residual) const {
    using std::atan2;
    using Vec3 = Eigen::Matrix<T, 3, 1>;
    const Eigen::Map<const Eigen::Quaternion<T>> q_w_b(q_w_b_ptr), q_b_s(q_b_s_ptr);
    const Eigen::Map<const Vec3> p_w_b(p_w_b_ptr), p_b_s(p_b_s_ptr);
    const Vec3 p_w_s = p_w_b + q_w_b * p_b_s;
    // The position error along the local east, north, up at the fix, the covariance's axes.
    const Vec3 e_n = ConstantTimes<T>(R_n_w_, Vec3(p_w_s - z_.head<3>().cast<T>()));
    T e[4];
    int k = 0;
    for (int c : components_) {
      if (c < 3) {
        e[k++] = e_n[c];
      } else {
        const Vec3 x_w = q_w_b * (q_b_s * Vec3(T(1), T(0), T(0)));
        const Vec3 u_n = ConstantTimes<T>(R_n_w_, x_w);
        e[k++] = WrapAngle<T>(atan2(u_n.x(), u_n.y()) - T(z_[3]));
      }
    }
    for (int i = 0; i < k; ++i) {
      residual[i] = T(0);
      for (int j = 0; j <= i; ++j) residual[i] += T(sqrt_info_(i, j)) * e[j];
    }
    return true;
  }

  int num_residuals() const { return static_cast<int>(components_.size()); }

  static std::unique_ptr<ceres::CostFunction> Create(const PoseFix& fix,
                                                     const Eigen::Matrix3d& R_n_w);

 private:
  std::vector<int> components_;  ///< measured indices into (e, n, u, heading)
  Eigen::Vector4d z_;            ///< e, n, u (m), heading (rad)
  Eigen::Matrix4d sqrt_info_;    ///< L^-1 (lower triangular) in the top-left block
  Eigen::Matrix3d R_n_w_;
};

}  // namespace skerry
