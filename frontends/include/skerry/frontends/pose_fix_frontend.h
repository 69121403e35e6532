#pragma once
/// \file
/// The pose-fix frontend, the seam's first consumer (solvers/sensor_block.h): it turns pose fixes
/// from an external matcher (the LiDAR/aerial matcher of prior work fed its EKF with these; radar
/// against a chart, USBL) into measurement blocks on the full pose of the keyframe at each fix's
/// time, with the measured frame's extrinsic T_b_s (factors/pose_fix_factor.h).

#include <string>

#include "skerry/core/earth_model.h"
#include "skerry/core/measurements.h"
#include "skerry/core/sensor_config.h"
#include "skerry/solvers/estimator_config.h"
#include "skerry/solvers/sensor_block.h"

namespace skerry {

class PoseFixFrontend {
 public:
  /// The sensor's name in dataset.yaml and in the configuration's `sensors:`.
  static constexpr char kName[] = "pose_fixes";

  /// `mount`: T_b_s of the measured frame; `options`: the configuration's sensors.pose_fixes.
  PoseFixFrontend(const SensorMount& mount, const SensorOptions& options, const EarthModel& earth);

  /// What registers with an estimator (RegisterSensor): loss, gate and extrinsic.
  SensorSpec Spec() const;
  /// Registers with an estimator (SlidingWindowEstimator, NavigationEstimator, ...).
  template <typename Estimator>
  void Register(Estimator* estimator) {
    id_ = estimator->RegisterSensor(Spec());
  }
  SensorId id() const { return id_; }

  /// The block of one fix (std::invalid_argument when its covariance is not positive definite).
  SensorMeasurement Measurement(const PoseFix& fix) const;

 private:
  SensorMount mount_;
  SensorOptions options_;
  EarthModel earth_;
  SensorId id_ = -1;
};

}  // namespace skerry
