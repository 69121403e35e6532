#pragma once
/// \file
/// The skerry subcommands. Each returns the process exit status; bad input surfaces as
/// skerry::InputError, caught in main.

#include <cstdint>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace skerry::cli {

struct SimulateOptions {
  std::string scenario = "harbour";
  std::optional<std::uint64_t> seed;  ///< not given: the scenario's own seed
  std::string out;
  /// Drop every error skerry's models lack (sim::MatchedToEstimator): the world of the model
  /// of the estimator configuration `matched_config`.
  bool matched = false;
  std::string matched_config = "default";
  std::string earth;  ///< wgs84 | flat: overrides the scenario's Earth (empty: keep it)
  /// Override the scenario's dem.error (sim/dem_error.h): sigma and length, m (< 0: keep it).
  double dem_error_m = -1.0;
  double dem_error_length_m = -1.0;
  /// Override the scenario's dem.relief (sim/terrain_relief.h): the gain (< 0: keep it).
  double dem_relief = -1.0;
  bool overwrite = false;  ///< replace a dataset already in `out` (output_folder.h)
  int jobs = 0;            ///< threads rendering camera frames (0: every core)
};

struct EstimateOptions {
  std::string dataset;
  std::string config = "default";  ///< preset name or YAML file
  /// `--set KEY=VALUE`s on the configuration (LoadEstimatorConfig's overrides), in order.
  std::vector<std::string> set;
  std::string out;
  bool quiet = false;
  bool overwrite = false;  ///< replace results already in `out` (output_folder.h)
  /// smooth: only the data up to this time (s, the data's clock; DatasetUntil), so the batch's
  /// last keyframe is the best estimate a causal estimator could make then. Empty: all of it
  /// (an option, not a NaN sentinel: `--until nan` is refused like `--until inf`).
  std::optional<double> until_s;
  /// Threads of a camera frame's horizon traces (skyline.threads) and, for smooth, of the batch
  /// solve (batch_solver.num_threads); empty: the configuration's. The estimate is the same
  /// whatever their number.
  std::optional<int> jobs;
};

struct EvaluateOptions {
  /// states.csv (with covariances.csv beside it) or a trajectory: TUM, KITTI or EuRoC
  /// (trajectory_formats.h)
  std::string estimate;
  std::string groundtruth;         ///< a trajectory: TUM, KITTI or EuRoC
  std::string estimate_format;     ///< tum | kitti | euroc; empty: from the extension
  std::string groundtruth_format;  ///< tum | kitti | euroc; empty: from the extension
  std::string events;              ///< optional events.csv
  std::string json_out;            ///< optional
  double rpe_delta_s = 1.0;
  /// A span to summarise (span_summary.h), seconds in the data's time; empty: not asked for (one
  /// of the two given: the other is the first / last estimate).
  std::optional<double> from_s;
  std::optional<double> to_s;
  double edge_s = 300.0;  ///< the span's first and last stretch compared for growth
};

struct ImportOptions {
  std::string format;  ///< euroc | husky | nmea0183 | nmea2000 (canboat JSON)
  std::string input;   ///< a recording's folder (euroc, husky) or a log file (nmea0183, nmea2000)
  std::string out;
  double fixes_rate_hz = 0.0;  ///< euroc: position fixes from ground truth at this rate (0: none)
  double fixes_sigma_m = 0.5;
  std::uint64_t seed = 1;
  bool overwrite = false;  ///< replace a dataset already in `out` (output_folder.h)
  /// nmea0183 / nmea2000: KIND=SOURCE, the source to keep for a kind of record
  /// (marine_dataset.h); default: the one with the most records.
  std::vector<std::string> sources;
};

/// A run the watchdog gave up on (exit status 3): not a result.
class EstimatorDiverged : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

int Simulate(const SimulateOptions& options);
int Run(const EstimateOptions& options);
int Smooth(const EstimateOptions& options);
int Evaluate(const EvaluateOptions& options);
int Import(const ImportOptions& options);

}  // namespace skerry::cli
