#pragma once
// Helpers shared by the simulator tests.

#include "skerry/sim/scenario.h"

namespace skerry::sim::testing {

/// The scenario with a perfect IMU (no white noise, biases, scale factor or misalignment) and
/// perfect GNSS (no noise, drift, multipath, latency or jitter).
inline ScenarioConfig Perfect(ScenarioConfig c) {
  c.imu.errors = ImuErrorModel();
  c.imu.errors.noise.gyro_noise_density_rad_s_sqrt_hz = 0.0;
  c.imu.errors.noise.accel_noise_density_m_s2_sqrt_hz = 0.0;
  c.imu.errors.noise.gyro_bias_random_walk_rad_s2_sqrt_hz = 0.0;
  c.imu.errors.noise.accel_bias_random_walk_m_s3_sqrt_hz = 0.0;
  c.gnss.noise_sigma_horizontal_m = 0.0;
  c.gnss.noise_sigma_vertical_m = 0.0;
  c.gnss.drift_sigma_horizontal_m = 0.0;
  c.gnss.drift_sigma_vertical_m = 0.0;
  c.gnss.heading_sigma_deg = 0.0;
  c.gnss.slow_drift_sigma_horizontal_m = 0.0;
  c.gnss.slow_drift_sigma_vertical_m = 0.0;
  c.gnss.multipath_rate_per_hour = 0.0;
  c.gnss.latency_s = 0.0;
  c.gnss.stamp_jitter_s = 0.0;
  return c;
}

/// A built-in scenario from the source tree (independent of $SKERRY_SCENARIO_DIR).
inline ScenarioConfig SourceScenario(const std::string& name) {
  return LoadScenario(std::string(SKERRY_SOURCE_DIR) + "/config/scenarios/" + name + ".yaml");
}

}  // namespace skerry::sim::testing
