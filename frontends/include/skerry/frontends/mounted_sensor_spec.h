#pragma once
/// \file
/// The spec of a sensor mounted on the vessel at T_b_s, with the configuration's options for it
/// (loss, gate, extrinsic calibration and its prior): what every mounted frontend registers.

#include <string>

#include "skerry/core/sensor_config.h"
#include "skerry/solvers/estimator_config.h"
#include "skerry/solvers/sensor_block.h"

namespace skerry {

SensorSpec MountedSensorSpec(const std::string& name,
                             const SensorMount& mount,
                             const SensorOptions& options);

}  // namespace skerry
