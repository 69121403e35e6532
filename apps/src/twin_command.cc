#include "twin_command.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "output_folder.h"
#include "run_outputs.h"
#include "skerry/core/input_error.h"
#include "skerry/eval/hellinger_floor.h"
#include "skerry/io/dataset.h"
#include "skerry/io/estimate_io.h"
#include "skerry/sim/spline_motion.h"
#include "skerry/sim/twin.h"
#include "skerry/solvers/batch_smoother.h"
#include "skerry/solvers/pipeline.h"
#include "skerry/twin/gnss_statistics.h"
#include "skerry/twin/gnss_track.h"
#include "skerry/twin/twin_calibration.h"
#include "skerry/twin/twin_fidelity.h"
#include "skerry/twin/twin_identification.h"
#include "skerry/twin/twin_yaml.h"

namespace skerry::cli {
namespace {

struct TwinOptions {
  std::string dataset;
  std::string out;
  std::string config = "default";
  std::int64_t seed = 1;
  int twins = 19;
  double alpha = 0.1;
  std::string model;  ///< twin.yaml whose `model:` replaces the identified one
  std::string imu_noise = "rest";
  double min_rest_s = 10.0;
  int jobs = 0;
  bool calibrate = false;
  int calibration_twins = 4;
  bool overwrite = false;
  bool quiet = false;
};

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The window over a dataset, IMU and GNSS only; a run that diverged or never started is an
// error naming the dataset.
std::vector<EstimateRecord> WindowRecords(const Dataset& data,
                                          const EstimatorConfig& config,
                                          const std::string& what) {
  const WindowRun run = RunWindow(data, config);
  if (run.diverged) {
    throw InputError(what, 0, "", "the estimator diverged on it: " + run.failure);
  }
  if (run.records.empty()) throw InputError(what, 0, "", "the estimator never started on it");
  return run.records;
}

// A run of the test as a run folder `skerry report` and `skerry fidelity` read: the estimates,
// and a summary.json naming the twin as its dataset (whose ground truth is the batch through the
// recording, the truth of every run here).
void WriteRunFolder(const std::string& dir,
                    const std::vector<EstimateRecord>& records,
                    const std::string& name,
                    const Dataset& twin,
                    const std::string& twin_dir,
                    const std::string& config) {
  std::filesystem::create_directories(dir);
  WriteEstimateFiles(dir, records);
  nlohmann::json summary;
  summary["command"] = "twin";
  summary["dataset"] = DatasetJson(twin);
  summary["dataset"]["directory"] = std::filesystem::absolute(twin_dir).lexically_normal().string();
  summary["configuration"] = {{"name", name}, {"estimator", config}};
  WriteJson(dir + "/summary.json", summary);
}

// How far the recording is from being one more twin, over the blocks a twin should reproduce
// (the full state saturates and repeats them): per block, the recording's mean AHED to the twins
// less the twins' mean AHED to each other, squared, averaged over the blocks. Zero in
// expectation for a perfect twin. Minimising the recording's AHED alone would favour twins with
// too little noise, which come closer to everything, each other most of all.
double CalibrationObjective(const std::vector<EstimateRecord>& real,
                            const std::vector<std::vector<EstimateRecord>>& twins) {
  const TwinFidelity f = CompareWithTwins(real, twins);
  const FidelityBlock blocks[] = {FidelityBlock::kPosition, FidelityBlock::kHeading,
                                  FidelityBlock::kAttitude, FidelityBlock::kVelocity,
                                  FidelityBlock::kBiases};
  double sum = 0.0;
  for (FidelityBlock b : blocks) {
    const TwinFidelityBlock& x = f.blocks[static_cast<int>(b)];
    sum += (x.real_ahed - x.twins_ahed) * (x.real_ahed - x.twins_ahed);
  }
  return sum / 5.0;
}

void PrintFidelity(const char* title, const TwinFidelity& f, double alpha) {
  std::printf("  %s", title);
  if (f.failed_twins > 0) {
    std::printf(" (%d twins left out: the estimator gave up on them)", f.failed_twins);
  }
  std::printf(" (coverage %.1f %%: epochs with both the recording's and a twin's estimate):\n",
              100.0 * f.coverage);
  std::printf("  %-9s %9s %9s %9s | %9s %9s %9s | %6s %5s %6s  %s\n", "block", "real-twin",
              "meandiff", "covdiff", "twin-twin", "sd", "max", "floor", "p", "z", "verdict");
  for (int b = 0; b < kNumFidelityBlocks; ++b) {
    const TwinFidelityBlock& x = f.blocks[b];
    std::printf("  %-9s %9.3f %9.3f %9.3f | %9.3f %9.3f %9.3f | %6.3f %5.2f %6.2f  %s\n",
                FidelityBlockName(static_cast<FidelityBlock>(b)), x.real_ahed, x.real_meandiff,
                x.real_covdiff, x.twins_ahed, x.twins_sd, x.twins_max, x.floor, x.p_value, x.z,
                x.indistinguishable ? "indistinguishable" : "twin differs");
  }
  std::printf(
      "  (AHED of the recording's run against each twin's, and between twins; p: the two-sided "
      "rank of the recording among all %d runs by mean distance to the others, rejected at "
      "p <= %.2f; z: that distance against the twins'; docs/twin.md)\n",
      f.twins + 1, alpha);
}

void PrintIdentified(const char* name, const IdentifiedValue& v, const char* unit, double scale) {
  if (v.identified) {
    std::printf("    %-34s %10.4g +- %-9.2g %s\n", name, v.value * scale, v.sigma * scale, unit);
  } else {
    std::printf("    %-34s %10s\n", name, "(not identified)");
  }
}

// Where the twin comes from; with --model, that file's model replaces the identified one. Writes
// identification/gnss_residuals.csv.
TwinProvenance Provenance(const TwinOptions& o,
                          const std::string& config,
                          size_t keyframes,
                          const sim::SplineMotion& truth,
                          TwinIdentification* id) {
  TwinProvenance prov;
  prov.recording = std::filesystem::absolute(o.dataset).lexically_normal().string();
  prov.config = config;
  prov.truth_keyframes = static_cast<int>(keyframes);
  prov.knot_s = truth.knot_s();
  prov.truth_start_s = NsToSeconds(truth.start_ns());
  prov.truth_end_s = NsToSeconds(truth.end_ns());
  prov.seed = static_cast<std::uint64_t>(o.seed);
  if (!o.model.empty()) {
    id->model = ReadTwinModel(o.model);
    prov.model_source = std::filesystem::absolute(o.model).lexically_normal().string();
  }
  std::filesystem::create_directories(o.out + "/identification");
  WriteGnssResidualsCsv(o.out + "/identification/gnss_residuals.csv", *id);
  return prov;
}

// A recording without IMU (a marine logger's file): the truth is a maximum-likelihood track
// through the fixes, the twin re-simulates the GNSS only, and the test compares statistics of
// the fixes, since no estimator runs on GNSS alone.
int RunGnssOnlyTwin(const TwinOptions& o, Dataset real, std::chrono::steady_clock::time_point t0) {
  if (real.gnss_fixes.size() < 30) {
    throw InputError(real.gnss_path, 0, "", "a twin needs at least 30 fixes");
  }
  PrepareOutputFolder(o.out, DatasetFiles(), o.overwrite);
  // The track is the antenna's: the antenna is the body origin of the twin.
  real.gnss.p_b_g.setZero();
  const GnssTrack track = SmoothGnssTrack(real.gnss_fixes);
  const sim::SplineMotion truth(track.states);
  TwinIdentification id = IdentifyTwin(real, truth);
  // Residuals against a track through the same fixes understate their white noise (the track
  // follows part of it); the track's likelihood does not. A latency cannot be told from motion.
  id.model.gnss.white_sigma_horizontal_m = track.white_sigma_horizontal_m.value;
  id.model.gnss.white_sigma_vertical_m = track.white_sigma_vertical_m.value;
  id.model.gnss.latency_s = 0.0;
  id.model.gnss.drift_sigma_horizontal_m = id.model.gnss.drift_sigma_vertical_m = 0.0;
  const TwinProvenance prov = Provenance(o, "(none: no IMU)", track.states.size(), truth, &id);
  if (!o.quiet) {
    std::printf("skerry twin: '%s' has no IMU: its GNSS alone, along a track through its fixes\n",
                real.name.c_str());
    std::printf("  track: %zu fixes, %.1f s; white noise (maximum likelihood):\n",
                track.states.size(), NsToSeconds(truth.end_ns() - truth.start_ns()));
    PrintIdentified("horizontal", track.white_sigma_horizontal_m, "m", 1.0);
    PrintIdentified("vertical", track.white_sigma_vertical_m, "m", 1.0);
    std::printf("    acceleration PSD %.3g m^2/s^3 horizontal, %.3g vertical\n",
                track.accel_psd_horizontal, track.accel_psd_vertical);
    std::printf("    gross-error episodes: %d (%d fixes)\n", id.gross.episodes, id.gross.fixes);
    if (id.gnss_timing) {
      std::printf("  gnss %.2f Hz, jitter %.2g s, %d gaps (longest %.2f s), %.2f%% dropped\n",
                  id.gnss_timing->rate_hz, id.gnss_timing->period_jitter_s, id.gnss_timing->gaps,
                  id.gnss_timing->longest_gap_s, 100.0 * id.gnss_timing->dropout_share);
    }
  }
  const GnssStatistics real_stats = MeasureGnssStatistics(real.gnss_fixes);
  auto compare = [&](const sim::TwinModel& model, std::uint64_t first_seed, int count) {
    std::vector<GnssStatistics> twins;
    for (int k = 0; k < count; ++k) {
      twins.push_back(MeasureGnssStatistics(
          sim::SimulateTwin(real, truth, model, first_seed + static_cast<std::uint64_t>(k))
              .gnss_fixes));
    }
    return CompareGnssStatistics(real_stats, twins, o.alpha);
  };
  // Calibration: the model whose fixes' statistics lie closest to the recording's.
  std::unique_ptr<TwinCalibration> calibration;
  const sim::TwinModel identified = id.model;
  std::vector<StatisticComparison> before;
  if (o.calibrate) {
    std::vector<TwinParameter> params;
    for (TwinParameter& p : CalibratableParameters(real, track.white_sigma_horizontal_m.value)) {
      if (p.name.find("vertical") != std::string::npos && !real_stats.vertical_identified) continue;
      params.push_back(p);
    }
    const int n_cal = std::max(o.calibration_twins, 8);
    TwinCalibrationOptions copt;
    copt.rounds = 3;  // a model costs milliseconds here
    // Each statistic in units of the identified model's twins' spread, held fixed.
    std::vector<double> scales;
    for (const StatisticComparison& c : compare(id.model, prov.seed + 1000, n_cal)) {
      scales.push_back(c.twins_sd);
    }
    calibration = std::make_unique<TwinCalibration>(CalibrateTwin(
        id.model, params,
        [&](const sim::TwinModel& m) {
          return StatisticsDistance(compare(m, prov.seed + 1000, n_cal), scales);
        },
        copt));
    id.model = calibration->model;
    if (!o.quiet) {
      std::printf(
          "  calibration (%d twins per model): distance of the statistics %.2f -> %.2f in "
          "%d evaluations\n",
          n_cal, calibration->objective_before, calibration->objective_after,
          calibration->evaluations);
      for (const TwinCalibrationStep& st : calibration->steps) {
        if (st.kept) {
          std::printf("    %-40s -> %.4g (%.3f)\n", st.parameter.c_str(), st.value, st.objective);
        }
      }
    }
  }
  const Dataset twin = sim::SimulateTwin(real, truth, id.model, prov.seed);
  WriteDataset(twin, o.out);
  std::vector<StatisticComparison> stats;
  auto print = [&](const char* title, const std::vector<StatisticComparison>& table) {
    std::printf("  %s: the fixes' statistics, the recording's among %d twins':\n", title, o.twins);
    std::printf("  %-38s %10s | %10s %10s %10s %10s | %5s  %s\n", "statistic", "real", "twins",
                "sd", "min", "max", "p", "verdict");
    for (const StatisticComparison& c : table) {
      std::printf("  %-38s %10.4g | %10.4g %10.2g %10.4g %10.4g | %5.2f  %s\n", c.name.c_str(),
                  c.real, c.twins_mean, c.twins_sd, c.twins_min, c.twins_max, c.p_value,
                  c.indistinguishable ? "indistinguishable" : "twin differs");
    }
  };
  if (o.twins >= 2) {
    if (calibration) {
      before = compare(identified, prov.seed, o.twins);
      if (!o.quiet) print("identified model", before);
    }
    stats = compare(id.model, prov.seed, o.twins);
    if (!o.quiet) print(calibration ? "calibrated model" : "identified model", stats);
  }
  WriteTwinYaml(o.out + "/twin.yaml", real, id, prov, nullptr, nullptr, calibration.get(),
                calibration ? &identified : nullptr, &track, stats.empty() ? nullptr : &stats,
                before.empty() ? nullptr : &before);
  if (!o.quiet) {
    std::printf("twin written to %s (twin.yaml, identification/) in %.1f s\n", o.out.c_str(),
                Seconds(t0));
  }
  return 0;
}

int RunTwin(const TwinOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  if (o.twins == 1 || o.twins < 0 || o.twins > 99) {
    throw InputError("(command line)", 0, "--twins", "must be 0 (no fidelity check) or 2..99");
  }
  if (!(o.alpha > 0.0 && o.alpha < 1.0)) {
    throw InputError("(command line)", 0, "--alpha", "must be in (0, 1)");
  }
  if (o.imu_noise != "rest" && o.imu_noise != "residuals") {
    throw InputError("(command line)", 0, "--imu-noise", "must be rest or residuals");
  }
  const Dataset real = LoadDataset(o.dataset);
  if (!real.has_gnss) {
    throw InputError(o.dataset, 0, "sensors.gnss",
                     "skerry twin needs GNSS fixes to identify the receiver's model");
  }
  if (!real.has_imu) return RunGnssOnlyTwin(o, real, t0);
  const EstimatorConfig config = LoadPreset(o.config);
  PrepareOutputFolder(o.out, DatasetFiles(), o.overwrite);

  // --- The truth: the batch smoother's trajectory through the recording. ---------------------
  if (!o.quiet) {
    std::printf("skerry twin: '%s', config '%s'\n", real.name.c_str(), config.name.c_str());
  }
  const WindowRun pass = RunWindow(real, config);
  if (pass.diverged) throw InputError(o.dataset, 0, "", "the estimator diverged: " + pass.failure);
  if (pass.records.size() < 2) throw InputError(o.dataset, 0, "", "the estimator never started");
  const BatchResult batch = SmoothBatch(real, config, pass.records, pass.decisions, {});
  if (!batch.usable || batch.records.size() < 2) {
    throw InputError(o.dataset, 0, "", "the batch smoother gave no trajectory to twin along");
  }
  std::vector<NavState> states;
  for (const EstimateRecord& r : batch.records) states.push_back(r.state);
  const sim::SplineMotion truth(states);
  if (!o.quiet) {
    std::printf("  truth: batch over %zu keyframes (%d iterations), %.1f s of %.1f s recorded\n",
                states.size(), batch.iterations, NsToSeconds(truth.end_ns() - truth.start_ns()),
                NsToSeconds(real.imu_samples.back().t_ns - real.imu_samples.front().t_ns));
  }

  // --- Identification. ------------------------------------------------------------------------
  TwinIdentifyOptions io;
  io.imu_noise = o.imu_noise;
  io.min_rest_s = o.min_rest_s;
  TwinIdentification id = IdentifyTwin(real, truth, io);
  const TwinProvenance prov = Provenance(o, config.name, states.size(), truth, &id);
  const std::string id_dir = o.out + "/identification";
  if (id.imu.allan) {
    WriteAllanCsv(id_dir + "/allan.csv", *id.imu.allan);
    WriteAllanSvg(id_dir + "/allan.svg", *id.imu.allan,
                  "Allan deviation of '" + real.name + "' at rest");
  }
  if (!o.quiet) {
    std::printf("  IMU (white noise from the %s", id.imu.noise_source.c_str());
    if (id.imu.allan) {
      std::printf("; longest rest %.1f s from t=%.1f s, Allan deviation in identification/",
                  id.imu.allan->rest.duration_s,
                  NsToSeconds(real.imu_samples[id.imu.allan->rest.begin].t_ns -
                              real.imu_samples.front().t_ns));
    } else {
      std::printf("; no rest of %.0f s or more", o.min_rest_s);
    }
    std::printf("):\n");
    if (id.imu.allan) {
      PrintIdentified("gyro white noise (rest)", id.imu.allan->gyro_combined.white_density,
                      "rad/s/sqrt(Hz)", 1.0);
      PrintIdentified("accel white noise (rest)", id.imu.allan->accel_combined.white_density,
                      "m/s^2/sqrt(Hz)", 1.0);
    }
    PrintIdentified("gyro white noise (residuals)", id.imu.residual_gyro_density, "rad/s/sqrt(Hz)",
                    1.0);
    PrintIdentified("accel white noise (residuals)", id.imu.residual_accel_density,
                    "m/s^2/sqrt(Hz)", 1.0);
    PrintIdentified("gyro bias instability", id.imu.gyro_bias_instability, "rad/s", 1.0);
    PrintIdentified("accel bias instability", id.imu.accel_bias_instability, "m/s^2", 1.0);
    std::printf("    (dataset.yaml says gyro %.3g, accel %.3g)\n",
                real.imu.noise.gyro_noise_density_rad_s_sqrt_hz,
                real.imu.noise.accel_noise_density_m_s2_sqrt_hz);
    const GnssErrorModelFit& g = *id.gnss;
    std::printf("  GNSS (%zu fixes in the truth's span):\n", id.gnss_residuals.t_s.size());
    PrintIdentified("latency", g.latency_s, "s", 1.0);
    PrintIdentified("white sigma horizontal", g.white_sigma_horizontal_m, "m", 1.0);
    PrintIdentified("white sigma vertical", g.white_sigma_vertical_m, "m", 1.0);
    PrintIdentified("drift sigma horizontal", g.drift_sigma_horizontal_m, "m", 1.0);
    PrintIdentified("drift sigma vertical", g.drift_sigma_vertical_m, "m", 1.0);
    PrintIdentified("drift correlation time", g.drift_tau_s, "s", 1.0);
    std::printf("    gross-error episodes: %d (%d fixes)\n", id.gross.episodes, id.gross.fixes);
    if (id.gross.episodes > 0) {
      PrintIdentified("  rate", id.gross.rate_per_hour, "per hour", 1.0);
      PrintIdentified("  mean length", id.gross.mean_duration_s, "s", 1.0);
      PrintIdentified("  RMS horizontal offset", id.gross.offset_horizontal_m, "m", 1.0);
    }
    if (id.heading.samples > 0) PrintIdentified("heading sigma", id.heading.sigma_deg, "deg", 1.0);
    for (const std::optional<StreamTiming>* t : {&id.imu_timing, &id.gnss_timing}) {
      if (!*t) continue;
      std::printf("  %-4s %.2f Hz, jitter %.2g s, %d gaps (longest %.2f s), %.2f%% dropped\n",
                  (*t)->name.c_str(), (*t)->rate_hz, (*t)->period_jitter_s, (*t)->gaps,
                  (*t)->longest_gap_s, 100.0 * (*t)->dropout_share);
    }
  }

  // --- The estimator on the recording (over the truth's span) and on twins of given seeds. ---
  const int jobs =
      std::max(1, o.jobs > 0 ? o.jobs : static_cast<int>(std::thread::hardware_concurrency()));
  const Dataset cropped = CropToTruth(real, truth);
  // The window on twins of the given seeds. A twin the estimator gives up on (diverged, never
  // started) is left out and named in `failed`: the recording's run held, so that is a finding
  // about the model, not an error of the command.
  struct TwinRuns {
    std::vector<std::vector<EstimateRecord>> runs;  // of the twins that held, in seed order
    std::vector<std::uint64_t> seeds;               // their seeds
    std::vector<std::string> failed;                // "seed N: why"
  };
  auto run_twins = [&](const sim::TwinModel& model, const std::vector<std::uint64_t>& seeds) {
    std::vector<std::vector<EstimateRecord>> runs(seeds.size());
    std::vector<std::string> errors(seeds.size());
    std::atomic<size_t> next{0};
    auto worker = [&]() {
      for (size_t i = next++; i < seeds.size(); i = next++) {
        try {
          runs[i] = WindowRecords(sim::SimulateTwin(real, truth, model, seeds[i]), config,
                                  "twin of seed " + std::to_string(seeds[i]));
        } catch (const InputError& e) {
          errors[i] = e.what();
        }
      }
    };
    std::vector<std::thread> pool;
    for (int j = 0; j < std::min<int>(jobs, static_cast<int>(seeds.size())); ++j) {
      pool.emplace_back(worker);
    }
    for (std::thread& t : pool) t.join();
    TwinRuns out;
    for (size_t i = 0; i < seeds.size(); ++i) {
      if (errors[i].empty()) {
        out.runs.push_back(std::move(runs[i]));
        out.seeds.push_back(seeds[i]);
      } else {
        out.failed.push_back(errors[i]);
      }
    }
    return out;
  };
  std::vector<EstimateRecord> real_run;
  if (o.twins >= 2 || o.calibrate) real_run = WindowRecords(cropped, config, o.dataset);
  // Tens of twin runs would repeat the estimator's warnings (re-acquisitions, restarts) by the
  // hundred; the runs' outcome is what the test reports. -v keeps them.
  if (spdlog::get_level() == spdlog::level::warn) spdlog::set_level(spdlog::level::err);

  // --- Calibration: the model whose twins come closest to the recording. --------------------
  std::unique_ptr<TwinFidelity> before;
  std::unique_ptr<TwinCalibration> calibration;
  const sim::TwinModel identified = id.model;
  if (o.calibrate) {
    std::vector<std::uint64_t> seeds;
    for (int k = 0; k < o.calibration_twins; ++k) seeds.push_back(prov.seed + 1000 + k);
    auto objective = [&](const sim::TwinModel& model) {
      const TwinRuns t = run_twins(model, seeds);
      // A model whose twins the estimator gives up on is not the recording's.
      if (!t.failed.empty() || t.runs.size() < 2) return 1e9;
      return CalibrationObjective(real_run, t.runs);
    };
    if (!o.quiet) {
      std::printf(
          "  calibrating: %d twins per model, objective the mean squared gap between "
          "real-vs-twin and twin-vs-twin AHED over position, heading, attitude, velocity and "
          "biases...\n",
          o.calibration_twins);
      std::fflush(stdout);
    }
    double reference = 0.5;
    if (id.gnss) reference = std::max(id.gnss->white_sigma_horizontal_m.value, 0.05);
    calibration = std::make_unique<TwinCalibration>(
        CalibrateTwin(id.model, CalibratableParameters(real, reference), objective));
    id.model = calibration->model;
    if (!o.quiet) {
      std::printf("  calibration: objective %.5f -> %.5f in %d evaluations\n",
                  calibration->objective_before, calibration->objective_after,
                  calibration->evaluations);
      for (const TwinCalibrationStep& st : calibration->steps) {
        if (st.kept)
          std::printf("    %-40s -> %.4g (%.4f)\n", st.parameter.c_str(), st.value, st.objective);
      }
    }
  }

  // --- The twin itself. -----------------------------------------------------------------------
  const Dataset twin = sim::SimulateTwin(real, truth, id.model, prov.seed);
  WriteDataset(twin, o.out);

  // --- How far it is from the recording, against the spread between twins. -------------------
  std::unique_ptr<TwinFidelity> fidelity;
  if (o.twins >= 2) {
    std::vector<std::uint64_t> seeds;
    for (int k = 0; k < o.twins; ++k) seeds.push_back(prov.seed + k);
    if (!o.quiet) {
      std::printf("  fidelity: the window on the recording and on %d twins (%d in parallel)\n",
                  o.twins, jobs);
    }
    // The test over the twins the estimator held; those it gave up on are named.
    auto test = [&](const sim::TwinModel& model, const char* title, TwinRuns* kept) {
      *kept = run_twins(model, seeds);
      for (const std::string& f : kept->failed) {
        std::fprintf(stderr, "skerry twin: %s: %s (left out of the test)\n", title, f.c_str());
      }
      if (kept->runs.size() < 2) {
        throw std::runtime_error("skerry twin: the estimator gave up on " +
                                 std::to_string(kept->failed.size()) + " of " +
                                 std::to_string(seeds.size()) + " twins of the " + title +
                                 ", which it did not on the recording: the twin differs");
      }
      auto f = std::make_unique<TwinFidelity>(CompareWithTwins(real_run, kept->runs, o.alpha));
      f->failed_twins = static_cast<int>(kept->failed.size());
      if (!o.quiet) PrintFidelity(title, *f, o.alpha);
      return f;
    };
    TwinRuns kept;
    if (calibration) before = test(identified, "identified model", &kept);
    fidelity = test(id.model, calibration ? "calibrated model" : "identified model", &kept);
    WriteRunFolder(o.out + "/fidelity/real", real_run, "recording", twin, o.out, config.name);
    WriteFidelityOverTimeCsv(o.out + "/fidelity/over_time.csv", *fidelity);
    for (size_t i = 0; i < kept.runs.size(); ++i) {
      const std::string seed = std::to_string(kept.seeds[i]);
      WriteRunFolder(o.out + "/fidelity/twin-" + seed, kept.runs[i], "twin of seed " + seed, twin,
                     o.out, config.name);
    }
  }
  WriteTwinYaml(o.out + "/twin.yaml", real, id, prov, fidelity.get(), before.get(),
                calibration.get(), &identified);
  if (!o.quiet) {
    std::printf("twin written to %s (twin.yaml, identification/%s) in %.1f s\n", o.out.c_str(),
                fidelity ? ", fidelity/" : "", Seconds(t0));
  }
  return 0;
}

}  // namespace

Subcommand AddTwinCommand(CLI::App& app) {
  auto o = std::make_shared<TwinOptions>();
  CLI::App* cmd = app.add_subcommand(
      "twin",
      "A digital twin of a recording: sensor models identified from it, the recording "
      "re-simulated along its batch trajectory, and the twin's distance from it (docs/twin.md)");
  cmd->add_option("--dataset", o->dataset, "The real recording (a dataset folder)")->required();
  cmd->add_option("--out", o->out, "The twin's dataset folder")->required();
  cmd->add_option("--config", o->config, "Estimator preset or YAML for the batch and the runs")
      ->capture_default_str();
  cmd->add_option("--seed", o->seed, "The twin's seed; the fidelity twins take the next ones")
      ->capture_default_str()
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--twins", o->twins,
                  "Twins of consecutive seeds run for the fidelity test (0: none)")
      ->capture_default_str();
  cmd->add_option("--alpha", o->alpha, "Level of the fidelity test")->capture_default_str();
  cmd->add_option("--model", o->model,
                  "A twin.yaml whose model: section replaces the identified model");
  cmd->add_option("--imu-noise", o->imu_noise,
                  "IMU white noise of the twin: rest (Allan deviation, else residuals) or "
                  "residuals")
      ->capture_default_str();
  cmd->add_option("--min-rest", o->min_rest_s, "Shortest rest (s) used for the Allan deviation")
      ->capture_default_str();
  cmd->add_flag("--calibrate", o->calibrate,
                "Search the model for the twin closest to the recording (docs/twin.md)");
  cmd->add_option("--calibration-twins", o->calibration_twins,
                  "Twins per model tried by --calibrate")
      ->capture_default_str()
      ->check(CLI::Range(2, 50));
  cmd->add_option("-j,--jobs", o->jobs, "Parallel estimator runs (default: cores)");
  cmd->add_flag("--overwrite", o->overwrite, "Replace a dataset already in --out");
  cmd->add_flag("-q,--quiet", o->quiet, "No summary on the terminal");
  Subcommand s;
  s.app = cmd;
  s.run = [o]() { return RunTwin(*o); };
  return s;
}

}  // namespace skerry::cli
