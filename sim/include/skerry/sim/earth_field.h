#pragma once
/// \file
/// The Earth around the dataset's local ENU frame w, as the simulator sees it: the Earth's
/// rotation in w, GeographicLib's WGS84 normal gravity (with the centrifugal term) at any point,
/// the local level frame there, and w <-> geodetic. On the flat Earth (EarthKind::kFlat): no
/// rotation, constant gravity along -up, the local level equal to w everywhere.
///
/// Written from GeographicLib directly, apart from the estimator's core/earth_model, so that each
/// checks the other.

#include <Eigen/Core>
#include <memory>

#include "skerry/core/earth_model.h"
#include "skerry/core/geodesy.h"

namespace skerry::sim {

class EarthField {
 public:
  EarthField(const GeoOrigin& origin, const EarthConfig& earth);
  ~EarthField();
  EarthField(EarthField&&) noexcept;
  EarthField& operator=(EarthField&&) noexcept;

  bool round() const { return impl_ != nullptr; }
  const GeoOrigin& origin() const { return origin_; }
  const EarthConfig& earth() const { return earth_; }
  /// The Earth's rotation rate in w (zero when flat).
  const Eigen::Vector3d& omega_ie_w() const { return omega_ie_w_; }
  /// Gravity (gravitation plus the centrifugal term) at p_w, in w.
  Eigen::Vector3d GravityAt(const Eigen::Vector3d& p_w) const;
  /// R_w_n: the local level (east, north, up) frame at p_w, in w.
  Eigen::Matrix3d LocalLevelAt(const Eigen::Vector3d& p_w) const;
  /// w -> geodetic (lat deg, lon deg, ellipsoidal h m); throws std::logic_error when flat.
  Eigen::Vector3d ToGeodetic(const Eigen::Vector3d& p_w) const;
  /// Geodetic -> w, with R_w_n at that point when `R_w_n` is given (round Earth only).
  Eigen::Vector3d FromGeodetic(double lat_deg,
                               double lon_deg,
                               double height_m,
                               Eigen::Matrix3d* R_w_n = nullptr) const;

 private:
  struct Impl;
  GeoOrigin origin_;
  EarthConfig earth_;
  Eigen::Vector3d omega_ie_w_ = Eigen::Vector3d::Zero();
  std::unique_ptr<Impl> impl_;
};

}  // namespace skerry::sim
