#pragma once
/// \file
/// Whole-trajectory smoothing with the same factors as the window: one keyframe per window
/// keyframe, every IMU interval, every GNSS fix the window neither rejected nor dropped, a Ceres
/// solve over all of it, then a chi-square check of every GNSS residual at the solution (fixes
/// beyond the gate left out and the problem re-solved, up to three rounds), and the marginal
/// covariance of every state.

#include <atomic>
#include <string>
#include <vector>

#include "skerry/io/dataset.h"
#include "skerry/io/estimate_io.h"
#include "skerry/solvers/sensor_block.h"
#include "skerry/solvers/sliding_window_estimator.h"

namespace skerry {

/// A sensor's extrinsic as estimated (calibrate), with its 6x6 covariance (rotation vector rad,
/// position m) when it could be computed.
struct ExtrinsicEstimate {
  SensorId sensor = 0;
  Eigen::Quaterniond q_b_s = Eigen::Quaterniond::Identity();
  Eigen::Vector3d p_b_s = Eigen::Vector3d::Zero();
  bool has_covariance = false;
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Zero();
};

/// A sensor's parameter as estimated (SensorSpec::parameter_prior_sigma > 0), with its variance
/// when it could be computed.
struct SensorParameterEstimate {
  SensorId sensor = 0;
  double value = 0.0;
  bool has_variance = false;
  double variance = 0.0;
};

/// The gyro's calibration as estimated (estimate_gyro_calibration): E, the gyro measuring
/// (I + E) omega + bg, and the covariance of vec(E) (column-major).
struct GyroCalibrationEstimate {
  bool estimated = false;
  Eigen::Matrix3d E = Eigen::Matrix3d::Zero();
  bool has_covariance = false;
  Eigen::Matrix<double, 9, 9> covariance = Eigen::Matrix<double, 9, 9>::Zero();
};

struct BatchResult {
  std::vector<EstimateRecord> records;
  int iterations = 0;  ///< Ceres iterations that tried a step, over every solve
  double solve_s = 0.0;
  double covariance_s = 0.0;
  int gnss_used = 0;                             ///< position factors kept
  int headings_used = 0;                         ///< dual-antenna heading factors
  int gnss_rejected_after_solve = 0;             ///< fixes left out at the final solution
  std::vector<int> sensor_used;                  ///< per sensor: blocks in at the solution
  std::vector<int> sensor_rejected_after_solve;  ///< per sensor: blocks left out by its gate
  /// Per sensor: blocks that found no keyframe at their time (the window withdrew the estimates
  /// there, or they are past the IMU data): not in the batch.
  std::vector<int> sensor_unplaced;
  /// Per block of the sensors beyond IMU and GNSS, in time order: in at the solution
  /// (kAccepted), left out by its gate (kRejectedByGate) or not in the batch (kDropped: no
  /// keyframe at its time, its cost not made there, or dropped by the window whose decisions the
  /// batch takes), with the gate's degrees of freedom and innovation at its last evaluation
  /// (dim = the residual's size and d2 = 0 where it was never gated). Never `reacquired`.
  std::vector<SensorRecord> sensor_decisions;
  std::vector<ExtrinsicEstimate> extrinsics;        ///< every sensor with an extrinsic
  std::vector<SensorParameterEstimate> parameters;  ///< every sensor with an estimated parameter
  GyroCalibrationEstimate gyro_calibration;
  bool usable = false;
  /// The stop flag was set during the solve: `records` are the iterate it had (every keyframe,
  /// not converged), with covariances at that iterate.
  bool interrupted = false;
  std::string ceres_report;
};

/// The batch smoother over the data up to t_end_ns, started from nothing but `start` (a first
/// state and its covariance: the prior of the start rule) and the data: keyframes at the
/// window's rate, their values predicted through the IMU from the solution so far over spans that
/// double (10 s, 20 s, 40 s, ...) and re-solved, every fix it can tie to a keyframe with the
/// robust losses and, at each solution, the fixes beyond the gate dropped (up to three rounds).
/// Nothing of a window's estimates or decisions goes in, so its estimate at t_end_ns is a
/// reference for the window's: the best causal estimate (pipeline.h SmoothUntil).
/// `sensors`: every block of the sensors beyond IMU and GNSS (their decisions are not used), each
/// on a keyframe at its time, judged by its sensor's gate at each solution like the fixes.
BatchResult SmoothFrom(const Dataset& data,
                       const EstimatorConfig& config,
                       const EstimateRecord& start,
                       TimeNs t_end_ns,
                       const SensorLog& sensors = {});

/// What SmoothBatch takes of a window's estimates: their states (their times become the batch
/// keyframes, their values the initial guess) and the first one's covariance (the prior). 144
/// bytes a keyframe, where a window's EstimateRecord, with its 15x15 covariance, is 2 kB: a
/// caller can let the records go before the batch.
struct BatchStart {
  std::vector<NavState> states;
  StateCovariance first_covariance = StateCovariance::Zero();
};

/// The BatchStart of a window's estimates.
BatchStart BatchStartOf(const std::vector<EstimateRecord>& records);

/// `initial`: the window's keyframe estimates (their times become the batch keyframes, their
/// values the initial guess; the first record's covariance is the prior). `decisions`: the
/// window's decision per GNSS fix, decisions[k] about data.gnss_fixes[k] (positions it rejected
/// or dropped stay out, and headings it did not take); std::logic_error if they do not match.
/// `sensors`: the blocks of the other sensors and the window's decisions: those it accepted go in
/// on the keyframe at their time (the window made one there), rejected ones start out, and all
/// are judged again at each solution; dropped ones stay out.
BatchResult SmoothBatch(const Dataset& data,
                        const EstimatorConfig& config,
                        const std::vector<EstimateRecord>& initial,
                        const std::vector<FixRecord>& decisions,
                        const SensorLog& sensors = {},
                        const std::atomic<bool>* stop = nullptr);
/// The same, with the same result, for a caller done with the window's records and with the IMU
/// record: the states and the first covariance in a BatchStart (moved in), and
/// `data->imu_samples` emptied, with those states, once the graph is built. The batch
/// preintegrates the IMU while it builds the graph and never reads it again, so neither is held
/// through the solve, where memory peaks (the IMU: 40 MB an hour at 200 Hz). Nothing is emptied
/// when there is nothing to solve (fewer than two states) or the build throws.
BatchResult SmoothBatch(Dataset* data,
                        const EstimatorConfig& config,
                        BatchStart initial,
                        const std::vector<FixRecord>& decisions,
                        const SensorLog& sensors = {},
                        const std::atomic<bool>* stop = nullptr);

}  // namespace skerry
