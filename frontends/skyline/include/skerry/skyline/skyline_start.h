#pragma once
/// \file
/// A first state without GNSS (init.mode skyline): the global search (frame_locator.h) on the
/// first camera frames, within a radius of a prior position, heading unknown, roll and pitch from
/// the accelerometer. Velocity is unknown (zero with a wide sigma) and the biases are at zero with
/// the dataset's priors.

#include <optional>
#include <vector>

#include "skerry/core/measurements.h"
#include "skerry/core/sensor_config.h"
#include "skerry/io/estimate_io.h"
#include "skerry/skyline/skyline_frontend.h"

namespace skerry::skyline {

struct SkylineStartOptions {
  double search_radius_m = 1000.0;
  double velocity_sigma_m_s = 5.0;
  int max_frames = 10;  ///< frames tried, in order, before giving up
};

/// The state at the first frame (of those handed to `frontend`) the search locates; nullopt
/// when none of the first max_frames does. `prior_p_w_b`: the centre of the search.
std::optional<EstimateRecord> SkylineStartState(const SkylineFrontend& frontend,
                                                const std::vector<ImuSample>& imu,
                                                const ImuConfig& imu_config,
                                                const Eigen::Vector3d& prior_p_w_b,
                                                const SkylineStartOptions& options);

}  // namespace skerry::skyline
