#pragma once
/// \file
/// A digital twin of a recording: the recording's own sensors, configuration and time stamps,
/// with every measurement synthesised along a smooth truth (spline_motion.h: the batch
/// smoother's trajectory through the real data) from sensor models identified from the data
/// (docs/twin.md; the identification is apps' `skerry twin`).
///
/// IMU: what a perfect IMU at the recording's mounting senses on the truth (IdealImu, on the
/// recording's Earth: earth_field.h), plus the truth's biases (the batch's estimate, interpolated),
/// plus a bias random walk and white noise of the model's densities. GNSS: the truth's antenna
/// position `latency_s` before each real fix's stamp, plus white noise, a first-order
/// Gauss-Markov drift stepped over the real intervals (x+ = phi x + sigma sqrt(1 - phi^2) w,
/// phi = exp(-dt / tau)), and gross-error episodes (a jump, a fix from a reflected signal):
/// episodes start after exponentially distributed gaps (mean 1 / rate) and last an exponentially
/// distributed time (mean `gross_mean_duration_s`, at least one fix), during which every fix is
/// off by one offset drawn per episode (horizontal: a uniform direction and a Rayleigh length of
/// RMS `gross_offset_horizontal_m`; vertical: normal). Optionally a receiver that solves once
/// every `solve_period_s` and propagates its solution to the fixes between (the Furuno logs'
/// 129025 rapid updates: docs/twin.md): at each solution, at stamps `solve_phase_s` + k period, a
/// fresh horizontal offset, and a horizontal propagation velocity error, a first-order
/// Gauss-Markov process stepped from solution to solution; a fix at t carries
/// offset + v_err (t - t_solution), a sawtooth locked to the receiver's clock. The receiver's
/// reported sigmas are the real fix's. Dual-antenna heading where the real fix has one.
/// Samples and fixes outside the truth's span are not in the twin.

#include <cstdint>

#include "skerry/io/dataset.h"
#include "skerry/sim/spline_motion.h"

namespace skerry::sim {

struct TwinImuModel {
  double gyro_noise_density_rad_s_sqrt_hz = 0.0;
  double accel_noise_density_m_s2_sqrt_hz = 0.0;
  /// Bias wander on top of the truth's biases (0: none; the truth's biases already wander as the
  /// batch saw them).
  double gyro_bias_random_walk_rad_s2_sqrt_hz = 0.0;
  double accel_bias_random_walk_m_s3_sqrt_hz = 0.0;
};

struct TwinGnssModel {
  double white_sigma_horizontal_m = 0.0;  ///< per axis
  double white_sigma_vertical_m = 0.0;
  double drift_sigma_horizontal_m = 0.0;  ///< per axis, stationary
  double drift_sigma_vertical_m = 0.0;
  double drift_tau_s = 300.0;
  double gross_rate_per_hour = 0.0;        ///< gross-error episodes per hour (0: none)
  double gross_mean_duration_s = 0.0;      ///< their mean length
  double gross_offset_horizontal_m = 0.0;  ///< RMS horizontal length of an episode's offset
  double gross_offset_vertical_m = 0.0;    ///< 1-sigma of its vertical
  double latency_s = 0.0;                  ///< a fix shows where the antenna was this long before
  double heading_sigma_deg = 0.0;          ///< dual-antenna heading noise
  /// Solve and propagate (0: off, and the other solve_ and propagation_ values unused): the
  /// receiver's solutions are at stamps solve_phase_s + k solve_period_s (stamps' own time scale,
  /// e.g. UTC s), the fixes between them propagated.
  double solve_period_s = 0.0;
  double solve_phase_s = 0.0;
  double solve_offset_sigma_m = 0.0;            ///< per horizontal axis, fresh at each solution
  double propagation_velocity_sigma_m_s = 0.0;  ///< per horizontal axis, stationary
  double propagation_velocity_tau_s = 5.0;      ///< its correlation time (> 0)
};

struct TwinModel {
  TwinImuModel imu;
  TwinGnssModel gnss;
};

/// The twin of `real` along `truth` with `model`, deterministic in `seed`. It keeps real's name
/// (with "-twin"), origin, Earth, sensor configuration (what the user tells skerry: the noise
/// model of dataset.yaml, not the identified one) and stamps, and adds ground truth
/// (groundtruth.tum, truth_states.csv at `truth_rate_hz` over the truth's span). Throws
/// std::invalid_argument when the truth does not overlap the recording or a model value is
/// negative or not finite (or the drift's or the propagation velocity's tau is 0). With the solve
/// period at 0 the twin draws exactly the random numbers it drew before that model existed.
Dataset SimulateTwin(const Dataset& real,
                     const SplineMotion& truth,
                     const TwinModel& model,
                     std::uint64_t seed,
                     double truth_rate_hz = 50.0);

}  // namespace skerry::sim
