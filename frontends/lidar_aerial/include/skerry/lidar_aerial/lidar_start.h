#pragma once
/// \file
/// A first state from the LiDAR and the aerial photo (init.mode lidar): the first scans
/// registered on their own (coarse search with the heading all round, then the fine step) within
/// a radius of a prior position, roll and pitch from the accelerometer (sensor_start.h). What
/// starts a vessel at rest, where no course over ground gives a heading and a MEMS gyro cannot
/// find north, and a vessel whose receiver is drifting.

#include <Eigen/Core>
#include <functional>
#include <optional>
#include <vector>

#include "skerry/core/measurements.h"
#include "skerry/core/sensor_config.h"
#include "skerry/io/estimate_io.h"
#include "skerry/lidar_aerial/lidar_aerial_frontend.h"

namespace skerry::lidar_aerial {

/// Where a start is searched for at a time, and how well that is known.
struct StartPrior {
  Eigen::Vector3d p_w_b = Eigen::Vector3d::Zero();  ///< the search's centre
  /// The horizontal covariance of p_w_b as the vessel's position (a receiver's fix: its sigma,
  /// its drift's stationary sigma and its antenna's lever arm at a heading not yet known). A
  /// location farther from it than the gate allows is not taken (the receiver and the scan
  /// disagree: a second, nearly as good match of a repetitive harbour, which the ambiguity test
  /// let through). None (the harbour's origin): nothing to test against.
  std::optional<Eigen::Matrix2d> horizontal_cov;
};

struct LidarStartOptions {
  double search_radius_m = 30.0;  ///< around the prior (the coarse search caps it at 50 m)
  double velocity_sigma_m_s = 5.0;
  int max_scans = 10;               ///< scans tried, in order, before giving up
  double gate_probability = 0.999;  ///< chi-square (2 dof) of a location against the prior
};

/// The state at the first block (of those `frontend` made) the search locates unambiguously and
/// inside the prior's gate; nullopt when none of the first max_scans does. `prior(t)`: the
/// search's centre at t (the receiver's fix there, or the harbour's origin) and its covariance.
std::optional<EstimateRecord> LidarStartState(const LidarAerialFrontend& frontend,
                                              const std::vector<ImuSample>& imu,
                                              const ImuConfig& imu_config,
                                              const std::function<StartPrior(TimeNs)>& prior,
                                              const LidarStartOptions& options);

}  // namespace skerry::lidar_aerial
