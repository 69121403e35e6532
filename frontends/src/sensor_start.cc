#include "skerry/frontends/sensor_start.h"

#include <algorithm>

namespace skerry {

Eigen::Vector3d BodyUpAt(const std::vector<ImuSample>& imu,
                         const ImuConfig& imu_config,
                         TimeNs t_ns,
                         double half_window_s) {
  Eigen::Vector3d f = Eigen::Vector3d::Zero();
  int n = 0;
  const TimeNs half = SecondsToNs(half_window_s);
  for (auto it = std::lower_bound(imu.begin(), imu.end(), t_ns - half,
                                  [](const ImuSample&s, TimeNs v) { return s.t_ns < v; });
       it != imu.end() && it->t_ns <= t_ns + half; ++it) {
    f += it->accel_m_s2;
    ++n;
  }
  if (n == 0 || f.norm() == 0.0) return Eigen::Vector3d::Zero();
  return (imu_config.q_b_i * (f / n)).normalized();
}

EstimateRecord StartFromRelocation(TimeNs t_ns,
                                   const Relocation& found,
                                   const ImuConfig& imu_config,
                                   double velocity_sigma_m_s) {
  EstimateRecord out;
  out.state.t_ns = t_ns;
  out.state.q_w_b = found.q_w_b;
  out.state.p_w_b = found.p_w_b;
  out.has_covariance = true;
  out.covariance.setZero();
  out.covariance.topLeftCorner<6, 6>() = found.covariance;
  out.covariance.block<3, 3>(kVel, kVel)
      .diagonal()
      .setConstant(velocity_sigma_m_s * velocity_sigma_m_s);
  out.covariance.block<3, 3>(kBg, kBg).diagonal().setConstant(
      imu_config.gyro_bias_prior_sigma_rad_s * imu_config.gyro_bias_prior_sigma_rad_s);
  out.covariance.block<3, 3>(kBa, kBa).diagonal().setConstant(
      imu_config.accel_bias_prior_sigma_m_s2 * imu_config.accel_bias_prior_sigma_m_s2);
  return out;
}

}  // namespace skerry
