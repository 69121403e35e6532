#pragma once
/// \file
/// Geodesy through GeographicLib: the local ENU world frame is a LocalCartesian frame tangent to
/// the WGS84 ellipsoid at the dataset origin. All heights are ellipsoidal (not orthometric).

#include <Eigen/Core>
#include <memory>

namespace skerry {

struct GeoOrigin {
  double lat_deg = 0.0;
  double lon_deg = 0.0;
  double height_m = 0.0;  ///< ellipsoidal
};

/// Converts between geodetic coordinates and the local ENU frame at an origin.
class LocalFrame {
 public:
  explicit LocalFrame(const GeoOrigin& origin);
  ~LocalFrame();
  LocalFrame(const LocalFrame& other);
  LocalFrame& operator=(const LocalFrame& other);

  /// lat/lon (deg), ellipsoidal height (m) -> ENU (m).
  Eigen::Vector3d ToEnu(double lat_deg, double lon_deg, double height_m) const;
  /// ENU (m) -> lat/lon (deg), ellipsoidal height (m), returned as (lat, lon, h).
  Eigen::Vector3d ToGeodetic(const Eigen::Vector3d& p_enu) const;
  const GeoOrigin& origin() const { return origin_; }

 private:
  GeoOrigin origin_;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace skerry
