#include "skerry/factors/bias_random_walk_factor.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

namespace skerry {

BiasRandomWalkFactor::BiasRandomWalkFactor(const ImuNoise& noise, double dt_s) {
  const double dt = std::max(dt_s, 1e-6);
  sqrt_info_g_ = 1.0 / (noise.gyro_bias_random_walk_rad_s2_sqrt_hz * std::sqrt(dt));
  sqrt_info_a_ = 1.0 / (noise.accel_bias_random_walk_m_s3_sqrt_hz * std::sqrt(dt));
}

bool BiasRandomWalkFactor::Evaluate(double const* const* parameters,
                                    double* residuals,
                                    double** jacobians) const {
  using Vec3 = Eigen::Map<const Eigen::Vector3d>;
  Eigen::Map<Eigen::Matrix<double, 6, 1>> r(residuals);
  r.head<3>() = sqrt_info_g_ * (Vec3(parameters[2]) - Vec3(parameters[0]));
  r.tail<3>() = sqrt_info_a_ * (Vec3(parameters[3]) - Vec3(parameters[1]));
  if (jacobians == nullptr) return true;
  using Jac = Eigen::Map<Eigen::Matrix<double, 6, 3, Eigen::RowMajor>>;
  const double sign[4] = {-1.0, -1.0, 1.0, 1.0};
  for (int k = 0; k < 4; ++k) {
    if (jacobians[k] == nullptr) continue;
    Jac J(jacobians[k]);
    J.setZero();
    if (k % 2 == 0) {
      J.topRows<3>().diagonal().setConstant(sign[k] * sqrt_info_g_);
    } else {
      J.bottomRows<3>().diagonal().setConstant(sign[k] * sqrt_info_a_);
    }
  }
  return true;
}

}  // namespace skerry
