#pragma once
/// \file
/// A smooth, twice-differentiable motion through a sequence of estimated states (a batch
/// smoother's trajectory): the truth a digital twin re-simulates its sensors along (twin.h).
///
/// The states (any spacing) are first resampled on a uniform grid of knots, the position by cubic
/// Hermite interpolation of position and velocity, the rotation by slerp. Position is then a
/// uniform cubic B-spline that interpolates the knots, its end velocities clamped to the states'
/// (a tridiagonal solve: Ahlberg, Nilson & Walsh 1967, the B-spline form of de Boor 1978 ch. IX);
/// rotation is a cumulative cubic B-spline on SO(3) (Kim, Kim & Shin 1995; in the form of Sommer,
/// Usenko, Schubert, Demmel & Cremers 2020, "Efficient derivative computation for cumulative
/// B-splines on Lie groups", eq. 4-6), whose control rotations are corrected until the curve
/// passes through the knots' rotations (a damped fixed-point iteration). Both give velocity and
/// acceleration, angular rate and angular acceleration in closed form (Sommer et al. eq. 38-39),
/// so that the IMU a twin synthesises from them integrates back to the same curve.
///
/// All quantities are in the Earth-fixed frame w of the states: v_w and a_w are the derivatives
/// of p_w_b, omega_b and alpha_b the body rate of R_w_b relative to w and its derivative
/// (BodyKinematics). The biases are interpolated linearly. The ends are clamped in velocity, not
/// in acceleration: within two knots of either end the acceleration is the spline's, not the
/// states' motion's (a transient of up to a few cm/s^2 on a vessel in waves).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "skerry/core/nav_state.h"
#include "skerry/sim/vessel_motion.h"

namespace skerry::sim {

class SplineMotion {
 public:
  /// Through `states` (strictly increasing time, at least 2, unit quaternions) with knots every
  /// `knot_s` seconds (> 0; 0 picks the median state spacing). Throws std::invalid_argument
  /// naming the state otherwise.
  explicit SplineMotion(const std::vector<NavState>& states, double knot_s = 0.0);

  TimeNs start_ns() const { return start_ns_; }
  TimeNs end_ns() const { return end_ns_; }
  double knot_s() const { return h_; }
  /// True on [start_ns, end_ns].
  bool Covers(TimeNs t_ns) const { return t_ns >= start_ns_ && t_ns <= end_ns_; }

  /// The kinematics at t (clamped to the span); t_s is seconds since start_ns().
  BodyKinematics At(TimeNs t_ns) const;
  /// The state at t: pose and velocity of the curve, biases interpolated from the states.
  NavState StateAt(TimeNs t_ns) const;

 private:
  double h_ = 0.1;
  TimeNs start_ns_ = 0, end_ns_ = 0;
  std::vector<Eigen::Vector3d> c_;     // position control points, c_[k + 1] is c_k (k >= -1)
  std::vector<Eigen::Quaterniond> r_;  // rotation control points, likewise
  std::vector<TimeNs> bias_t_;         // the states' times and biases
  std::vector<Eigen::Matrix<double, 6, 1>> bias_;
};

}  // namespace skerry::sim
