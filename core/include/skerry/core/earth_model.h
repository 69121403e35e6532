#pragma once
/// \file
/// The Earth as skerry's estimators see it, in the local ENU world frame `w` of a dataset.
///
/// `w` is a GeographicLib LocalCartesian frame: tangent to the WGS84 ellipsoid at the dataset
/// origin and fixed to the Earth, so it rotates with the Earth. Newton's law in such a frame
/// (Savage, "Strapdown Analytics", 2000, eq. 4.1.1-1; Groves, "Principles of GNSS, Inertial, and
/// Multisensor Integrated Navigation Systems", 2nd ed. 2013, eq. 5.33 in the e-frame, which `w`
/// is up to a constant rotation and offset) reads
///
///   dR_w_i/dt = R_w_i [omega_ib]x - [omega_ie_w]x R_w_i
///   dv_w/dt   = R_w_i f_i + g_w(p_w) - 2 omega_ie_w x v_w
///   dp_w/dt   = v_w
///
/// with omega_ib, f_i what a gyro and an accelerometer at the IMU measure, omega_ie_w the Earth's
/// rotation rate expressed in `w` (constant, since `w` is Earth-fixed) and g_w the gravity vector
/// (gravitation plus centrifugal acceleration, "plumb-bob" gravity) at p_w. Nothing in these
/// equations is flat: the curvature of the Earth enters only through g_w(p), whose direction
/// follows the local vertical (3 mrad tilted 20 km from the origin) and whose magnitude falls with
/// height, and through positions below the tangent plane (31 m at 20 km).
///
/// Two models:
/// - kWgs84 (the default, for any real recording): WGS84 rotation rate and the normal gravity of
///   the WGS84 ellipsoid (GeographicLib NormalGravity, Moritz 1980 "Geodetic Reference System
///   1980", including the centrifugal term). The deflection of the vertical and gravity anomalies
///   of the real Earth (up to ~5e-4 m/s^2) are left to the accelerometer bias.
/// - kFlat: no rotation and a constant gravity (0, 0, -gravity_m_s2): for data whose world frame
///   is not tied to the Earth (a motion-capture room whose axes' azimuth is unknown), and to
///   reproduce the flat-world figures. Wrong by the Earth's rate (15 deg/h) and by a tilt of the
///   vertical of 0.16 mrad per km from the origin.
///
/// Copies are cheap (the GeographicLib objects are shared and immutable).

#include <Eigen/Core>
#include <memory>
#include <string>

#include "skerry/core/geodesy.h"

namespace skerry {

enum class EarthKind { kWgs84, kFlat };

/// What dataset.yaml says about the Earth (`earth:` section).
struct EarthConfig {
  EarthKind kind = EarthKind::kWgs84;
  double gravity_m_s2 = 9.80665;  ///< kFlat only: magnitude of the constant gravity
};

/// "wgs84" / "flat"; ParseEarthKind returns false on anything else.
std::string EarthKindName(EarthKind kind);
bool ParseEarthKind(const std::string& name, EarthKind* kind);

/// Gravity near a reference point to first order, g(p) ~ g_ref + dg_dp (p - p_ref): what a factor
/// needs to evaluate gravity with Ceres Jets. The second-order error at a distance d from p_ref is
/// of order g d^2 / R^2: 4e-6 m/s^2 at 4 km, 2.4e-7 m/s^2 at 1 km.
struct LocalGravity {
  Eigen::Vector3d p_ref_w = Eigen::Vector3d::Zero();
  Eigen::Vector3d g_ref_w = Eigen::Vector3d(0.0, 0.0, -9.80665);
  Eigen::Matrix3d dg_dp = Eigen::Matrix3d::Zero();  ///< gravity gradient tensor, 1/s^2

  template <typename T>
  Eigen::Matrix<T, 3, 1> At(const Eigen::Matrix<T, 3, 1>& p_w) const {
    const Eigen::Matrix<T, 3, 1> d = p_w - p_ref_w.cast<T>();
    Eigen::Matrix<T, 3, 1> g;
    for (int r = 0; r < 3; ++r) {
      g[r] = T(g_ref_w[r]) + dg_dp(r, 0) * d[0] + dg_dp(r, 1) * d[1] + dg_dp(r, 2) * d[2];
    }
    return g;
  }
};

class EarthModel {
 public:
  /// The WGS84 Earth seen from a local ENU frame at `origin`.
  explicit EarthModel(const GeoOrigin& origin, const EarthConfig& config = EarthConfig());
  /// A flat, non-rotating Earth with constant gravity (origin at 0, 0, 0).
  static EarthModel Flat(double gravity_m_s2 = 9.80665);

  EarthKind kind() const { return config_.kind; }
  const EarthConfig& config() const { return config_; }
  const GeoOrigin& origin() const { return origin_; }

  /// The Earth's rotation rate relative to inertial space, expressed in w (rad/s); zero when flat.
  const Eigen::Vector3d& omega_ie_w() const { return omega_ie_w_; }

  /// Gravity (gravitation + centrifugal) at p_w, expressed in w (m/s^2).
  Eigen::Vector3d Gravity(const Eigen::Vector3d& p_w) const;
  /// Gravity and its gradient at p_w, for factors (LocalGravity::At).
  LocalGravity GravityNear(const Eigen::Vector3d& p_w) const;

  /// R_w_n: the local-level ENU frame n at p_w (east, north, up of the ellipsoid normal there)
  /// expressed in w. Identity at the origin and for the flat model.
  Eigen::Matrix3d LocalLevel(const Eigen::Vector3d& p_w) const;

 private:
  struct Impl;
  EarthModel(const GeoOrigin& origin,
             const EarthConfig& config,
             std::shared_ptr<const Impl> impl,
             const Eigen::Vector3d& omega_ie_w);
  GeoOrigin origin_;
  EarthConfig config_;
  std::shared_ptr<const Impl> impl_;  ///< null for the flat model
  Eigen::Vector3d omega_ie_w_ = Eigen::Vector3d::Zero();
};

}  // namespace skerry
