#include "skerry/factors/gnss_position_factor.h"

namespace skerry {

GnssPositionFactor::GnssPositionFactor(const Eigen::Vector3d& z_w,
                                       const Eigen::Vector3d& sigma_enu_m,
                                       const Eigen::Vector3d& lever_arm_b,
                                       double dt_s,
                                       const Eigen::Matrix3d& R_n_w)
    : z_w_(z_w),
      sqrt_info_(sigma_enu_m.cwiseInverse().asDiagonal() * R_n_w),
      lever_arm_b_(lever_arm_b),
      dt_s_(dt_s) {}

std::unique_ptr<ceres::CostFunction> GnssPositionFactor::Create(const Eigen::Vector3d& z_w,
                                                                const Eigen::Vector3d& sigma_enu_m,
                                                                const Eigen::Vector3d& lever_arm_b,
                                                                double dt_s,
                                                                const Eigen::Matrix3d& R_n_w) {
  return std::make_unique<ceres::AutoDiffCostFunction<GnssPositionFactor, 3, 4, 3, 3, 3>>(
      new GnssPositionFactor(z_w, sigma_enu_m, lever_arm_b, dt_s, R_n_w));
}

}  // namespace skerry
