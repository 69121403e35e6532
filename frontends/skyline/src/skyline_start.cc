#include "skerry/skyline/skyline_start.h"

#include <spdlog/spdlog.h>

#include <algorithm>

namespace skerry::skyline {

std::optional<EstimateRecord> SkylineStartState(const SkylineFrontend& frontend,
                                                const std::vector<ImuSample>& imu,
                                                const ImuConfig& imu_config,
                                                const Eigen::Vector3d& prior_p_w_b,
                                                const SkylineStartOptions& options) {
  const std::vector<TimeNs> times = frontend.FrameTimes();
  int tried = 0;
  for (TimeNs t : times) {
    if (tried++ >= options.max_frames) break;
    // The body's up: the mean specific force over the second around the frame (waves average
    // out to first order), IMU frame to body.
    Eigen::Vector3d f = Eigen::Vector3d::Zero();
    int n = 0;
    for (auto it = std::lower_bound(imu.begin(), imu.end(), t - SecondsToNs(0.5),
                                    [](const ImuSample&s, TimeNs v) { return s.t_ns < v; });
         it != imu.end() && it->t_ns <= t + SecondsToNs(0.5); ++it) {
      f += it->accel_m_s2;
      ++n;
    }
    if (n == 0) continue;
    const Eigen::Vector3d up_b = imu_config.q_b_i * (f / n);
    const std::optional<Relocation> r =
        frontend.Locate(t, up_b, prior_p_w_b, options.search_radius_m);
    if (!r) continue;
    EstimateRecord out;
    out.state.t_ns = t;
    out.state.q_w_b = r->q_w_b;
    out.state.p_w_b = r->p_w_b;
    out.has_covariance = true;
    out.covariance.setZero();
    out.covariance.topLeftCorner<6, 6>() = r->covariance;
    out.covariance.block<3, 3>(kVel, kVel)
        .diagonal()
        .setConstant(options.velocity_sigma_m_s * options.velocity_sigma_m_s);
    out.covariance.block<3, 3>(kBg, kBg).diagonal().setConstant(
        imu_config.gyro_bias_prior_sigma_rad_s * imu_config.gyro_bias_prior_sigma_rad_s);
    out.covariance.block<3, 3>(kBa, kBa).diagonal().setConstant(
        imu_config.accel_bias_prior_sigma_m_s2 * imu_config.accel_bias_prior_sigma_m_s2);
    spdlog::info("t={:.3f}: started from the skyline of frame {} ({})", NsToSeconds(t), tried,
                 r->reason);
    return out;
  }
  return std::nullopt;
}

}  // namespace skerry::skyline
