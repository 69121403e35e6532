#pragma once
/// \file
/// Is the vehicle at rest at the start of the data, and for how long? (init.static_s: auto)
///
/// A platform at rest is not a quiet IMU: a MAV on the ground with its motors running shakes its
/// gyro by 0.01-0.1 rad/s (EuRoC), a moored hull rolls with the waves. What rest means is that
/// nothing moves on average: the IMU is cut into blocks of kRestBlockS and the start is at rest
/// while every block's mean gyro and mean specific force stay within a tolerance of the first
/// block's, and the specific force is gravity. The tolerances are the larger of four standard
/// errors of a block mean under the white-noise model and 0.3 deg/s (gyro), 0.1 m/s^2
/// (accelerometer): a turn or a take-off moves the means by much more (EuRoC: 0.1 rad/s and
/// 0.6 m/s^2 in the half second of take-off), a swell rolling a hull 0.35 deg at 4.5 s by 0.015
/// rad/s. A hull rolling in waves is therefore not at rest, and starts as a moving one.

#include <vector>

#include "skerry/core/measurements.h"
#include "skerry/core/sensor_config.h"

namespace skerry {

constexpr double kRestBlockS = 0.5;
constexpr double kRestMinS = 2.0;   ///< a shorter rest is not used
constexpr double kRestMaxS = 30.0;  ///< rest beyond this is not waited for

struct RestPeriod {
  bool decided = false;     ///< false: every block so far is at rest and kRestMaxS not reached
  double duration_s = 0.0;  ///< from the first sample; 0 when not at rest (or under kRestMinS)
};

/// Rest at the start of `imu` (samples in time order, the IMU's own frame), with the noise
/// model and rate of `config`.
RestPeriod DetectRestAtStart(const std::vector<ImuSample>& imu,
                             const ImuConfig& config,
                             double gravity_m_s2);

}  // namespace skerry
