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

struct LidarStartOptions {
  double search_radius_m = 30.0;  ///< around the prior (the coarse search caps it at 50 m)
  double velocity_sigma_m_s = 5.0;
  int max_scans = 10;  ///< scans tried, in order, before giving up
};

/// The state at the first block (of those `frontend` made) the search locates unambiguously;
/// nullopt when none of the first max_scans does. `prior_p_w_b(t)`: the search's centre at t (the
/// receiver's fix there, or the harbour's origin).
std::optional<EstimateRecord> LidarStartState(
    const LidarAerialFrontend& frontend,
    const std::vector<ImuSample>& imu,
    const ImuConfig& imu_config,
    const std::function<Eigen::Vector3d(TimeNs)>& prior_p_w_b,
    const LidarStartOptions& options);

}  // namespace skerry::lidar_aerial
