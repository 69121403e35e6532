#pragma once
/// \file
/// The simulator: a scenario and a seed in, a complete Dataset (IMU, GNSS, ground truth, true
/// states with biases, GNSS events) out.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>

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

}  // namespace skerry::sim
