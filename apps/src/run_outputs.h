#pragma once
/// \file
/// Writing an estimator run to its output folder: trajectory.tum, states.csv, covariances.csv
/// and summary.json.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "skerry/core/gnss_event.h"
#include "skerry/core/input_error.h"
#include "skerry/eval/evaluation.h"
#include "skerry/io/atomic_file.h"
#include "skerry/io/dataset.h"
#include "skerry/io/estimate_io.h"
#include "skerry/solvers/estimator_config.h"
#include "skerry/solvers/pipeline.h"
#include "skerry/solvers/sliding_window_estimator.h"

namespace skerry::cli {

/// `updates.csv`: one row per window update, header `t,update_ms,solved,solve_ms,iterations,usable`
/// (s, ms, 0/1, ms, count, 0/1).
void WriteUpdatesCsv(const std::string& path, const std::vector<UpdateStats>& stats);

/// updates.csv written as the updates come; it appears complete at Commit() (AtomicFile).
class UpdatesCsvWriter {
 public:
  explicit UpdatesCsvWriter(const std::string& path);
  void Append(const std::vector<UpdateStats>& stats);
  void Commit() { file_.Commit(); }

 private:
  AtomicFile file_;
};

/// `blocks.csv`: one row per block of the sensors beyond IMU and GNSS, in the order they were
/// given: `t,sensor,decision,reacquired,dim,d2` (s, name, accepted | rejected | dropped, 0/1, the
/// gate's degrees of freedom and innovation, 0 when not gated), then the frontends' own figures
/// per block (SensorLog::live_frontend_blocks), the columns of every sensor in the order the
/// sensors registered; a cell is empty where a sensor has no such column or the block no such
/// figure. Not written (false) when the run had no such blocks.
bool WriteBlocksCsv(const std::string& path, const SensorLog& log);
/// The same with other decisions about log's blocks than the window's: the batch's
/// (BatchResult::sensor_decisions, in time order; `skerry smooth`).
bool WriteBlocksCsv(const std::string& path,
                    const SensorLog& log,
                    const std::vector<SensorRecord>& decisions);

/// What summary.json says about a window's updates, gathered piece by piece: a run over a day
/// keeps 10 bytes per keyframe here (the times, for their median and p95) and nothing else.
struct UpdateFigures {
  size_t keyframes = 0;
  int solve_failures = 0;
  std::vector<float> update_ms;
  std::vector<float> solve_ms;       ///< solved updates only
  std::vector<uint16_t> iterations;  ///< solved updates only

  void Add(size_t records, const std::vector<UpdateStats>& stats);
};

/// The estimate of a run folder: its states.csv with the covariances.csv beside it (if any).
/// InputError naming states.csv when the folder has none.
std::vector<EstimateRecord> ReadRunEstimate(const std::string& run_dir);

/// Dataset facts for summary.json (its directory made absolute, so reports can find it).
nlohmann::json DatasetJson(const Dataset& data);

/// The accuracy figures of one evaluation, with the GNSS-event figures when `events` is not
/// empty.
nlohmann::json AccuracyJson(const EvaluationResult& evaluation,
                            const std::vector<GnssEvent>& events);

/// Accuracy against the dataset's ground truth (null when it has none).
nlohmann::json AccuracyJson(const Dataset& data, const std::vector<EstimateRecord>& records);

/// median / p95 (linear interpolation, core Percentile) / max of a list.
nlohmann::json DistributionJson(std::vector<double> values);

/// Solver statistics of a window run (solves, failures, update/solve time, iterations, GNSS);
/// the updates' figures from `updates` when given (a streamed run), else from the run's own.
nlohmann::json WindowStatsJson(const WindowRun& run, const UpdateFigures* updates = nullptr);

/// The summary.json of a window run: dataset, configuration, solver, timing, accuracy.
/// The live estimator's verdict: `status` ("ok" or "diverged"), `failure` when diverged, and
/// `events` (fall-backs to align, watchdog restarts, giving up) with time, kind and reason.
void AddStatusJson(const WindowRun& run, nlohmann::json* summary);
/// A run stopped by a signal (stop_signal.h): `status` "interrupted" and `interrupted`
/// {signal, data_until_s: the data time its estimates reach}; its files hold every estimate made.
void MarkInterrupted(const std::string& signal, TimeNs fed_until_ns, nlohmann::json* summary);

/// The batch's sensor blocks, by sensor name: used at the solution, and left out by the gate.
nlohmann::json BatchSensorsJson(const std::vector<SensorSpec>& sensors, const BatchResult& batch);

/// Estimated sensor parameters per sensor name: value, sigma (null when unknown), the prior.
/// The gyro's estimated calibration (estimate_gyro_calibration): scale factors in ppm and the
/// misalignment E(r, c) off the diagonal in mrad, each with its sigma, beside the datasheet prior.
nlohmann::json GyroCalibrationJson(const GyroCalibrationEstimate& x, const ImuConfig& imu);

nlohmann::json SensorParametersJson(const std::vector<SensorSpec>& sensors,
                                    const std::vector<SensorParameterEstimate>& parameters);

/// Calibrated extrinsics (calibrate: in the configuration) with their sigmas, by sensor name.
nlohmann::json ExtrinsicsJson(const std::vector<SensorSpec>& sensors,
                              const std::vector<ExtrinsicEstimate>& extrinsics);

/// `updates` and `records` (for the accuracy) when the run was streamed (RunWindow with a sink):
/// its figures and the estimates kept for evaluation; the dataset's sample counts and duration
/// are then those the run read.
nlohmann::json WindowSummaryJson(const Dataset& data,
                                 const EstimatorConfig& config,
                                 const WindowRun& run,
                                 const UpdateFigures* updates = nullptr,
                                 const std::vector<EstimateRecord>* records = nullptr);

void WriteJson(const std::string& path, const nlohmann::json& json);

/// A whole text file; InputError(path, 0, "file") when it cannot be opened.
std::string ReadTextFile(const std::string& path);

/// A JSON file; InputError naming the file when it cannot be opened or parsed.
nlohmann::json ReadJsonFile(const std::string& path);

/// Runs `read`, which takes figures out of JSON read from `file`; a member of the wrong type (a
/// file edited or damaged: found by fuzzing) becomes an InputError naming the file, not an
/// exception from the JSON library.
template <typename F>
auto WithJsonErrorsIn(const std::string& file, F&& read) -> decltype(read()) {
  try {
    return read();
  } catch (const nlohmann::json::exception& e) {
    throw InputError(file, 0, "json", std::string("unexpected content (") + e.what() + ")");
  }
}

}  // namespace skerry::cli
