#pragma once
/// \file
/// Raw sensor measurements.

#include <Eigen/Core>

#include "skerry/core/time.h"

namespace skerry {

/// One IMU sample, in the IMU frame.
struct ImuSample {
  TimeNs t_ns = 0;
  Eigen::Vector3d gyro_rad_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel_m_s2 = Eigen::Vector3d::Zero();  ///< specific force
};

/// One GNSS fix. Heights are ellipsoidal (WGS84). Sigmas are the receiver's 1-sigma figures.
struct GnssFix {
  TimeNs t_ns = 0;
  double lat_deg = 0.0;
  double lon_deg = 0.0;
  double height_m = 0.0;
  Eigen::Vector3d sigma_enu_m = Eigen::Vector3d::Ones();  ///< east, north, up
  /// Antenna position in local ENU (filled on load).
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero();
  bool has_heading = false;  ///< dual-antenna heading present
  double heading_deg = 0.0;  ///< clockwise from north, of the antenna baseline
  double sigma_heading_deg = 0.0;
};

}  // namespace skerry
