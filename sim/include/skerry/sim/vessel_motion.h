#pragma once
/// \file
/// The true, smooth motion of the hull: manoeuvres (speed and rate-of-turn profiles with
/// C2-smooth ramps) plus wave-induced roll, pitch and heave (sums of sinusoids) plus heel in
/// turns. Every quantity an ideal IMU senses is available in closed form, so that integrating
/// the ideal IMU reproduces the trajectory (see docs/simulator.md).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "skerry/sim/scenario.h"

namespace skerry::sim {

/// The kinematic state of the hull body (FLU) at one instant, in local ENU.
struct BodyKinematics {
  double t_s = 0.0;
  Eigen::Vector3d p_w_b = Eigen::Vector3d::Zero();  ///< body origin, m
  Eigen::Vector3d v_w = Eigen::Vector3d::Zero();    ///< body-origin velocity, m/s
  Eigen::Vector3d a_w = Eigen::Vector3d::Zero();    ///< body-origin acceleration, m/s^2
  Eigen::Quaterniond q_w_b = Eigen::Quaterniond::Identity();
  Eigen::Vector3d omega_b = Eigen::Vector3d::Zero();  ///< angular rate in body, rad/s
  Eigen::Vector3d alpha_b = Eigen::Vector3d::Zero();  ///< d(omega_b)/dt, rad/s^2
  double roll_rad = 0.0;                              ///< R_w_b = Rz(yaw_enu) Ry(pitch) Rx(roll)
  double pitch_rad = 0.0;
  double yaw_enu_rad = 0.0;  ///< = pi/2 - heading, not wrapped
  double speed_m_s = 0.0;    ///< through the water
};

class VesselMotion {
 public:
  /// Builds the motion over [0, duration_s] (it continues straight beyond); the wave phases are
  /// drawn from `seed`.
  VesselMotion(const TrajectorySpec& trajectory,
               const WaveSpec& waves,
               double duration_s,
               std::uint64_t seed);

  /// The state at time t_s (seconds from the start, >= 0).
  BodyKinematics At(double t_s) const;

 private:
  struct Segment {  // one manoeuvre on [t0, t1)
    Leg::Type type = Leg::Type::kStraight;
    double t0 = 0.0;
    double t1 = 0.0;
    double u0 = 0.0;      // speed at t0
    double du = 0.0;      // kSpeedChange: final minus initial speed
    double yaw0 = 0.0;    // ENU yaw at t0
    double r_peak = 0.0;  // kTurn: signed ENU yaw rate of the steady part
    double ramp_s = 0.0;  // kTurn
    double hold_s = 0.0;  // kTurn
  };
  struct Wave {
    double amplitude;  // rad or m
    double omega_rad_s;
    double phase_rad;
  };
  struct Profile {  // speed u and ENU yaw rate r with their derivatives, and the yaw angle
    double u, du, ddu, r, dr, ddr, yaw;
  };

  const Segment& SegmentAt(double t_s) const;
  Profile ProfileAt(double t_s) const;
  Eigen::Vector2d HorizontalVelocity(double t_s) const;

  std::vector<Segment> segments_;
  std::vector<Wave> roll_, pitch_, heave_;
  Eigen::Vector3d start_enu_m_;
  Eigen::Vector2d current_enu_m_s_;
  double heel_rad_per_m_s2_;
  double table_step_s_;
  std::vector<Eigen::Vector2d> table_p_xy_;  // horizontal position at k * table_step_s_
};

}  // namespace skerry::sim
