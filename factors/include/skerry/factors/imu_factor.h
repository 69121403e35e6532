#pragma once
/// \file
/// Preintegrated IMU factor between two consecutive keyframes.
///
///   r = sqrt_info * [ Log( dR(bg)^T R_w_i(i)^T R_w_i(j) )                          ]
///                   [ R_w_i(i)^T (v_j - v_i - g dt) - dv(bg, ba)                      ]
///                   [ R_w_i(i)^T (p_j - p_i - v_i dt - 1/2 g dt^2) - dp(bg, ba)       ]
/// Forster et al. T-RO 2017 eq. (45), with the bias corrections of eq. (44). The states are body
/// states; R_w_i, p_i, v_i are those of the IMU frame/point (BodyToImu, lever arm and extrinsic
/// rotation applied). sqrt_info = L^-1 for the preintegration covariance cov = L L^T (lower
/// triangular, so sqrt_info^T sqrt_info = cov^-1), computed once at construction.
///
/// Parameter blocks: q_w_b(i)[4], p_w_b(i)[3], v_w(i)[3], bg(i)[3], ba(i)[3], q_w_b(j)[4],
/// p_w_b(j)[3], v_w(j)[3]. Biases are held constant over the interval (the bias random-walk
/// factor links bg/ba of i and j).

#include <ceres/autodiff_cost_function.h>

#include <memory>

#include "skerry/core/constant_product.h"
#include "skerry/core/so3.h"
#include "skerry/factors/imu_preintegration.h"

namespace skerry {

class ImuFactor {
 public:
  static constexpr int kResiduals = 9;

  ImuFactor(std::shared_ptr<const ImuPreintegration> pim,
            const ImuConfig& imu,
            const Eigen::Vector3d& gyro_start_rad_s,
            const Eigen::Vector3d& gyro_end_rad_s);

  template <typename T>
  bool operator()(const T* q_i_ptr,
                  const T* p_i_ptr,
                  const T* v_i_ptr,
                  const T* bg_i_ptr,
                  const T* ba_i_ptr,
                  const T* q_j_ptr,
                  const T* p_j_ptr,
                  const T* v_j_ptr,
                  T* residual_ptr) const {
    using Vec3 = Eigen::Matrix<T, 3, 1>;
    const Eigen::Map<const Eigen::Quaternion<T>> q_i(q_i_ptr);
    const Eigen::Map<const Vec3> p_i(p_i_ptr), v_i(v_i_ptr), bg(bg_i_ptr), ba(ba_i_ptr);
    const Eigen::Map<const Eigen::Quaternion<T>> q_j(q_j_ptr);
    const Eigen::Map<const Vec3> p_j(p_j_ptr), v_j(v_j_ptr);

    const ImuKinematics<T> ki = BodyToImu<T>(q_i, p_i, v_i, bg, gyro_start_rad_s_, imu_);
    const ImuKinematics<T> kj = BodyToImu<T>(q_j, p_j, v_j, bg, gyro_end_rad_s_, imu_);
    Eigen::Quaternion<T> dq;
    Vec3 dv, dp;
    pim_->CorrectedDeltas<T>(bg, ba, &dq, &dv, &dp);

    const T dt = T(pim_->dt_s());
    const Vec3 g_w(T(0), T(0), T(-imu_.gravity_m_s2));
    const Eigen::Quaternion<T> q_i_w = ki.q_w_i.conjugate();
    Eigen::Matrix<T, 9, 1> r;
    r.template segment<3>(0) = LogQ<T>(dq.conjugate() * (q_i_w * kj.q_w_i));
    r.template segment<3>(3) = q_i_w * (kj.v_w_i - ki.v_w_i - g_w * dt) - dv;
    r.template segment<3>(6) =
        q_i_w * (kj.p_w_i - ki.p_w_i - ki.v_w_i * dt - T(0.5) * g_w * dt * dt) - dp;
    Eigen::Map<Eigen::Matrix<T, 9, 1>> residual(residual_ptr);
    residual = ConstantTimes<T>(sqrt_info_, r, /*lower_triangular=*/true);
    return true;
  }

  /// The caller owns the returned cost function.
  static std::unique_ptr<ceres::CostFunction> Create(std::shared_ptr<const ImuPreintegration> pim,
                                                     const ImuConfig& imu,
                                                     const Eigen::Vector3d& gyro_start_rad_s,
                                                     const Eigen::Vector3d& gyro_end_rad_s);

  const Eigen::Matrix<double, 9, 9>& sqrt_info() const { return sqrt_info_; }

 private:
  std::shared_ptr<const ImuPreintegration> pim_;
  ImuConfig imu_;
  Eigen::Vector3d gyro_start_rad_s_, gyro_end_rad_s_;
  Eigen::Matrix<double, 9, 9> sqrt_info_;
};

}  // namespace skerry
