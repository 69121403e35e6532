#include "commands.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <utility>

#include "command_line_time.h"
#include "output_folder.h"
#include "run_outputs.h"
#include "skerry/core/input_error.h"
#include "skerry/eval/evaluation.h"
#include "skerry/eval/event_metrics.h"
#include "skerry/eval/span_summary.h"
#include "skerry/frontends/dataset_sensors.h"
#include "skerry/io/csv_reader.h"
#include "skerry/io/dataset.h"
#include "skerry/io/estimate_io.h"
#include "skerry/io/importers.h"
#include "skerry/io/marine_dataset.h"
#include "skerry/io/measurement_stream.h"
#include "skerry/io/nmea0183.h"
#include "skerry/io/nmea2000_json.h"
#include "skerry/io/trajectory.h"
#include "skerry/io/trajectory_formats.h"
#include "skerry/sim/aerial_render.h"
#include "skerry/sim/lidar_scans.h"
#include "skerry/sim/scenario.h"
#include "skerry/sim/simulator.h"
#include "skerry/solvers/batch_smoother.h"
#include "skerry/solvers/pipeline.h"
#include "stop_signal.h"

namespace skerry::cli {

namespace {

// A one-line progress bar on stderr (only when stderr is a terminal or forced).
class Progress {
 public:
  explicit Progress(bool enabled, std::string label)
      : enabled_(enabled), label_(std::move(label)) {}
  void operator()(double fraction) {
    if (!enabled_) return;
    const int percent = static_cast<int>(fraction * 100.0 + 0.5);
    if (percent == last_) return;
    last_ = percent;
    const int width = 30;
    const int filled = percent * width / 100;
    std::fprintf(stderr, "\r%s [%s%s] %3d%%", label_.c_str(), std::string(filled, '#').c_str(),
                 std::string(width - filled, ' ').c_str(), percent);
    if (percent >= 100) std::fprintf(stderr, "\n");
    std::fflush(stderr);
  }

 private:
  bool enabled_;
  std::string label_;
  int last_ = -1;
};

void PrintAccuracy(const nlohmann::json& acc) {
  if (acc.is_null()) return;
  std::printf("  horizontal RMSE %.3f m (max %.3f), heading RMSE %.3f deg (max %.3f)\n",
              acc["horizontal_m"]["rmse"].get<double>(), acc["horizontal_m"]["max"].get<double>(),
              acc["heading_deg"]["rmse"].get<double>(), acc["heading_deg"]["max"].get<double>());
  if (acc.contains("nees")) {
    const auto& n = acc["nees"];
    std::printf(
        "  position ANEES %.2f (95%% bounds %.2f..%.2f: %d epochs, worth %.0f independent ones)\n",
        n["anees_position"].get<double>(), n["anees_position_bounds_95"][0].get<double>(),
        n["anees_position_bounds_95"][1].get<double>(), n["count"].get<int>(),
        n["effective_count"].get<double>());
  }
  if (acc.contains("events")) {
    const auto& e = acc["events"];
    std::printf("  outside outages: horizontal RMSE %.3f m, heading RMSE %.3f deg\n",
                e["horizontal_outside_outages_m"]["rmse"].get<double>(),
                e["heading_outside_outages_deg"]["rmse"].get<double>());
    // JSON null: no estimate inside the event (the watchdog withdrew them).
    auto metres = [](const nlohmann::json& v) {
      return v.is_number() ? fmt::format("{:.2f} m", v.get<double>()) : std::string("n/a");
    };
    for (const auto& o : e["outages"]) {
      std::printf("  outage at %.0f s for %.0f s: horizontal error at its end %s\n",
                  o["t_start_s"].get<double>(), o["duration_s"].get<double>(),
                  metres(o["horizontal_error_at_end_m"]).c_str());
    }
    for (const auto& jm : e["jumps"]) {
      std::printf("  GNSS jump of %.1f m at %.0f s for %.0f s: max horizontal error %s\n",
                  jm["offset_m"].get<double>(), jm["t_start_s"].get<double>(),
                  jm["duration_s"].get<double>(), metres(jm["max_horizontal_error_m"]).c_str());
    }
  }
}

bool ShowProgress(bool quiet) { return !quiet && isatty(fileno(stderr)); }

double SecondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// A diverged run is not a result: summary.json says so (status, why, the watchdog's events) and
// nothing else is written; the command fails.
[[noreturn]] void ThrowDiverged(const char* command,
                                const EstimateOptions& o,
                                const Dataset& data,
                                const EstimatorConfig& config,
                                const WindowRun& run,
                                const UpdateFigures* streamed = nullptr) {
  std::filesystem::create_directories(o.out);
  nlohmann::json summary = WindowSummaryJson(data, config, run, streamed);
  summary["command"] = command;
  summary.erase("accuracy");
  WriteJson(o.out + "/summary.json", summary);
  throw EstimatorDiverged(o.dataset + ": " + run.failure +
                          "; no estimates written (summary.json has the watchdog's events)");
}

std::string GnssPath(const std::string& dir, const Dataset& data) {
  return data.gnss_path.empty() ? dir + "/gnss.csv" : data.gnss_path;
}

// Why a window gave no estimate, said as precisely as the data allow.
[[noreturn]] void ThrowNeverInitialised(const std::string& dir,
                                        const Dataset& data,
                                        const EstimatorConfig& config) {
  if (!data.has_gnss) {
    throw InputError(dir + "/dataset.yaml", 0, "sensors.gnss",
                     "no GNSS sensor: nothing to start the estimator from (init.mode given needs "
                     "a first state from the API)");
  }
  if (data.gnss_fixes.empty()) {
    throw InputError(GnssPath(dir, data), 0, "t", "no fixes: the file has a header and no data");
  }
  if (data.gnss_fixes.front().t_ns >= data.imu_samples.back().t_ns) {
    throw InputError(GnssPath(dir, data), 0, "t",
                     "every fix is after the last IMU sample (" +
                         FormatSeconds(data.imu_samples.back().t_ns) + " s): different clocks?");
  }
  const std::string why =
      config.init.mode == "align"
          ? "no GNSS fix arrived, or too few for a velocity"
          : "no GNSS fixes with enough motion for a course over ground, and no dual-antenna "
            "heading; if the course is not the heading or the vehicle starts at rest, try "
            "init.mode: align (docs/configuration.md)";
  throw InputError(dir, 0, "gnss", "the estimator never initialised (" + why + ")");
}

}  // namespace

int Simulate(const SimulateOptions& o) {
  sim::ScenarioConfig scenario = sim::LoadScenario(o.scenario);
  if (o.matched) {
    const GnssDriftParams& d = LoadPreset(o.matched_config).gnss_drift;
    scenario =
        sim::MatchedToEstimator(scenario, {d.sigma_horizontal_m, d.sigma_vertical_m, d.tau_s});
  }
  if (!o.earth.empty()) {
    const EarthKind before = scenario.earth.kind;
    ParseEarthKind(o.earth, &scenario.earth.kind);
    // A world other than the scenario's says so in the dataset's name, as --matched does.
    if (scenario.earth.kind != before) {
      scenario.name += scenario.earth.kind == EarthKind::kFlat ? "-flat" : "-wgs84";
    }
  }
  if (o.dem_error_m >= 0 || o.dem_error_length_m >= 0) {
    if (!scenario.dem) {
      throw InputError(o.scenario, 0, "dem", "--dem-error: the scenario has no dem");
    }
    if (o.dem_error_m >= 0) scenario.dem->error.sigma_m = o.dem_error_m;
    if (o.dem_error_length_m >= 0) scenario.dem->error.length_m = o.dem_error_length_m;
    // The map's error in the world says so in the dataset's name, as --earth does.
    scenario.name += fmt::format("-dem-error-{:g}m", scenario.dem->error.sigma_m);
  }
  if (o.dem_relief >= 0) {
    if (!scenario.dem) {
      throw InputError(o.scenario, 0, "dem", "--dem-relief: the scenario has no dem");
    }
    scenario.dem->relief.gain = o.dem_relief;
    scenario.name += fmt::format("-relief-{:g}", o.dem_relief);
  }
  const std::uint64_t seed = o.seed ? *o.seed : scenario.seed;
  PrepareOutputFolder(o.out, DatasetFiles(), o.overwrite);
  const auto t0 = std::chrono::steady_clock::now();
  Dataset data = sim::Simulate(scenario, seed);
  if (!data.cameras.empty()) {
    Progress progress(ShowProgress(false), "camera frames");
    sim::RenderCameraImages(
        scenario, seed, &data, o.out, [&progress](double f) { progress(f); }, o.jobs);
  }
  if (scenario.harbour.enabled && scenario.harbour.aerial_image.enabled) {
    Progress progress(ShowProgress(false), "aerial image");
    sim::RenderAerialImage(scenario, seed, &data, o.out, [&progress](double f) { progress(f); });
  }
  if (!data.lidars.empty()) {
    Progress progress(ShowProgress(false), "lidar scans");
    sim::RenderLidarScans(scenario, seed, &data, o.out, [&progress](double f) { progress(f); });
  }
  WriteDataset(data, o.out);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf(
      "simulated '%s' (seed %llu): %zu IMU samples, %zu GNSS fixes, %.0f s of data in %.1f s\n",
      scenario.name.c_str(), static_cast<unsigned long long>(seed), data.imu_samples.size(),
      data.gnss_fixes.size(), scenario.duration_s, s);
  if (!data.lidars.empty()) {
    std::printf("  %zu LiDAR scans in %s\n", data.lidar_scans[0].size(),
                data.lidars[0].scan_dir.c_str());
  }
  if (data.orthophoto) std::printf("  aerial image %s\n", data.orthophoto->path.c_str());
  std::printf("dataset written to %s\n", o.out.c_str());
  return 0;
}

// The dataset's sensors beyond IMU and GNSS through their frontends; a configuration naming a
// sensor the dataset lacks is an input error of the configuration.
SensorLog SensorsOf(const Dataset& data, const EstimatorConfig& config, const std::string& path) {
  try {
    return DatasetSensors(data, config);
  } catch (const std::invalid_argument& e) {
    throw InputError(path, 0, "sensors", e.what());
  }
}

// The frontends of cameras, LiDARs and a water surface need the whole IMU record before the run
// (a skyline start, the heights of the water); without them `run` streams the IMU and GNSS files.
bool NeedsWholeRecord(const Dataset& data) {
  return !data.cameras.empty() || !data.lidars.empty() || data.water_surface.has_value();
}

int Run(const EstimateOptions& o) {
  // From the start: a signal while the data load stops the run before its first sample.
  const StopSignal stop;
  const auto t_start = std::chrono::steady_clock::now();
  Dataset data = LoadDataset(o.dataset, DatasetParts::kWithoutStreams);
  RequireImu(data, "run");
  const bool streamed = !NeedsWholeRecord(data);
  // truth_states.csv is for the simulator's own checks: no estimator reads it.
  if (!streamed) data = LoadDataset(o.dataset, DatasetParts::kWithoutTruthStates);
  const double load_s = SecondsSince(t_start);
  EstimatorConfig config = LoadPreset(o.config, o.set);
  if (o.jobs) config.skyline.threads = *o.jobs;
  PrepareOutputFolder(o.out, RunResultFiles(), o.overwrite);
  if (!o.quiet) {
    if (streamed) {
      std::printf("skerry run: dataset '%s' (IMU and GNSS read as the run goes), config '%s'\n",
                  data.name.c_str(), config.name.c_str());
    } else {
      std::printf("skerry run: dataset '%s' (%zu IMU samples, %zu GNSS fixes), config '%s'\n",
                  data.name.c_str(), data.imu_samples.size(), data.gnss_fixes.size(),
                  config.name.c_str());
    }
  }
  // The estimates go to their files as they become final: memory does not grow with the
  // recording, but for the estimates kept to evaluate against a ground truth when there is one.
  std::filesystem::create_directories(o.out);
  EstimateFilesWriter estimates(o.out);
  UpdatesCsvWriter updates(o.out + "/updates.csv");
  UpdateFigures figures;
  std::vector<EstimateRecord> kept;
  double write_s = 0.0;  // the estimates and updates handed to their files, as the run goes
  const HistorySink sink = [&](const EstimatorHistory& piece) {
    const auto t_write = std::chrono::steady_clock::now();
    estimates.Append(piece.outputs);
    updates.Append(piece.stats);
    write_s += SecondsSince(t_write);
    figures.Add(piece.outputs.size(), piece.stats);
    if (!data.groundtruth.empty())
      kept.insert(kept.end(), piece.outputs.begin(), piece.outputs.end());
  };
  std::unique_ptr<MeasurementStream> input;
  if (streamed) {
    input = std::make_unique<DatasetFileStream>(data);
  } else {
    input = std::make_unique<InMemoryStream>(data);
  }
  Progress progress(ShowProgress(o.quiet), "window");
  const WindowRun run = RunWindow(
      input.get(), data, config, [&progress](double f) { progress(f); }, nullptr,
      SensorsOf(data, config, o.config), stop.flag(), sink);
  if (run.diverged) ThrowDiverged("run", o, data, config, run, &figures);
  if (estimates.count() == 0 && !run.interrupted) {
    ThrowNeverInitialised(
        o.dataset, streamed ? LoadDataset(o.dataset, DatasetParts::kWithoutTruthStates) : data,
        config);
  }
  // summary.json last: its presence says the other files are complete.
  const auto t_commit = std::chrono::steady_clock::now();
  estimates.Commit();
  updates.Commit();
  WriteBlocksCsv(o.out + "/blocks.csv", run.sensors);
  write_s += SecondsSince(t_commit);
  const auto t_evaluate = std::chrono::steady_clock::now();
  nlohmann::json summary = WindowSummaryJson(data, config, run, &figures, &kept);
  // wall_s is the window's, with the streamed reads and the writes as it went.
  summary["timing"]["load_s"] = load_s;
  summary["timing"]["write_s"] = write_s;
  summary["timing"]["evaluate_s"] = SecondsSince(t_evaluate);
  summary["timing"]["total_s"] = SecondsSince(t_start);
  if (run.interrupted) MarkInterrupted(stop.signal_name(), run.interrupted_at_ns, &summary);
  WriteJson(o.out + "/summary.json", summary);
  if (run.interrupted) {
    std::fprintf(stderr,
                 "\nskerry run: stopped by %s at t=%s s of the data; %zu keyframes estimated so "
                 "far written to %s (summary.json says \"interrupted\")\n",
                 stop.signal_name(), FormatSeconds(run.interrupted_at_ns).c_str(),
                 estimates.count(), o.out.c_str());
    return stop.exit_status();
  }
  if (!o.quiet) {
    std::printf("  %zu keyframes, %zu solves, %.1f s for %.0f s of data (%.0fx real time)\n",
                estimates.count(), summary["solver"]["solves"].get<size_t>(), run.wall_s,
                run.data_s, run.data_s / std::max(run.wall_s, 1e-9));
    for (const EstimatorEvent& e : run.events) {
      std::printf("  %s at t=%s: %s\n",
                  e.kind == EstimatorEvent::Kind::kFellBackToAlign ? "start" : "watchdog",
                  FormatSeconds(e.t_ns).c_str(), e.reason.c_str());
    }
    if (summary.contains("align") && !summary["align"]["clear_winner"].get<bool>()) {
      std::printf(
          "  align: no clear heading after %.1f s; kept the likeliest hypothesis (started at %.0f "
          "deg, weight %.3f of %d) with its heading sigma widened to the bank's spread\n",
          summary["align"]["decided_after_s"].get<double>(),
          summary["align"]["kept_start_yaw_deg"].get<double>(),
          summary["align"]["kept_weight"].get<double>(), config.init.align_hypotheses);
    } else if (summary.contains("align")) {
      std::printf(
          "  align: decided %.1f s after the start, kept the hypothesis started at %.0f deg "
          "(weight %.3f of %d); estimates before then are that hypothesis' own\n",
          summary["align"]["decided_after_s"].get<double>(),
          summary["align"]["kept_start_yaw_deg"].get<double>(),
          summary["align"]["kept_weight"].get<double>(), config.init.align_hypotheses);
    }
    PrintAccuracy(summary["accuracy"]);
    std::printf(
        "results in %s (trajectory.tum, states.csv, covariances.csv, updates.csv, summary.json)\n",
        o.out.c_str());
  }
  return 0;
}

int Smooth(const EstimateOptions& o) {
  // From the start: a signal while the data load stops the run before its first sample.
  const StopSignal stop;
  const auto t_start = std::chrono::steady_clock::now();
  // All but truth_states.csv, which nothing here reads (the accuracy is against `groundtruth`).
  Dataset data = LoadDataset(o.dataset, DatasetParts::kWithoutTruthStates);
  if (o.until_s) {
    const TimeNs until_ns = CommandLineTime(*o.until_s, "--until");
    const TimeNs first_ns = data.imu_samples.empty() ? 0 : data.imu_samples.front().t_ns;
    data = DatasetUntil(data, until_ns);
    if (data.imu_samples.size() < 2) {
      throw InputError(
          kCommandLine, 0, "--until",
          "leaves no IMU record: the data begin at t=" + FormatSeconds(first_ns) + " s");
    }
  }
  double load_s = SecondsSince(t_start);
  RequireImu(data, "smooth");
  EstimatorConfig config = LoadPreset(o.config, o.set);
  if (o.jobs) {
    config.batch_ceres.num_threads = *o.jobs;
    config.skyline.threads = *o.jobs;  // the initial pass's frames
  }
  PrepareOutputFolder(o.out, RunResultFiles(), o.overwrite);
  if (!o.quiet) {
    std::printf("skerry smooth: dataset '%s', config '%s'\n", data.name.c_str(),
                config.name.c_str());
  }
  Progress progress(ShowProgress(o.quiet), "initial pass (window)");
  WindowRun run = RunWindow(
      data, config, [&progress](double f) { progress(f); }, nullptr,
      SensorsOf(data, config, o.config), stop.flag());
  if (run.diverged) ThrowDiverged("smooth", o, data, config, run);
  if (run.records.empty() && !run.interrupted) ThrowNeverInitialised(o.dataset, data, config);
  if (run.interrupted) {
    // Stopped in the initial pass: its estimates are what there is; the batch does not run.
    WriteEstimateFiles(o.out, run.records);
    nlohmann::json summary = WindowSummaryJson(data, config, run);
    summary["command"] = "smooth";
    summary["estimates"] = "initial window pass (the batch did not run)";
    MarkInterrupted(stop.signal_name(), run.interrupted_at_ns, &summary);
    WriteJson(o.out + "/summary.json", summary);
    std::fprintf(stderr,
                 "\nskerry smooth: stopped by %s in the initial pass at t=%s s; its %zu keyframes "
                 "written to %s (summary.json says \"interrupted\")\n",
                 stop.signal_name(), FormatSeconds(run.interrupted_at_ns).c_str(),
                 run.records.size(), o.out.c_str());
    return stop.exit_status();
  }
  // What summary.json says of the dataset and the window pass is taken now, and the batch gets
  // only the states and the first covariance: the window's records (2 kB a keyframe, with their
  // covariances) are gone before the batch builds its graph, and so is the ground truth (64
  // bytes a pose; read again for the batch's figures); the batch lets the IMU record and the
  // states go once its graph is built (memory peaks in its solve).
  const nlohmann::json dataset_json = DatasetJson(data);
  const nlohmann::json window_stats = WindowStatsJson(run);
  auto t_evaluate = std::chrono::steady_clock::now();
  const nlohmann::json window_accuracy = AccuracyJson(data, run.records);
  double evaluate_s = SecondsSince(t_evaluate);
  BatchStart start = BatchStartOf(run.records);
  const TimeNs window_end_ns = run.records.back().state.t_ns;
  std::vector<EstimateRecord>().swap(run.records);
  std::vector<StampedPose>().swap(data.groundtruth);
  if (!o.quiet) std::printf("  batch solve over %zu keyframes...\n", start.states.size());
  const auto t_batch = std::chrono::steady_clock::now();
  const BatchResult batch =
      SmoothBatch(&data, config, std::move(start), run.decisions, run.sensors, stop.flag());
  const double batch_s = SecondsSince(t_batch);
  const auto t_write = std::chrono::steady_clock::now();
  WriteEstimateFiles(o.out, batch.records);
  // The batch's decisions beside the frontends' figures (the blocks as the batch made them).
  WriteBlocksCsv(o.out + "/blocks.csv", run.sensors, batch.sensor_decisions);
  const double write_s = SecondsSince(t_write);
  if (!data.groundtruth_path.empty()) {
    const auto t_load = std::chrono::steady_clock::now();
    data.groundtruth = ReadTum(data.groundtruth_path);
    load_s += SecondsSince(t_load);
  }
  nlohmann::json summary;
  summary["command"] = "smooth";
  summary["dataset"] = dataset_json;
  if (o.until_s) summary["until_s"] = *o.until_s;  // the data were cut there
  summary["configuration"] = {{"name", config.name}, {"yaml", ToYaml(config)}};
  summary["solver"] = {{"keyframes", batch.records.size()},
                       {"iterations", batch.iterations},
                       {"usable", batch.usable},
                       {"gnss_used", batch.gnss_used},
                       {"gnss_rejected_after_solve", batch.gnss_rejected_after_solve},
                       {"sensors", BatchSensorsJson(run.sensors.sensors, batch)},
                       {"ceres", batch.ceres_report},
                       {"initial_window", window_stats}};
  AddStatusJson(run, &summary);  // the initial window's verdict and events
  t_evaluate = std::chrono::steady_clock::now();
  summary["accuracy"] = AccuracyJson(data, batch.records);
  evaluate_s += SecondsSince(t_evaluate);
  summary["accuracy_window"] = window_accuracy;
  summary["timing"] = {{"load_s", load_s},
                       {"window_s", run.wall_s},
                       {"batch_s", batch_s},
                       {"batch_solve_s", batch.solve_s},
                       {"covariance_s", batch.covariance_s},
                       {"write_s", write_s},
                       {"evaluate_s", evaluate_s},
                       {"total_s", SecondsSince(t_start)},
                       {"data_s", run.data_s}};
  if (batch.interrupted) {
    summary["estimates"] = "batch iterate when stopped (not converged)";
    MarkInterrupted(stop.signal_name(), window_end_ns, &summary);
  }
  if (!batch.extrinsics.empty()) {
    std::vector<ExtrinsicEstimate> calibrated;
    for (const ExtrinsicEstimate& x : batch.extrinsics) {
      if (run.sensors.sensors.at(x.sensor).calibrate) calibrated.push_back(x);
    }
    if (!calibrated.empty())
      summary["extrinsics"] = ExtrinsicsJson(run.sensors.sensors, calibrated);
  }
  if (!batch.parameters.empty()) {
    summary["sensor_parameters"] = SensorParametersJson(run.sensors.sensors, batch.parameters);
  }
  if (batch.gyro_calibration.estimated) {
    summary["gyro_calibration"] = GyroCalibrationJson(batch.gyro_calibration, data.imu);
  }
  WriteJson(o.out + "/summary.json", summary);
  if (batch.interrupted) {
    std::fprintf(stderr,
                 "\nskerry smooth: stopped by %s in the batch solve after %d iterations; its "
                 "iterate (not converged) written to %s (summary.json says \"interrupted\")\n",
                 stop.signal_name(), batch.iterations, o.out.c_str());
    return stop.exit_status();
  }
  if (!o.quiet) {
    std::printf("  batch: %d iterations, %.1f s solve, %.2f s covariances\n", batch.iterations,
                batch.solve_s, batch.covariance_s);
    PrintAccuracy(summary["accuracy"]);
    std::printf("results in %s (trajectory.tum, states.csv, covariances.csv, summary.json)\n",
                o.out.c_str());
  }
  return 0;
}

int Evaluate(const EvaluateOptions& o) {
  std::vector<EstimateRecord> est;
  const std::filesystem::path p(o.estimate);
  // A run's states.csv (header `t,px,...`) also ends in .csv; any other .csv is EuRoC.
  if (o.estimate_format.empty() && p.extension() == ".csv" && IsStatesCsv(o.estimate)) {
    est = ReadEstimate(o.estimate, (p.parent_path() / "covariances.csv").string());
  } else {
    const TrajectoryFormat format = TrajectoryFormatFor(o.estimate, o.estimate_format);
    for (const StampedPose& pose : ReadTrajectory(o.estimate, format)) {
      EstimateRecord r;
      r.state.t_ns = pose.t_ns;
      r.state.p_w_b = pose.p_w_b;
      r.state.q_w_b = pose.q_w_b;
      est.push_back(r);
    }
  }
  const std::vector<StampedPose> gt =
      ReadTrajectory(o.groundtruth, TrajectoryFormatFor(o.groundtruth, o.groundtruth_format));
  const std::vector<GnssEvent> events =
      o.events.empty() ? std::vector<GnssEvent>() : ReadEventsCsv(o.events);
  const EvaluationResult ev = skerry::Evaluate(est, gt, o.rpe_delta_s);
  const nlohmann::json acc = AccuracyJson(ev, events);
  std::printf("evaluated %zu epochs (%d outside the ground truth)\n", ev.epochs.size(),
              ev.unmatched);
  std::printf(
      "  ATE (no alignment): 3-D RMSE %.3f m, horizontal RMSE %.3f m, vertical RMSE %.3f m\n",
      ev.position3d.rmse, ev.horizontal.rmse, ev.vertical.rmse);
  std::printf("  per axis RMSE: east %.3f, north %.3f, up %.3f m\n", ev.east.rmse, ev.north.rmse,
              ev.up.rmse);
  std::printf("  heading RMSE %.3f deg, roll/pitch RMSE %.3f deg\n", ev.heading_deg.rmse,
              ev.roll_pitch_deg.rmse);
  std::printf("  RPE over %.1f s: %.3f m, %.3f deg (RMSE)\n", ev.rpe_delta_s, ev.rpe_trans_m.rmse,
              ev.rpe_rot_deg.rmse);
  if (ev.nees_count > 0) {
    const auto b = AneesBounds(3, ev.nees_effective_count);
    std::printf(
        "  position ANEES %.2f, 95%% bounds [%.2f, %.2f] (%d epochs, worth %.0f independent "
        "ones)\n",
        ev.anees_pos, b.first, b.second, ev.nees_count, ev.nees_effective_count);
  }
  nlohmann::json out = acc;
  if (o.from_s || o.to_s) {
    const TimeNs from_given = o.from_s ? CommandLineTime(*o.from_s, "--from") : 0;
    const TimeNs to_given = o.to_s ? CommandLineTime(*o.to_s, "--to") : 0;
    if (ev.epochs.empty()) {
      throw InputError(o.estimate, 0, "--from", "no estimate lies inside the ground truth");
    }
    const TimeNs from = o.from_s ? from_given : ev.epochs.front().t_ns;
    const TimeNs to = o.to_s ? to_given : ev.epochs.back().t_ns;
    SpanSummary s;
    try {
      s = SummariseSpan(ev, from, to, o.edge_s);
    } catch (const std::invalid_argument& e) {
      throw InputError(o.estimate, 0, "--from/--to", e.what());
    }
    std::printf("  span %.1f-%.1f s (%d epochs): horizontal mean %.3f m, max %.3f m, RMSE %.3f m\n",
                s.from_s, s.to_s, s.count, s.horizontal.mean, s.horizontal.max, s.horizontal.rmse);
    std::printf(
        "    first %.0f s mean %.3f m, last %.0f s mean %.3f m (x%.2f); heading RMSE %.4f deg\n",
        s.edge_s, s.first_mean_m, s.edge_s, s.last_mean_m, s.growth, s.heading_rmse_deg);
    if (s.nees_count > 0) {
      std::printf(
          "    horizontal ANEES %.2f [%.2f, %.2f], position ANEES %.2f [%.2f, %.2f] (95%% bounds, "
          "worth %.0f independent epochs)\n",
          s.anees_horizontal, s.bounds_horizontal.first, s.bounds_horizontal.second, s.anees_pos,
          s.bounds_pos.first, s.bounds_pos.second, s.nees_effective_count);
    }
    out["span"] = {
        {"from_s", s.from_s},
        {"to_s", s.to_s},
        {"epochs", s.count},
        {"horizontal_mean_m", s.horizontal.mean},
        {"horizontal_max_m", s.horizontal.max},
        {"horizontal_rmse_m", s.horizontal.rmse},
        {"edge_s", s.edge_s},
        {"first_mean_m", s.first_mean_m},
        {"last_mean_m", s.last_mean_m},
        {"growth", s.growth},
        {"heading_rmse_deg", s.heading_rmse_deg},
        {"nees_epochs", s.nees_count},
        {"anees_horizontal", s.anees_horizontal},
        {"anees_position", s.anees_pos},
        {"anees_horizontal_bounds", {s.bounds_horizontal.first, s.bounds_horizontal.second}},
        {"anees_position_bounds", {s.bounds_pos.first, s.bounds_pos.second}},
        {"nees_effective_count", s.nees_effective_count}};
  }
  if (!o.json_out.empty()) WriteJson(o.json_out, out);
  return 0;
}

namespace {

// UTC as 2026-08-03T04:47:01.360Z.
std::string FormatUtc(TimeNs t_ns) {
  const std::time_t seconds = static_cast<std::time_t>(t_ns / 1000000000);
  std::tm tm{};
  gmtime_r(&seconds, &tm);
  char text[32];
  std::strftime(text, sizeof(text), "%Y-%m-%dT%H:%M:%S", &tm);
  return fmt::format("{}.{:03d}Z", text, static_cast<int>(t_ns % 1000000000 / 1000000));
}

// A marine log (NMEA 0183, or NMEA 2000 as canboat JSON) into a dataset without IMU, with its
// account on stdout: what was read, used and refused, per source and kind what was kept.
int ImportMarineLog(const ImportOptions& o) {
  MarineDatasetOptions options;
  for (const std::string& s : o.sources) {
    const std::size_t eq = s.find('=');
    MarineKind kind;
    if (eq == std::string::npos || eq + 1 == s.size() || !ParseMarineKind(s.substr(0, eq), &kind)) {
      throw InputError(kCommandLine, 0, "--source",
                       s + ": expected KIND=SOURCE with KIND one of fix, heading, course, "
                           "attitude, rate_of_turn (e.g. fix=25, heading=HE)");
    }
    options.sources[kind] = s.substr(eq + 1);
  }
  const MarineLog log =
      o.format == "nmea0183" ? nmea0183::ReadLog(o.input) : nmea2000::ReadCanboatJson(o.input);
  MarineSelection selection;
  const Dataset data = MarineLogToDataset(log, options, &selection);
  PrepareOutputFolder(o.out, DatasetFiles(), o.overwrite);
  WriteDataset(data, o.out);
  const TrackFigures track = FixTrackFigures(data.gnss_fixes);
  std::printf("imported %s %s (%s):\n", o.format.c_str(), o.input.c_str(),
              o.format == "nmea0183" ? "sentences" : "records");
  std::printf("%s", DescribeStats(log.stats).c_str());
  for (const auto& [kind, sel] : selection) {
    if (sel.records_by_source.empty()) {
      std::printf("  %s: none\n", MarineKindName(kind));
      continue;
    }
    std::string sources;
    for (const auto& [source, n] : sel.records_by_source) {
      sources += fmt::format("{}{} x{}", sources.empty() ? "" : ", ", source, n);
    }
    std::printf(
        "  %s: kept %d from source %s (sources: %s); dropped %d of other sources, %d at "
        "a time already taken\n",
        MarineKindName(kind), sel.kept, sel.source.c_str(), sources.c_str(), sel.other_sources,
        sel.duplicates);
  }
  // Where the sigmas of the fixes kept came from (the first of each time, as kept).
  std::map<std::string, int> sigma_sources;
  TimeNs last_t = std::numeric_limits<TimeNs>::min();
  for (const MarineFix& f : log.fixes) {
    if (f.source != selection[MarineKind::kFix].source || f.t_ns <= last_t) continue;
    last_t = f.t_ns;
    ++sigma_sources[FixSigmaSourceName(f.sigma_source)];
  }
  std::string sigmas;
  for (const auto& [name, n] : sigma_sources) {
    sigmas += fmt::format("{}{} {}", sigmas.empty() ? "" : ", ", name, n);
  }
  const TimeNs t0 = data.gnss_fixes.front().t_ns, t1 = data.gnss_fixes.back().t_ns;
  std::printf("  fixes: %d from %s to %s UTC (%.1f s), %.2f Hz, track %.1f m; sigmas: %s\n",
              track.fixes, FormatUtc(t0).c_str(), FormatUtc(t1).c_str(), track.span_s,
              track.rate_hz, track.length_m, sigmas.c_str());
  std::printf("dataset '%s' (no IMU) written to %s\n", data.name.c_str(), o.out.c_str());
  return 0;
}

}  // namespace

int Import(const ImportOptions& o) {
  if (!o.sources.empty() && o.format != "nmea0183" && o.format != "nmea2000") {
    throw InputError(kCommandLine, 0, "--source",
                     "chooses the source of a marine log's records: --format nmea0183 or "
                     "nmea2000 only");
  }
  if (o.format == "nmea0183" || o.format == "nmea2000") {
    if (o.fixes_rate_hz != 0.0) {
      throw InputError(kCommandLine, 0, "--fixes-rate",
                       "fixes from ground truth are made for --format euroc only (" + o.format +
                           " has its own GNSS)");
    }
    return ImportMarineLog(o);
  }
  Dataset data;
  const bool fixes = o.fixes_rate_hz != 0.0;
  if (fixes) {
    if (!(o.fixes_rate_hz > 0.0 && o.fixes_rate_hz <= 1000.0)) {
      throw InputError(kCommandLine, 0, "--fixes-rate",
                       fmt::format("{} Hz: expected a rate in (0, 1000] Hz", o.fixes_rate_hz));
    }
    if (!(o.fixes_sigma_m > 0.0 && std::isfinite(o.fixes_sigma_m))) {
      throw InputError(kCommandLine, 0, "--fixes-sigma",
                       fmt::format("{} m: expected a noise sigma > 0", o.fixes_sigma_m));
    }
    if (o.format != "euroc") {
      throw InputError(kCommandLine, 0, "--fixes-rate",
                       "fixes from ground truth are made for --format euroc only (" + o.format +
                           " has its own GNSS)");
    }
  }
  if (o.format == "euroc") {
    data = ImportEuroc(o.input);
    if (fixes && data.groundtruth.empty()) {
      throw InputError(o.input, 0, "--fixes-rate",
                       "the sequence has no ground truth (mav0/state_groundtruth_estimate0/"
                       "data.csv) to make fixes from");
    }
    if (fixes) {
      AddFixesFromGroundTruth(o.fixes_rate_hz, o.fixes_sigma_m, o.seed, &data);
    }
  } else if (o.format == "husky") {
    data = ImportHusky(o.input);
  } else {
    throw InputError(kCommandLine, 0, "--format",
                     "expected euroc, husky, nmea0183 or nmea2000 (canboat JSON)");
  }
  PrepareOutputFolder(o.out, DatasetFiles(), o.overwrite);
  WriteDataset(data, o.out);
  std::printf("imported %s: %zu IMU samples, %zu GNSS fixes, %zu ground-truth poses -> %s\n",
              o.format.c_str(), data.imu_samples.size(), data.gnss_fixes.size(),
              data.groundtruth.size(), o.out.c_str());
  return 0;
}

}  // namespace skerry::cli
