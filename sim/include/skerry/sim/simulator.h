#pragma once
/// \file
/// The simulator: a scenario and a seed in, a complete Dataset (IMU, GNSS, ground truth, true
/// states with biases, GNSS events) out.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>

#include "skerry/core/dataset.h"
#include "skerry/core/measurements.h"
#include "skerry/sim/scenario.h"
#include "skerry/sim/vessel_motion.h"

namespace skerry::sim {

/// Simulates the scenario. Deterministic: the same config and seed give a bit-identical dataset
/// on any platform with IEEE doubles and the same libm (mt19937_64 plus our own Box-Muller, no
/// std::normal_distribution). Time starts at 0 ns. Throws std::invalid_argument on a config
/// that LoadScenario would have rejected (non-positive rates or duration).
Dataset Simulate(const ScenarioConfig& config, std::uint64_t seed);

/// What a perfect IMU at T_b_i = (q_b_i, p_b_i) senses for the body motion `kin`:
///   gyro  = R_b_i^T omega_b
///   accel = R_w_i^T (a_w_i - g_w),  g_w = (0, 0, -gravity),
///   a_w_i = a_w + R_w_b (alpha_b x p_b_i + omega_b x (omega_b x p_b_i)).
ImuSample IdealImu(const BodyKinematics& kin,
                   const Eigen::Quaterniond& q_b_i,
                   const Eigen::Vector3d& p_b_i,
                   double gravity_m_s2);

}  // namespace skerry::sim
