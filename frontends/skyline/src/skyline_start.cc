#include "skerry/skyline/skyline_start.h"

#include <spdlog/spdlog.h>

#include "skerry/frontends/sensor_start.h"

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
    const Eigen::Vector3d up_b = BodyUpAt(imu, imu_config, t);
    if (up_b.isZero()) continue;
    const std::optional<Relocation> r =
        frontend.Locate(t, up_b, prior_p_w_b, options.search_radius_m);
    if (!r) continue;
    spdlog::info("t={:.3f}: started from the skyline of frame {} ({})", NsToSeconds(t), tried,
                 r->reason);
    return StartFromRelocation(t, *r, imu_config, options.velocity_sigma_m_s);
  }
  return std::nullopt;
}

}  // namespace skerry::skyline
