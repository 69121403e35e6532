#pragma once
/// \file
/// Shared helpers for the factors tests: an analytic ground-truth trajectory with its ideal IMU
/// samples, numeric Jacobians, and small random-state utilities.
///
/// The trajectory is defined for the IMU frame `i` (position and ZYX Euler angles as sums of
/// sinusoids) in the Earth-fixed world w, so the ideal gyro and accelerometer readings have
/// closed forms:
///   omega_i = ZYX Euler-rate map (below) + R_w_i^T W,  f_i = R_w_i^T (a_w_i + 2 W x v_w_i -
///   g_w(p))
/// with the Earth's rate W and gravity g_w(p) of an EarthModel (flat by default: W = 0,
/// g = (0, 0, -9.80665)); the whole trajectory can be moved away from the origin.
/// The body state follows from the extrinsics (q_b_i, p_b_i) by rigid-body kinematics:
///   R_w_b = R_w_i R_b_i^T,  p_w_b = p_w_i - R_w_b p_b_i,  v_w_b = v_w_i - R_w_b (omega_b x p_b_i).
/// TrajectoryTest in test_imu_preintegration.cc checks these closed forms against numeric
/// derivatives, so the generator is itself tested.

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "skerry/core/earth_model.h"
#include "skerry/core/nav_state.h"
#include "skerry/core/sensor_config.h"
#include "skerry/core/so3.h"
#include "skerry/factors/imu_preintegration.h"

namespace skerry {
namespace test {

inline const Eigen::Vector3d kGravityW(0.0, 0.0, -9.80665);

/// Smooth analytic motion of the IMU frame: a boat-like surge with sway/heave oscillations,
/// a slow turn, and roll/pitch oscillations.
class AnalyticTrajectory {
 public:
  AnalyticTrajectory() = default;
  /// The same motion started at `offset_w` on the given Earth.
  AnalyticTrajectory(const EarthModel& earth, const Eigen::Vector3d& offset_w)
      : earth_(earth), offset_w_(offset_w) {}

  const EarthModel& earth() const { return earth_; }

  /// IMU-frame position in world ENU, m, and its first two derivatives.
  Eigen::Vector3d p_w_i(double t) const {
    return offset_w_ + Eigen::Vector3d(3.0 * t + 2.0 * std::sin(0.7 * t),
                                       1.5 * std::sin(1.1 * t + 0.3), 0.3 * std::sin(2.1 * t));
  }
  Eigen::Vector3d v_w_i(double t) const {
    return {3.0 + 1.4 * std::cos(0.7 * t), 1.65 * std::cos(1.1 * t + 0.3),
            0.63 * std::cos(2.1 * t)};
  }
  Eigen::Vector3d a_w_i(double t) const {
    return {-0.98 * std::sin(0.7 * t), -1.815 * std::sin(1.1 * t + 0.3),
            -1.323 * std::sin(2.1 * t)};
  }

  /// ZYX Euler angles (yaw, pitch, roll) and their rates.
  Eigen::Vector3d euler(double t) const {
    return {0.3 + 0.2 * t + 0.4 * std::sin(0.5 * t), 0.1 * std::sin(1.3 * t),
            0.15 * std::sin(1.7 * t + 0.2)};
  }
  Eigen::Vector3d euler_rate(double t) const {
    return {0.2 + 0.2 * std::cos(0.5 * t), 0.13 * std::cos(1.3 * t),
            0.255 * std::cos(1.7 * t + 0.2)};
  }

  Eigen::Quaterniond q_w_i(double t) const {
    const Eigen::Vector3d e = euler(t);
    return Eigen::Quaterniond(Eigen::AngleAxisd(e[0], Eigen::Vector3d::UnitZ()) *
                              Eigen::AngleAxisd(e[1], Eigen::Vector3d::UnitY()) *
                              Eigen::AngleAxisd(e[2], Eigen::Vector3d::UnitX()));
  }

  /// Angular velocity of the IMU frame relative to w, expressed in the IMU frame.
  Eigen::Vector3d omega_wi(double t) const {
    const Eigen::Vector3d e = euler(t), de = euler_rate(t);
    const double sp = std::sin(e[1]), cp = std::cos(e[1]);
    const double sr = std::sin(e[2]), cr = std::cos(e[2]);
    return {de[2] - de[0] * sp, de[1] * cr + de[0] * cp * sr, -de[1] * sr + de[0] * cp * cr};
  }

  /// What an ideal gyro reads: the rate relative to inertial space.
  Eigen::Vector3d gyro(double t) const {
    return omega_wi(t) + q_w_i(t).conjugate() * earth_.omega_ie_w();
  }

  /// Specific force in the IMU frame (what an ideal accelerometer reads).
  Eigen::Vector3d accel(double t) const {
    return q_w_i(t).conjugate() *
           (a_w_i(t) + 2.0 * earth_.omega_ie_w().cross(v_w_i(t)) - earth_.Gravity(p_w_i(t)));
  }

  /// True body state at t for the given extrinsics and biases.
  NavState BodyState(double t,
                     const ImuConfig& imu,
                     const Eigen::Vector3d& bg,
                     const Eigen::Vector3d& ba) const {
    NavState s;
    s.q_w_b = q_w_i(t) * imu.q_b_i.conjugate();
    s.p_w_b = p_w_i(t) - s.q_w_b * imu.p_b_i;
    const Eigen::Vector3d omega_b = imu.q_b_i * omega_wi(t);
    s.v_w = v_w_i(t) - s.q_w_b * omega_b.cross(imu.p_b_i);
    s.bg = bg;
    s.ba = ba;
    return s;
  }

  /// The Earth terms of an interval starting at t (ImuFactor, PredictBodyState).
  ImuEarthTerms EarthTerms(double t) const { return EarthTermsNear(earth_, p_w_i(t)); }

 private:
  EarthModel earth_ = EarthModel::Flat();
  Eigen::Vector3d offset_w_ = Eigen::Vector3d::Zero();
};

/// One preintegration step: the measurement held over [t, t + dt].
struct ImuStep {
  double dt;
  Eigen::Vector3d gyro;
  Eigen::Vector3d accel;
};

/// Ideal (noise-free, biased) IMU samples at `rate_hz` over [t0, t1], turned into steps by
/// averaging consecutive samples (the trapezoidal rule the preintegration header documents).
inline std::vector<ImuStep> IdealImuSteps(const AnalyticTrajectory& traj,
                                          double t0,
                                          double t1,
                                          double rate_hz,
                                          const Eigen::Vector3d& bg = Eigen::Vector3d::Zero(),
                                          const Eigen::Vector3d& ba = Eigen::Vector3d::Zero()) {
  const int n = static_cast<int>(std::lround((t1 - t0) * rate_hz));
  const double dt = (t1 - t0) / n;
  std::vector<ImuStep> steps;
  steps.reserve(n);
  for (int k = 0; k < n; ++k) {
    const double ta = t0 + k * dt, tb = t0 + (k + 1) * dt;
    steps.push_back({dt, 0.5 * (traj.gyro(ta) + traj.gyro(tb)) + bg,
                     0.5 * (traj.accel(ta) + traj.accel(tb)) + ba});
  }
  return steps;
}

inline ImuPreintegration Preintegrate(const std::vector<ImuStep>& steps,
                                      const ImuNoise& noise,
                                      const Eigen::Vector3d& bg_lin,
                                      const Eigen::Vector3d& ba_lin) {
  ImuPreintegration pim(noise, bg_lin, ba_lin);
  for (const ImuStep& s : steps) pim.Integrate(s.dt, s.gyro, s.accel);
  return pim;
}

/// Central-difference Jacobian of f: R^n -> R^m at x0.
inline Eigen::MatrixXd NumericJacobian(
    const std::function<Eigen::VectorXd(const Eigen::VectorXd&)>& f,
    const Eigen::VectorXd& x0,
    double eps = 1e-6) {
  const Eigen::VectorXd f0 = f(x0);
  Eigen::MatrixXd J(f0.size(), x0.size());
  for (int k = 0; k < x0.size(); ++k) {
    Eigen::VectorXd xp = x0, xm = x0;
    xp[k] += eps;
    xm[k] -= eps;
    J.col(k) = (f(xp) - f(xm)) / (2.0 * eps);
  }
  return J;
}

/// The house `test_jacobian` helper: compares an analytic Jacobian with central differences of
/// f around x0, with a tolerance relative to max(1, |J|_max).
inline void TestJacobian(const std::string& name,
                         const Eigen::MatrixXd& J,
                         const std::function<Eigen::VectorXd(const Eigen::VectorXd&)>& f,
                         const Eigen::VectorXd& x0,
                         double tol = 1e-6,
                         double eps = 1e-6) {
  const Eigen::MatrixXd J_num = NumericJacobian(f, x0, eps);
  ASSERT_EQ(J.rows(), J_num.rows()) << name;
  ASSERT_EQ(J.cols(), J_num.cols()) << name;
  const double scale = std::max(1.0, J_num.cwiseAbs().maxCoeff());
  const double err = (J - J_num).cwiseAbs().maxCoeff();
  EXPECT_LE(err, tol * scale) << name << "\nanalytic:\n" << J << "\nnumeric:\n" << J_num;
}

/// Rotation error angle between two quaternions, rad.
inline double AngleBetween(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  return LogQ<double>(a.conjugate() * b).norm();
}

inline Eigen::Quaterniond RandomQuaternion(std::mt19937* rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Quaterniond q(n(*rng), n(*rng), n(*rng), n(*rng));
  return q.normalized();
}

inline Eigen::Vector3d RandomVector(std::mt19937* rng, double sigma) {
  std::normal_distribution<double> n(0.0, sigma);
  return {n(*rng), n(*rng), n(*rng)};
}

/// An IMU configuration with a non-trivial extrinsic: rotated and offset from the body origin.
inline ImuConfig RotatedOffsetImu() {
  ImuConfig imu;
  imu.q_b_i =
      Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d(0.3, -0.5, 0.8).normalized()));
  imu.p_b_i = Eigen::Vector3d(0.8, -0.35, 0.5);
  return imu;
}

}  // namespace test
}  // namespace skerry
