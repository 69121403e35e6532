#pragma once
/// \file
/// SO(3) helpers on Eigen quaternions ([x,y,z,w] storage, Hamilton convention).
///
/// Invariants: rotation vectors are full angles (|phi| = rotation angle in rad); Exp/Log follow
/// Forster et al., "On-Manifold Preintegration for Real-Time Visual-Inertial Odometry",
/// T-RO 2017, eqs. (3)-(8). Right Jacobians follow eq. (8) there. Templated versions let Ceres
/// Jets flow through; small-angle branches use the first Taylor terms.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

namespace skerry {

/// Skew-symmetric matrix [v]x such that [v]x w = v x w.
template <typename T>
Eigen::Matrix<T, 3, 3> Hat(const Eigen::Matrix<T, 3, 1>& v) {
  Eigen::Matrix<T, 3, 3> m;
  m << T(0), -v.z(), v.y(), v.z(), T(0), -v.x(), -v.y(), v.x(), T(0);
  return m;
}

/// Exp: rotation vector -> unit quaternion.
template <typename T>
Eigen::Quaternion<T> ExpQ(const Eigen::Matrix<T, 3, 1>& phi) {
  using std::cos;
  using std::sin;
  using std::sqrt;
  const T theta_sq = phi.squaredNorm();
  T re, im;
  if (theta_sq < T(1e-16)) {
    // Taylor: cos(t/2) ~ 1 - t^2/8, sin(t/2)/t ~ 1/2 - t^2/48.
    re = T(1) - theta_sq / T(8);
    im = T(0.5) - theta_sq / T(48);
  } else {
    const T theta = sqrt(theta_sq);
    re = cos(theta / T(2));
    im = sin(theta / T(2)) / theta;
  }
  return Eigen::Quaternion<T>(re, im * phi.x(), im * phi.y(), im * phi.z());
}

/// Log: unit quaternion -> rotation vector in (-pi, pi]. Chooses the sign with w >= 0.
template <typename T>
Eigen::Matrix<T, 3, 1> LogQ(const Eigen::Quaternion<T>& q_in) {
  using std::atan2;
  using std::sqrt;
  Eigen::Quaternion<T> q = q_in;
  if (q.w() < T(0)) q.coeffs() = -q.coeffs();
  const Eigen::Matrix<T, 3, 1> v = q.vec();
  const T n_sq = v.squaredNorm();
  if (n_sq < T(1e-16)) {
    // Taylor of 2*atan2(n, w)/n around n = 0: 2/w * (1 - n^2/(3 w^2)).
    const T w = q.w();
    return (T(2) / w - T(2) * n_sq / (T(3) * w * w * w)) * v;
  }
  const T n = sqrt(n_sq);
  return (T(2) * atan2(n, q.w()) / n) * v;
}

/// Rotation-matrix Exp.
inline Eigen::Matrix3d ExpSO3(const Eigen::Vector3d& phi) { return ExpQ(phi).toRotationMatrix(); }

/// Rotation-matrix Log.
inline Eigen::Vector3d LogSO3(const Eigen::Matrix3d& R) { return LogQ(Eigen::Quaterniond(R)); }

/// Right Jacobian Jr(phi): Exp(phi + dphi) ~ Exp(phi) Exp(Jr(phi) dphi). Forster eq. (8).
inline Eigen::Matrix3d RightJacobianSO3(const Eigen::Vector3d& phi) {
  const double theta_sq = phi.squaredNorm();
  const Eigen::Matrix3d W = Hat(phi);
  if (theta_sq < 1e-10) return Eigen::Matrix3d::Identity() - 0.5 * W + W * W / 6.0;
  const double theta = std::sqrt(theta_sq);
  return Eigen::Matrix3d::Identity() - (1.0 - std::cos(theta)) / theta_sq * W +
         (theta - std::sin(theta)) / (theta_sq * theta) * W * W;
}

/// Inverse right Jacobian: Log(Exp(phi) Exp(dphi)) ~ phi + Jr^-1(phi) dphi. Forster eq. (9).
inline Eigen::Matrix3d RightJacobianInverseSO3(const Eigen::Vector3d& phi) {
  const double theta_sq = phi.squaredNorm();
  const Eigen::Matrix3d W = Hat(phi);
  if (theta_sq < 1e-10) return Eigen::Matrix3d::Identity() + 0.5 * W + W * W / 12.0;
  const double theta = std::sqrt(theta_sq);
  return Eigen::Matrix3d::Identity() + 0.5 * W +
         (1.0 / theta_sq - (1.0 + std::cos(theta)) / (2.0 * theta * std::sin(theta))) * W * W;
}

/// Wrap an angle to (-pi, pi].
template <typename T>
T WrapAngle(const T& a) {
  using std::atan2;
  using std::cos;
  using std::sin;
  return atan2(sin(a), cos(a));
}

}  // namespace skerry
