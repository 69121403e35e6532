#pragma once
/// \file
/// Sensor descriptions read from dataset.yaml: extrinsics and noise, with units in the names.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

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
  /// The gyro's residual scale factors (ppm, each axis) and misalignment (mrad, each
  /// off-diagonal of E) after its factory calibration, one sigma, from the datasheet; 0: not
  /// stated. The prior of an estimated gyro calibration (estimate_gyro_calibration).
  double gyro_scale_factor_sigma_ppm = 0.0;
  double gyro_misalignment_sigma_mrad = 0.0;
  bool has_gyro_calibration_prior() const {
    return gyro_scale_factor_sigma_ppm > 0.0 || gyro_misalignment_sigma_mrad > 0.0;
  }
};

struct GnssConfig {
  Eigen::Vector3d p_b_g = Eigen::Vector3d::Zero();  ///< (primary) antenna in body, m
  /// Dual-antenna baseline direction in the body frame (primary -> secondary antenna). The
  /// heading measurement is the heading of this vector.
  Eigen::Vector3d baseline_b = Eigen::Vector3d::UnitX();
};

/// A vessel floats (sensors.water_surface): the ellipsoidal height of its body origin afloat and
/// how much the waves move it, applied `rate_hz` times a second (water_surface_factor.h).
struct WaterSurfaceConfig {
  double height_m = 0.0;  ///< ellipsoidal (WGS84) height of the body origin afloat
  double sigma_m = 0.3;   ///< heave, and roll/pitch of the origin off the centre of motion
  double rate_hz = 1.0;
};

/// Where a sensor sits on the vessel: T_b_s (sensor -> body).
struct SensorMount {
  Eigen::Quaterniond q_b_s = Eigen::Quaterniond::Identity();
  Eigen::Vector3d p_b_s = Eigen::Vector3d::Zero();  ///< sensor origin in body, m
};

/// A pinhole camera with OpenCV's distortion model (cv::projectPoints' coefficient order).
struct CameraConfig {
  std::string name;       ///< the key under sensors: (camera, camera_port, ...)
  std::string image_dir;  ///< folder of the images, relative to the dataset
  std::string file;       ///< camera.csv: t, image file name
  int width_px = 0, height_px = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;  ///< px
  /// OpenCV distortion coefficients: (k1, k2, p1, p2[, k3[, k4, k5, k6]]), 4, 5 or 8 of them.
  std::vector<double> distortion;
  SensorMount T_b_c;
};

struct LidarConfig {
  std::string name;      ///< the key under sensors: (lidar, lidar_bow, ...)
  std::string scan_dir;  ///< folder of the scans (PCD, PLY, KITTI .bin, LAS)
  std::string file;      ///< lidar.csv: t, scan file name
  SensorMount T_b_l;
};

}  // namespace skerry
