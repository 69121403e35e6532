#pragma once
/// \file
/// The navigation state of one keyframe.

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "skerry/core/time.h"

namespace skerry {

/// State of the hull body (FLU) at one instant, in the local ENU world frame.
/// Biases are those of the IMU, in the IMU frame.
struct NavState {
  TimeNs t_ns = 0;
  Eigen::Quaterniond q_w_b = Eigen::Quaterniond::Identity();  ///< T_w_b rotation
  Eigen::Vector3d p_w_b = Eigen::Vector3d::Zero();            ///< T_w_b translation, m
  Eigen::Vector3d v_w = Eigen::Vector3d::Zero();              ///< body-origin velocity, m/s
  Eigen::Vector3d bg = Eigen::Vector3d::Zero();               ///< gyro bias, rad/s
  Eigen::Vector3d ba = Eigen::Vector3d::Zero();               ///< accelerometer bias, m/s^2
};

/// Tangent ordering used for every 15x15 state covariance in skerry:
/// [dtheta (3, world-frame/left rotation perturbation, rad), dp (3, m), dv (3, m/s),
///  dbg (3, rad/s), dba (3, m/s^2)].
enum StateBlock : int { kRot = 0, kPos = 3, kVel = 6, kBg = 9, kBa = 12, kStateDim = 15 };

using StateCovariance = Eigen::Matrix<double, 15, 15>;

}  // namespace skerry
