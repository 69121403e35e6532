#pragma once
/// \file
/// Runs the estimators over a dataset: the window processes the data in time order as a live
/// system would; the batch smoother refines the whole trajectory afterwards.

#include <atomic>
#include <functional>
#include <string>
#include <vector>

#include "skerry/io/dataset.h"
#include "skerry/io/measurement_stream.h"
#include "skerry/solvers/batch_smoother.h"
#include "skerry/solvers/navigation_estimator.h"
#include "skerry/solvers/sliding_window_estimator.h"

namespace skerry {

struct WindowRun {
  std::vector<EstimateRecord> records;
  std::vector<UpdateStats> stats;
  GnssStats gnss;
  std::vector<FixRecord> decisions;  ///< per fix fed to the window, in order
  double wall_s = 0.0;
  double data_s = 0.0;  ///< span of the IMU data
  /// Read from the input: every IMU sample and fix unless interrupted.
  size_t imu_samples = 0;
  size_t gnss_fixes = 0;
  /// init.mode "align": when the yaw-hypothesis bank decided (-1: no bank, or never started),
  /// and the start yaw (deg, world frame) and posterior weight of the hypothesis kept. Records
  /// before the decision are the kept estimator's, which a live system would not have shown.
  TimeNs align_start_t_ns = -1;  ///< the kept hypothesis' first state
  TimeNs align_decision_t_ns = -1;
  double align_yaw0_deg = 0.0;
  double align_weight = 0.0;
  bool align_undecided = false;  ///< no clear winner: heading sigma widened to the bank's spread
  double align_heading_sigma_rad = 0.0;  ///< that widened 1-sigma (0 when decided)
  /// The watchdog's verdict (navigation_estimator.h): a diverged run is not a result, and
  /// `failure` says why; `events` lists fall-backs to align and restarts.
  bool diverged = false;
  std::string failure;
  /// The stop flag was set: the data were fed up to `interrupted_at_ns` (the last IMU sample
  /// fed) and the records are the estimates made until then.
  bool interrupted = false;
  TimeNs interrupted_at_ns = 0;
  std::vector<EstimatorEvent> events;
  /// The sensors beyond IMU and GNSS: their blocks, with the window's decision about each.
  SensorLog sensors;
  std::vector<SensorStats> sensor_stats;  ///< per sensor
  /// Calibrated extrinsics at the end of the run (calibrate: in the configuration).
  std::vector<ExtrinsicEstimate> extrinsics;
  /// Estimated sensor parameters at the end of the run.
  std::vector<SensorParameterEstimate> parameters;
  /// The gyro's calibration at the end of the run (estimate_gyro_calibration).
  GyroCalibrationEstimate gyro_calibration;
};

/// Where a run's estimates go as they become final (NavigationEstimator::TakeFinal), a piece at a
/// time in time order, instead of into WindowRun: a run over a day of data then keeps none of
/// them. Called every few seconds of data and once at the end.
using HistorySink = std::function<void(const EstimatorHistory& piece)>;

/// The NavigationEstimator over a recording read from `input` in time order (as the overload
/// below), `data` giving its sensors, origin and the blocks' frontends (its IMU and GNSS vectors
/// are not read and may be empty). With a `sink`, the records, stats and decisions go to it and
/// stay empty in the result; the data span is that of the samples read.
WindowRun RunWindow(MeasurementStream* input,
                    const Dataset& data,
                    const EstimatorConfig& config,
                    const std::function<void(double)>& progress = {},
                    const EstimateRecord* initial = nullptr,
                    const SensorLog& sensors = {},
                    const std::atomic<bool>* stop = nullptr,
                    const HistorySink& sink = {});

/// The NavigationEstimator over the data in time order. `progress(fraction)` is called now and
/// then (may be empty). `initial`: optional given first state (init.mode "given"). `sensors`:
/// the sensors beyond IMU and GNSS and their blocks (frontends/dataset_sensors.h builds them
/// from a dataset), registered in order and fed in time order with the IMU and GNSS. With
/// init.mode "align" (or auto falling back to it) the run is the kept hypothesis' (records from
/// the start of its data). Records are empty when the estimator never initialised.
WindowRun RunWindow(const Dataset& data,
                    const EstimatorConfig& config,
                    const std::function<void(double)>& progress = {},
                    const EstimateRecord* initial = nullptr,
                    const SensorLog& sensors = {},
                    const std::atomic<bool>* stop = nullptr);

/// The best estimate any live estimator with this model can make at `t_end_ns`: the batch
/// smoother over the data up to `t_end_ns` only (the maximum a posteriori estimate given
/// everything received so far; SmoothFrom), started from `window`'s first record alone (the
/// prior its start rule gave, or the kept hypothesis' with init.mode align) and otherwise
/// independent of it: its own keyframes, initial values and fix decisions. Its last record
/// against the window's estimate at the same keyframe shows what marginalisation and the window's
/// linearisation points cost; against the truth, what the data allow at all (e.g. at the end of
/// a GNSS outage). The window's sensor blocks (`window.sensors`) go in too, judged by the batch
/// alone. Records are empty when the window never started.
BatchResult SmoothUntil(const Dataset& data,
                        const EstimatorConfig& config,
                        const WindowRun& window,
                        TimeNs t_end_ns);

}  // namespace skerry
