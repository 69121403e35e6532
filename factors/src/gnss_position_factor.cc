#include "skerry/factors/gnss_position_factor.h"

namespace skerry {

GnssPositionFactor::GnssPositionFactor(const Eigen::Vector3d& z_w,
                                       const Eigen::Vector3d& sigma_enu_m,
                                       const Eigen::Vector3d& lever_arm_b,
                                       double dt_s)
    : z_w_(z_w), sqrt_info_(sigma_enu_m.cwiseInverse()), lever_arm_b_(lever_arm_b), dt_s_(dt_s) {}

Eigen::Vector3d GnssPositionFactor::Predict(const Eigen::Quaterniond& q_w_b,
                                            const Eigen::Vector3d& p_w_b,
                                            const Eigen::Vector3d& v_w) const {
  return p_w_b + v_w * dt_s_ + q_w_b * lever_arm_b_;
}

std::unique_ptr<ceres::CostFunction> GnssPositionFactor::Create(const Eigen::Vector3d& z_w,
                                                                const Eigen::Vector3d& sigma_enu_m,
                                                                const Eigen::Vector3d& lever_arm_b,
                                                                double dt_s) {
  return std::make_unique<ceres::AutoDiffCostFunction<GnssPositionFactor, 3, 4, 3, 3, 3>>(
      new GnssPositionFactor(z_w, sigma_enu_m, lever_arm_b, dt_s));
}

}  // namespace skerry
