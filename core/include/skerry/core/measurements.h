#pragma once
/// \file
/// Raw sensor measurements.

#include <Eigen/Core>
#include <vector>

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

/// A pose fix from an external matcher (a LiDAR/aerial or radar/chart matcher, a USBL): the
/// measured position of a sensor frame s (the point at p_b_s on the vessel) in the world frame,
/// horizontal or 3-D, optionally with the heading of s's x axis, and the full covariance of what
/// it measures.
struct PoseFix {
  TimeNs t_ns = 0;
  bool has_up = false;       ///< the up component is measured (3-D), else horizontal only
  bool has_heading = false;  ///< the heading is measured
  Eigen::Vector3d p_w = Eigen::Vector3d::Zero();  ///< local ENU, m (up ignored unless has_up)
  double heading_deg = 0.0;                       ///< clockwise from the local north at p_w
  /// Covariance over (east m, north m, up m, heading rad), in that order; only the rows and
  /// columns of what is measured are used (and must be positive definite).
  Eigen::Matrix4d covariance = Eigen::Matrix4d::Identity();

  /// The indices into (e, n, u, heading) that this fix measures.
  std::vector<int> MeasuredComponents() const {
    std::vector<int> c = {0, 1};
    if (has_up) c.push_back(2);
    if (has_heading) c.push_back(3);
    return c;
  }
};

}  // namespace skerry
