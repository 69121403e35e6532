#pragma once
/// \file
/// The simulator: a scenario and a seed in, a complete Dataset (IMU, GNSS, ground truth, true
/// states with biases, GNSS events) out.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <string>

#include "skerry/core/measurements.h"
#include "skerry/io/dataset.h"
#include "skerry/sim/earth_motion.h"
#include "skerry/sim/scenario.h"
#include "skerry/sim/vessel_motion.h"

namespace skerry::sim {

/// Simulates the scenario. Deterministic: the same config and seed give a bit-identical dataset
/// on any platform with IEEE doubles and the same libm (mt19937_64 plus our own Box-Muller, no
/// std::normal_distribution). Time starts at 0 ns. Throws std::invalid_argument on a config
/// that LoadScenario would have rejected (non-positive rates or duration).
Dataset Simulate(const ScenarioConfig& config, std::uint64_t seed);

/// The gyro's sensor matrix I + S + M that Simulate draws for `seed` (the gyro measures it times
/// the true rate, plus bias and noise): the truth of an estimated gyro calibration, E = this - I.
Eigen::Matrix3d SimulatedGyroMatrix(const ImuErrorModel& errors, std::uint64_t seed);

/// Renders the dataset's camera frames (Simulate puts their times and names in it) from the
/// scenario's DEM at the true poses (truth_states, interpolated), and writes them as PNG into
/// out_dir/<camera name>/, which becomes each camera's image folder. A segmentation mask or
/// the shaded grey image, as the scenario's camera.images says; pixel noise from `seed`. The
/// DEM is resampled around the track (60 km of view beyond it, clipped to the DEM). Throws
/// InputError naming the DEM when it cannot be read or does not cover the track.
/// `progress` (0..1) may be empty. Frames are rendered on `threads` threads (0: every core);
/// the files are the same whatever their number.
void RenderCameraImages(const ScenarioConfig& config,
                        std::uint64_t seed,
                        Dataset* data,
                        const std::string& out_dir,
                        const std::function<void(double)>& progress = {},
                        int threads = 0);

}  // namespace skerry::sim
