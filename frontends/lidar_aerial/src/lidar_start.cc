#include "skerry/lidar_aerial/lidar_start.h"

#include <spdlog/spdlog.h>

#include "skerry/core/chi_square.h"
#include "skerry/core/mahalanobis.h"
#include "skerry/frontends/sensor_start.h"

namespace skerry::lidar_aerial {

std::optional<EstimateRecord> LidarStartState(const LidarAerialFrontend& frontend,
                                              const std::vector<ImuSample>& imu,
                                              const ImuConfig& imu_config,
                                              const std::function<StartPrior(TimeNs)>& prior,
                                              const LidarStartOptions& options) {
  const double gate = ChiSquareQuantile(options.gate_probability, 2.0);
  int tried = 0;
  for (TimeNs t : frontend.BlockTimes()) {
    if (tried++ >= options.max_scans) break;
    if (!imu.empty() && t < imu.front().t_ns) continue;  // before the IMU starts
    const Eigen::Vector3d up_b = BodyUpAt(imu, imu_config, t);
    if (up_b.isZero()) continue;
    const StartPrior at = prior(t);
    const std::optional<Relocation> r = frontend.Locate(t, up_b, at.p_w_b, options.search_radius_m);
    if (!r) continue;
    if (at.horizontal_cov) {
      // The location against the prior: both covariances, chi-square in 2 dof.
      const Eigen::Vector2d d = r->p_w_b.head<2>() - at.p_w_b.head<2>();
      const std::optional<double> d2 =
          SquaredMahalanobis<2>(d, r->covariance.block<2, 2>(3, 3) + *at.horizontal_cov);
      if (!d2 || *d2 > gate) {
        spdlog::info(
            "t={:.3f}: the LiDAR scan {} located the vessel {:.1f} m from the receiver's fix "
            "(chi-square {:.1f} > {:.1f}): not taken as the start ({})",
            NsToSeconds(t), tried, d.norm(), d2.value_or(-1.0), gate, r->reason);
        continue;
      }
    }
    spdlog::info("t={:.3f}: started from the LiDAR scan {} on the aerial photo ({})",
                 NsToSeconds(t), tried, r->reason);
    return StartFromRelocation(t, *r, imu_config, options.velocity_sigma_m_s);
  }
  return std::nullopt;
}

}  // namespace skerry::lidar_aerial
