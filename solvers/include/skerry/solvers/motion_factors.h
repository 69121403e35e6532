#pragma once
/// \file
/// The factors that link two consecutive keyframes through the IMU: the preintegrated IMU factor
/// (imu_factor.h), the bias random walk and, when the GNSS drift is modelled, its Gauss-Markov
/// step over the same interval. One builder for the sliding window and the batch smoother, so
/// that both solve the same problem.

#include <Eigen/Core>

#include "skerry/core/earth_model.h"
#include "skerry/core/sensor_config.h"
#include "skerry/factors/imu_preintegration.h"
#include "skerry/solvers/estimator_config.h"
#include "skerry/solvers/nav_graph.h"

namespace skerry {

/// Adds the IMU factor (q, p, v, bg, ba of `prev`; q, p, v of `next`; and the IMU calibration
/// when the graph has one: then `pim` must carry its Jacobians), the bias random walk (bg, ba of
/// both) and, if `drift.enabled()`, the GNSS drift step (gb of both) over `pim`'s interval.
/// `gyro_prev`, `gyro_next`: the keyframes' gyro readings (lever-arm velocity); `earth`: the
/// Earth terms near the interval's start (EarthTermsNear). Returns the drift transition's
/// factor id, -1 without the drift model.
FactorId AddMotionFactors(NavGraph* graph,
                          KeyframeId prev,
                          KeyframeId next,
                          const ImuPreintegration& pim,
                          const ImuConfig& imu,
                          const Eigen::Vector3d& gyro_prev,
                          const Eigen::Vector3d& gyro_next,
                          const ImuEarthTerms& earth,
                          const GnssDriftParams& drift);

/// Whether an estimator with `config` on an IMU `imu` estimates the gyro's calibration: asked
/// for, and the dataset states its datasheet's sigmas.
inline bool EstimatesGyroCalibration(const EstimatorConfig& config, const ImuConfig& imu) {
  return config.estimate_gyro_calibration && imu.has_gyro_calibration_prior();
}

/// Adds the IMU calibration block (the gyro's E, GyroCalibrationJacobians) and its prior: zero
/// mean with the datasheet's sigmas (ImuConfig; an axis stated as 0 is held at 0 by a 1e-9
/// sigma), or, given `current` and its `covariance` (a window's new graph taking over what the
/// old one learnt), those.
void AddImuCalibration(NavGraph* graph,
                       const ImuConfig& imu,
                       const ImuCalibration* current = nullptr,
                       const Eigen::Matrix<double, 9, 9>* covariance = nullptr);

}  // namespace skerry
