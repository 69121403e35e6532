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

/// Adds the IMU factor (q, p, v, bg, ba of `prev`; q, p, v of `next`), the bias random walk (bg,
/// ba of both) and, if `drift.enabled()`, the GNSS drift step (gb of both) over `pim`'s interval.
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

}  // namespace skerry
