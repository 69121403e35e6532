#pragma once
/// \file
/// The true motion of the hull on the Earth, in the dataset's Earth-fixed local ENU frame w.
///
/// VesselMotion describes what a helmsman and the sea do, in the local level frame n at the
/// vessel: speed over ground along the surface, heading from the local north, roll and pitch
/// from the local level, heave. On the round Earth (EarthKind::kWgs84) the vessel follows the
/// WGS84 ellipsoid: latitude and longitude are integrated from the velocity over ground,
///   dlat/dt = v_n / (M + h),   dlon/dt = v_e / ((N + h) cos lat)        (Groves 2013, eq. 5.56)
/// (RK4 on a 10 ms table), the height is the origin's plus heave, and every quantity is then
/// carried into w through R_w_n (GeographicLib LocalCartesian) with the transport rate
///   omega_en^n = [-v_n / (M + h), v_e / (N + h), v_e tan(lat) / (N + h)]   (ENU; Groves eq. 5.44)
/// so that  v_w = R_w_n v_n,  a_w = R_w_n (dv_n/dt + omega_en^n x v_n),  R_w_b = R_w_n R_n_b,
/// omega_wb^b = omega_nb^b + R_b_n omega_en^n. Gravity is GeographicLib's normal gravity in the
/// local level frame (NormalGravity::Gravity(lat, h)), the Earth's rate (0, W cos lat, W sin lat)
/// in n. This is the navigation-frame formulation, written independently of the estimator's
/// Earth-fixed-frame one (core/earth_model), so that each checks the other.
///
/// On the flat Earth (EarthKind::kFlat) n = w everywhere: VesselMotion's kinematics are taken as
/// they are, with constant gravity and no rotation (the world skerry used to simulate).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <vector>

#include "skerry/core/earth_model.h"
#include "skerry/core/measurements.h"
#include "skerry/sim/earth_field.h"
#include "skerry/sim/vessel_motion.h"

namespace skerry::sim {

/// The hull's kinematics in w (BodyKinematics with omega_b and alpha_b relative to the
/// Earth-fixed w) and the Earth around it.
struct EarthKinematics {
  BodyKinematics body;
  double lat_deg = 0.0, lon_deg = 0.0, height_m = 0.0;        ///< body origin, ellipsoidal height
  Eigen::Matrix3d R_w_n = Eigen::Matrix3d::Identity();        ///< local level at the body origin
  Eigen::Quaterniond q_n_b = Eigen::Quaterniond::Identity();  ///< attitude from local level
};

class EarthMotion {
 public:
  EarthMotion(const VesselMotion& motion,
              const GeoOrigin& origin,
              const EarthConfig& earth,
              double duration_s);
  ~EarthMotion();

  EarthKinematics At(double t_s) const;

  /// The Earth's rotation rate in w (zero when flat).
  const Eigen::Vector3d& omega_ie_w() const { return field_.omega_ie_w(); }
  /// Gravity (with the centrifugal term) at any point of w, and the local level there.
  Eigen::Vector3d GravityAt(const Eigen::Vector3d& p_w) const { return field_.GravityAt(p_w); }
  Eigen::Matrix3d LocalLevelAt(const Eigen::Vector3d& p_w) const {
    return field_.LocalLevelAt(p_w);
  }
  /// w -> geodetic (lat, lon, ellipsoidal h).
  Eigen::Vector3d ToGeodetic(const Eigen::Vector3d& p_w) const { return field_.ToGeodetic(p_w); }
  const EarthField& field() const { return field_; }

 private:
  Eigen::Vector2d LatLonRate(double t_s, const Eigen::Vector2d& lat_lon_rad) const;
  Eigen::Vector2d LatLonAt(double t_s) const;

  const VesselMotion& motion_;
  GeoOrigin origin_;
  EarthField field_;
  double table_step_s_ = 0.01;
  std::vector<Eigen::Vector2d> table_lat_lon_rad_;
};

/// What a perfect IMU at T_b_i = (q_b_i, p_b_i) senses for the body motion `kin` (in the
/// Earth-fixed w, rates relative to it), on an Earth turning at omega_ie_w with gravity g_w_imu
/// at the IMU point:
///   gyro  = R_b_i^T (omega_b + R_w_b^T omega_ie_w)
///   accel = R_w_i^T (a_w_i + 2 omega_ie_w x v_w_i - g_w_imu)
///   v_w_i = v_w + R_w_b (omega_b x p_b_i),
///   a_w_i = a_w + R_w_b (alpha_b x p_b_i + omega_b x (omega_b x p_b_i)).
/// (Specific force is the acceleration relative to inertial space less gravitation; in a frame
/// turning with the Earth that is a + 2 W x v + W x (W x r) - gravitation, and gravity g_w
/// already holds -W x (W x r).)
ImuSample IdealImu(const BodyKinematics& kin,
                   const Eigen::Quaterniond& q_b_i,
                   const Eigen::Vector3d& p_b_i,
                   const Eigen::Vector3d& omega_ie_w,
                   const Eigen::Vector3d& g_w_imu);

}  // namespace skerry::sim
