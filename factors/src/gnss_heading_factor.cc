#include "skerry/factors/gnss_heading_factor.h"

namespace skerry {

GnssHeadingFactor::GnssHeadingFactor(double heading_rad,
                                     double sigma_rad,
                                     const Eigen::Vector3d& baseline_b,
                                     const Eigen::Matrix3d& R_n_w)
    : heading_rad_(heading_rad),
      sqrt_info_(1.0 / sigma_rad),
      baseline_b_(baseline_b),
      R_n_w_(R_n_w) {}

std::unique_ptr<ceres::CostFunction> GnssHeadingFactor::Create(double heading_rad,
                                                               double sigma_rad,
                                                               const Eigen::Vector3d& baseline_b,
                                                               const Eigen::Matrix3d& R_n_w) {
  return std::make_unique<ceres::AutoDiffCostFunction<GnssHeadingFactor, 1, 4>>(
      new GnssHeadingFactor(heading_rad, sigma_rad, baseline_b, R_n_w));
}

}  // namespace skerry
