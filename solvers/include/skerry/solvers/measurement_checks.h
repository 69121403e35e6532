#pragma once
/// \file
/// What the live estimators (NavigationEstimator, SlidingWindowEstimator) refuse from a caller,
/// before anything of the measurement is taken in: a non-finite number, a sigma that is not
/// positive (a covariance that is not positive definite). The refusal is std::invalid_argument
/// naming the field and time, like time that does not increase; the estimator is left as it was,
/// so the caller may go on with the next measurement (an IMU sample refused is bridged by the
/// preintegration from the previous one to the next). docs/robustness.md lists every fault and
/// its outcome.

#include "skerry/core/measurements.h"

namespace skerry {

/// Throws std::invalid_argument when a gyro or accelerometer value is not finite.
void CheckImuSample(const ImuSample& sample);

/// Throws std::invalid_argument when the position (ENU, lat/lon/height) or a sigma is not finite,
/// a sigma is not positive, or a heading (has_heading) or its sigma is not finite / positive.
void CheckGnssFix(const GnssFix& fix);

}  // namespace skerry
