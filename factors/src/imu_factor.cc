#include "skerry/factors/imu_factor.h"

#include <Eigen/Cholesky>

namespace skerry {

ImuFactor::ImuFactor(std::shared_ptr<const ImuPreintegration> pim,
                     const ImuConfig& imu,
                     const Eigen::Vector3d& gyro_start_rad_s,
                     const Eigen::Vector3d& gyro_end_rad_s,
                     const ImuEarthTerms& earth)
    : pim_(std::move(pim)),
      imu_(imu),
      gyro_start_rad_s_(gyro_start_rad_s),
      gyro_end_rad_s_(gyro_end_rad_s),
      earth_(earth),
      W_hat_(Hat(earth.omega_ie_w)),
      earth_turn_(ExpQ(Eigen::Vector3d(earth.omega_ie_w * pim_->dt_s()))) {
  // Whiten once: sqrt_info^T sqrt_info = cov^-1, sqrt_info = L^-1 for cov = L L^T. A tiny
  // diagonal floor keeps very short intervals well conditioned.
  Eigen::Matrix<double, 9, 9> cov = pim_->covariance();
  cov.diagonal().array() += 1e-14;
  const Eigen::LLT<Eigen::Matrix<double, 9, 9>> llt(cov);
  sqrt_info_ = llt.matrixL().solve(Eigen::Matrix<double, 9, 9>::Identity());
}

std::unique_ptr<ceres::CostFunction> ImuFactor::Create(std::shared_ptr<const ImuPreintegration> pim,
                                                       const ImuConfig& imu,
                                                       const Eigen::Vector3d& gyro_start_rad_s,
                                                       const Eigen::Vector3d& gyro_end_rad_s,
                                                       const ImuEarthTerms& earth) {
  return std::make_unique<ceres::AutoDiffCostFunction<ImuFactor, 9, 4, 3, 3, 3, 3, 4, 3, 3>>(
      new ImuFactor(std::move(pim), imu, gyro_start_rad_s, gyro_end_rad_s, earth));
}

}  // namespace skerry
