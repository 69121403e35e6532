#pragma once
/// \file
/// The sensors of a dataset beyond IMU and GNSS, through their frontends, as the measurement
/// blocks the estimators take (RunWindow, SmoothBatch): one place that knows which frontend
/// reads which part of a dataset.

#include "skerry/io/dataset.h"
#include "skerry/solvers/batch_smoother.h"
#include "skerry/solvers/estimator_config.h"

namespace skerry {

/// Pose fixes (PoseFixFrontend) and the water surface (WaterSurfaceFrontend, one block a
/// `rate_hz` over the IMU's span); the dataset's maps are loaded and checked against its
/// track (dataset_maps.h: InputError when they miss it). The sensors' options come from
/// config.sensors by name; an option for a sensor the dataset does not have is an
/// std::invalid_argument (a misspelt name would otherwise be ignored).
SensorLog DatasetSensors(const Dataset& data, const EstimatorConfig& config);

}  // namespace skerry
