#pragma once
/// \file
/// A first state from one sensor's own global search, without GNSS heading (init.mode skyline,
/// init.mode lidar): what the searches share. Roll and pitch come from the accelerometer (the
/// mean specific force around the frame: waves average out to first order), heading and position
/// from the search; velocity is unknown (zero with a wide sigma) and the biases start at zero with
/// the dataset's priors.

#include <Eigen/Core>
#include <vector>

#include "skerry/core/measurements.h"
#include "skerry/core/sensor_config.h"
#include "skerry/io/estimate_io.h"
#include "skerry/solvers/sensor_block.h"

namespace skerry {

/// The body's up (unit, body frame) from the mean specific force within `half_window_s` of t;
/// zero when there is no IMU sample there.
Eigen::Vector3d BodyUpAt(const std::vector<ImuSample>& imu,
                         const ImuConfig& imu_config,
                         TimeNs t_ns,
                         double half_window_s = 0.5);

/// The start at t from a search's pose and covariance, velocity zero with `velocity_sigma_m_s`,
/// biases zero with the IMU's priors.
EstimateRecord StartFromRelocation(TimeNs t_ns,
                                   const Relocation& found,
                                   const ImuConfig& imu_config,
                                   double velocity_sigma_m_s);

}  // namespace skerry
