#include "skerry/lidar_aerial/lidar_start.h"

#include <spdlog/spdlog.h>

#include "skerry/frontends/sensor_start.h"

namespace skerry::lidar_aerial {

std::optional<EstimateRecord> LidarStartState(
    const LidarAerialFrontend& frontend,
    const std::vector<ImuSample>& imu,
    const ImuConfig& imu_config,
    const std::function<Eigen::Vector3d(TimeNs)>& prior_p_w_b,
    const LidarStartOptions& options) {
  int tried = 0;
  for (TimeNs t : frontend.BlockTimes()) {
    if (tried++ >= options.max_scans) break;
    if (!imu.empty() && t < imu.front().t_ns) continue;  // before the IMU starts
    const Eigen::Vector3d up_b = BodyUpAt(imu, imu_config, t);
    if (up_b.isZero()) continue;
    const std::optional<Relocation> r =
        frontend.Locate(t, up_b, prior_p_w_b(t), options.search_radius_m);
    if (!r) continue;
    spdlog::info("t={:.3f}: started from the LiDAR scan {} on the aerial photo ({})",
                 NsToSeconds(t), tried, r->reason);
    return StartFromRelocation(t, *r, imu_config, options.velocity_sigma_m_s);
  }
  return std::nullopt;
}

}  // namespace skerry::lidar_aerial
