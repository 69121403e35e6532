#pragma once
/// \file
/// Sensor descriptions read from dataset.yaml: extrinsics and noise, with units in the names.

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace skerry {

/// IMU noise model: continuous-time white-noise densities and bias random-walk densities.
struct ImuNoise {
  double gyro_noise_density_rad_s_sqrt_hz = 1.7e-4;
  double accel_noise_density_m_s2_sqrt_hz = 2.0e-3;
  double gyro_bias_random_walk_rad_s2_sqrt_hz = 2.0e-5;
  double accel_bias_random_walk_m_s3_sqrt_hz = 3.0e-3;
};

struct ImuConfig {
  double rate_hz = 200.0;
  ImuNoise noise;
  Eigen::Quaterniond q_b_i = Eigen::Quaterniond::Identity();  ///< IMU -> body rotation
  Eigen::Vector3d p_b_i = Eigen::Vector3d::Zero();            ///< IMU origin in body, m
  /// Prior (initial) bias sigmas, used on the first state.
  double gyro_bias_prior_sigma_rad_s = 1e-3;
  double accel_bias_prior_sigma_m_s2 = 0.05;
};

struct GnssConfig {
  Eigen::Vector3d p_b_g = Eigen::Vector3d::Zero();  ///< (primary) antenna in body, m
  /// Dual-antenna baseline direction in the body frame (primary -> secondary antenna). The
  /// heading measurement is the heading of this vector.
  Eigen::Vector3d baseline_b = Eigen::Vector3d::UnitX();
};

}  // namespace skerry
