#include "twin_command.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "config_variant.h"
#include "output_folder.h"
#include "run_outputs.h"
#include "seed_number.h"
#include "skerry/core/input_error.h"
#include "skerry/core/time.h"
#include "skerry/eval/hellinger_floor.h"
#include "skerry/io/dataset.h"
#include "skerry/io/estimate_io.h"
#include "skerry/sim/earth_field.h"
#include "skerry/sim/spline_motion.h"
#include "skerry/sim/twin.h"
#include "skerry/solvers/batch_smoother.h"
#include "skerry/solvers/pipeline.h"
#include "skerry/twin/drift_detection.h"
#include "skerry/twin/gnss_statistics.h"
#include "skerry/twin/gnss_track.h"
#include "skerry/twin/solve_pattern.h"
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
  std::uint64_t seed = 1;
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
  bool no_drift_limit = false;  ///< skip the measured drift detection limit
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
    std::printf(" (the estimator gave up on %d twins: replaced by further seeds)", f.failed_twins);
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
  prov.seed = o.seed;
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
  // A receiver that solves once a period and propagates between (solve_pattern.h): a sawtooth
  // in the residuals. Then the white noise is the one about its lines.
  {
    std::vector<TimeNs> t;
    std::vector<Eigen::Vector2d> e;
    for (size_t i = 0; i < id.gnss_residuals.t_s.size(); ++i) {
      t.push_back(truth.start_ns() + SecondsToNs(id.gnss_residuals.t_s[i]));
      e.push_back(id.gnss_residuals.e_enu_m[i].head<2>());
    }
    id.solve_pattern = IdentifySolvePattern(t, e, id.gnss_gross);
    const SolvePattern& sp = *id.solve_pattern;
    if (sp.detected) {
      sim::TwinGnssModel& g = id.model.gnss;
      g.solve_period_s = sp.period_s;
      g.solve_phase_s = sp.phase_s;
      g.solve_offset_sigma_m = sp.offset_sigma_m.value;
      g.propagation_velocity_sigma_m_s = sp.propagation_velocity_sigma_m_s.value;
      if (sp.propagation_velocity_tau_s.identified) {
        g.propagation_velocity_tau_s = sp.propagation_velocity_tau_s.value;
      }
      g.white_sigma_horizontal_m = sp.white_sigma_horizontal_m.value;
    }
  }
  const TwinProvenance prov = Provenance(o, "(none: no IMU)", track.states.size(), truth, &id);
  const double solve_period_s = id.model.gnss.solve_period_s;  // --model's, with one
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
    const SolvePattern& sp = *id.solve_pattern;
    if (sp.detected) {
      std::printf(
          "  solve and propagate: a solution every %.2f s at phase %.3f s (jump ratio %.1f, "
          "z %.0f; correlation %.2f one period apart, %.2f half a period)\n",
          sp.period_s, sp.phase_s, sp.jump_ratio, sp.jump_z, sp.period_correlation,
          sp.half_period_correlation);
    } else {
      std::printf("  solve and propagate: %38s\n", "(not identified)");
    }
    PrintIdentified("white about its lines", sp.white_sigma_horizontal_m, "m", 1.0);
    PrintIdentified("offset at a solution", sp.offset_sigma_m, "m", 1.0);
    PrintIdentified("propagation velocity error", sp.propagation_velocity_sigma_m_s, "m/s", 1.0);
    PrintIdentified("its correlation time", sp.propagation_velocity_tau_s, "s", 1.0);
    if (id.gnss_timing) {
      std::printf("  gnss %.2f Hz, jitter %.2g s, %d gaps (longest %.2f s), %.2f%% dropped\n",
                  id.gnss_timing->rate_hz, id.gnss_timing->period_jitter_s, id.gnss_timing->gaps,
                  id.gnss_timing->longest_gap_s, 100.0 * id.gnss_timing->dropout_share);
    }
  }
  const GnssStatistics real_stats = MeasureGnssStatistics(real.gnss_fixes, solve_period_s);
  auto compare = [&](const sim::TwinModel& model, std::uint64_t first_seed, int count) {
    std::vector<GnssStatistics> twins;
    for (int k = 0; k < count; ++k) {
      twins.push_back(MeasureGnssStatistics(
          sim::SimulateTwin(real, truth, model, first_seed + static_cast<std::uint64_t>(k))
              .gnss_fixes,
          solve_period_s));
    }
    return CompareGnssStatistics(real_stats, twins, o.alpha);
  };
  // Calibration: the model whose fixes' statistics lie closest to the recording's.
  std::unique_ptr<TwinCalibration> calibration;
  const sim::TwinModel identified = id.model;
  std::vector<StatisticComparison> before;
  if (o.calibrate) {
    std::vector<TwinParameter> params;
    for (TwinParameter& p :
         CalibratableParameters(real, track.white_sigma_horizontal_m.value, solve_period_s > 0.0)) {
      if (p.name.find("vertical") != std::string::npos && !real_stats.vertical_identified) continue;
      params.push_back(p);
    }
    const int n_cal = std::max(o.calibration_twins, 8);
    TwinCalibrationOptions copt;
    copt.rounds = 3;  // a model costs milliseconds here
    // Each statistic in units of the identified model's twins' spread, held fixed.
    const std::vector<double> scales =
        StatisticsScales(compare(id.model, prov.seed + 1000, n_cal), real.gnss_fixes.size());
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

// How slow a GNSS drift the identification could see (drift_detection.h), into id->drift_detection
// and the unidentified drift sigmas; returns the seconds it took, and what could not be measured in
// `failures`.
// The batch through the same fixes takes whatever part of a slow GNSS error the IMU cannot
// tell from motion. A known Gauss-Markov error, of the white noise's size (well inside the
// quadratic part of the batch's losses, so the batch answers it linearly), is added to every
// fix at a few correlation times and the batch re-run; the change of the residuals against its
// new trajectory, over the added error, is the share that survives. The window pass is not
// re-run: its decisions are per fix index and stay valid, and the batch judges every fix again
// at its own solution (on the simulated harbour, re-running the window changed the gains in
// the third digit, and halving or doubling the added error changed them by under 5 %).
double MeasureDriftDetection(const TwinOptions& o,
                             const Dataset& real,
                             const sim::SplineMotion& truth,
                             const EstimatorConfig& config,
                             const WindowRun& pass,
                             const TwinIdentifyOptions& io,
                             TwinIdentification* id,
                             std::string* failures) {
  const auto t_limit = std::chrono::steady_clock::now();
  const GnssErrorModelFit& g = *id->gnss;
  std::vector<size_t> fix_index;
  const GnssResidualSeries before = GnssResidualsAgainstTruth(real, truth, &fix_index);
  // The fixes the error model was fitted to: those outside gross-error episodes.
  GnssResidualSeries clean;
  std::vector<long> clean_at(before.t_s.size(), -1);  // position in `before` -> in `clean`
  for (size_t i = 0; i < before.t_s.size(); ++i) {
    if (id->gnss_gross[i]) continue;
    clean_at[i] = static_cast<long>(clean.t_s.size());
    clean.t_s.push_back(before.t_s[i]);
    clean.e_enu_m.push_back(before.e_enu_m[i]);
    clean.v_enu_m_s.push_back(before.v_enu_m_s[i]);
  }
  std::vector<double> fix_t_s;
  for (const GnssFix& f : real.gnss_fixes) {
    fix_t_s.push_back(NsToSeconds(f.t_ns - real.gnss_fixes.front().t_ns));
  }
  const std::vector<double> taus =
      DriftProbeTaus(before.t_s.back() - before.t_s.front(), g.period_s);
  const double sigma_h = g.white_sigma_horizontal_m.value;
  const double sigma_v = g.white_sigma_vertical_m.value;
  const sim::EarthField earth(real.origin, real.earth);
  // Three realizations per correlation time, pooled (MeasureBatchGain): one realization of a
  // slow error has few swings over the span, and its gain alone scatters by tens of percent.
  constexpr size_t kRealizations = 3;
  const size_t n_runs = taus.size() * kRealizations;
  std::vector<std::optional<PerturbedBatchRun>> runs(n_runs);
  std::vector<std::string> errors(n_runs);
  auto probe = [&](size_t k) {
    const double tau = taus[k / kRealizations];
    const std::vector<Eigen::Vector3d> d = GaussMarkovPerturbation(
        fix_t_s, tau, sigma_h, sigma_v, o.seed * 1000003ULL + 7919ULL * (k + 1));
    Dataset perturbed = real;
    for (size_t i = 0; i < perturbed.gnss_fixes.size(); ++i) {
      GnssFix& f = perturbed.gnss_fixes[i];
      f.p_w += earth.LocalLevelAt(f.p_w) * d[i];  // d in the local east, north, up
    }
    const BatchResult b = SmoothBatch(perturbed, config, pass.records, pass.decisions, {});
    if (!b.usable || b.records.size() < 2) {
      errors[k] = "the batch gave no trajectory";
      return;
    }
    std::vector<NavState> s;
    for (const EstimateRecord& r : b.records) s.push_back(r.state);
    std::vector<size_t> after_index;
    const GnssResidualSeries after =
        GnssResidualsAgainstTruth(perturbed, sim::SplineMotion(s), &after_index);
    std::vector<long> at(real.gnss_fixes.size(), -1);  // fix index -> position in `after`
    for (size_t j = 0; j < after_index.size(); ++j) at[after_index[j]] = static_cast<long>(j);
    PerturbedBatchRun run;
    for (size_t i = 0; i < fix_index.size(); ++i) {
      const long j = at[fix_index[i]];
      if (clean_at[i] < 0 || j < 0) continue;
      run.injected_enu_m.push_back(d[fix_index[i]]);
      run.residual_change_enu_m.push_back(after.e_enu_m[j] - before.e_enu_m[i]);
      run.index.push_back(static_cast<size_t>(clean_at[i]));
    }
    if (run.injected_enu_m.size() < 30) {
      errors[k] = "its trajectory covers fewer than 30 fixes";
      return;
    }
    runs[k] = std::move(run);
  };
  const size_t workers = std::min<size_t>(
      n_runs,
      std::max(1, o.jobs > 0 ? o.jobs : static_cast<int>(std::thread::hardware_concurrency())));
  std::atomic<size_t> next{0};
  std::vector<std::thread> pool;
  for (size_t w = 0; w < workers; ++w) {
    pool.emplace_back([&]() {
      for (size_t k = next++; k < n_runs; k = next++) {
        try {
          probe(k);
        } catch (const std::exception& e) {  // a batch that failed: that run is left out
          errors[k] = e.what();
        }
      }
    });
  }
  for (std::thread& t : pool) t.join();
  // What the identification needs to call a drift seen, per axis pair, from the fit as made.
  const double threshold_h =
      DriftSeenThreshold(g.white_sigma_horizontal_m.value, g.drift_sigma_horizontal_m.sigma);
  const double threshold_v =
      DriftSeenThreshold(g.white_sigma_vertical_m.value, g.drift_sigma_vertical_m.sigma);
  // Each probe's limit from the gain, then checked against the identification itself (the
  // same fit as on the recording, on its residuals plus the surviving drift at the limit:
  // ConfirmDetection), the probes in parallel.
  std::vector<std::optional<DriftDetection>> probes(taus.size());
  std::vector<std::vector<PerturbedBatchRun>> kept(taus.size());
  for (size_t t = 0; t < taus.size(); ++t) {
    for (size_t k = t * kRealizations; k < (t + 1) * kRealizations; ++k) {
      if (runs[k]) {
        kept[t].push_back(std::move(*runs[k]));
      } else {
        char what[64];
        std::snprintf(what, sizeof(what), "; tau %.4g s, run %zu: ", taus[t], k % kRealizations);
        *failures += what + errors[k];
      }
    }
  }
  auto confirm = [&](size_t t) {
    // A probe with a run left out would state a limit from fewer swings: none rather than one
    // less sure than the others.
    if (kept[t].size() != kRealizations) return;
    const DriftDetection first =
        DriftDetectionAt(taus[t], MeasureBatchGain(kept[t]), threshold_h, threshold_v);
    probes[t] = ConfirmDetection(
        first, kept[t], clean, sigma_h, sigma_v,
        [&](const GnssResidualSeries& r) { return FitGnssErrorModel(r, io.gnss); });
  };
  std::vector<std::string> confirm_errors(taus.size());
  next = 0;
  pool.clear();
  for (size_t w = 0; w < std::min(workers, taus.size()); ++w) {
    pool.emplace_back([&]() {
      for (size_t t = next++; t < taus.size(); t = next++) {
        try {
          confirm(t);
        } catch (const std::exception& e) {
          confirm_errors[t] = e.what();
        }
      }
    });
  }
  for (std::thread& t : pool) t.join();
  for (size_t t = 0; t < taus.size(); ++t) {
    if (probes[t]) id->drift_detection.push_back(*probes[t]);
    if (!confirm_errors[t].empty()) {
      *failures += "; tau " + std::to_string(taus[t]) + " s: " + confirm_errors[t];
    }
  }
  StateDriftDetectionLimit(id->drift_detection, &*id->gnss);
  return Seconds(t_limit);
}

int RunTwin(const TwinOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  if (o.twins == 1 || o.twins < 0 || o.twins > 99) {
    throw InputError(kCommandLine, 0, "--twins", "must be 0 (no fidelity check) or 2..99");
  }
  if (!(o.alpha > 0.0 && o.alpha < 1.0)) {
    throw InputError(kCommandLine, 0, "--alpha", "must be in (0, 1)");
  }
  if (o.imu_noise != "rest" && o.imu_noise != "residuals") {
    throw InputError(kCommandLine, 0, "--imu-noise", "must be rest or residuals");
  }
  // nan passed every comparison as no rest at all, silently.
  if (!(o.min_rest_s > 0.0 && o.min_rest_s <= kMaxDurationS)) {
    throw InputError(kCommandLine, 0, "--min-rest", "must be a duration in (0, 1e9] s");
  }
  const Dataset real = LoadDataset(o.dataset);
  if (!real.has_gnss) {
    throw InputError(o.dataset, 0, "sensors.gnss",
                     "skerry twin needs GNSS fixes to identify the receiver's model");
  }
  if (!real.has_imu) return RunGnssOnlyTwin(o, real, t0);
  const EstimatorConfig config = LoadConfigVariant(o.config, "--config");
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

  double drift_limit_s = 0.0;
  std::string drift_limit_failures;
  if (!o.no_drift_limit && id.gnss) {
    drift_limit_s =
        MeasureDriftDetection(o, real, truth, config, pass, io, &id, &drift_limit_failures);
  }
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
    // A drift not seen, with its measured limit: the largest drift the data could have hidden.
    for (const auto& [name, v] : {std::pair{"drift sigma horizontal", g.drift_sigma_horizontal_m},
                                  std::pair{"drift sigma vertical", g.drift_sigma_vertical_m}}) {
      if (v.identified || id.drift_detection.empty()) {
        PrintIdentified(name, v, "m", 1.0);
      } else {
        std::printf("    %-34s %10s (a drift up to %.3g m may be unseen)\n", name,
                    "(not identified)", v.sigma);
      }
    }
    PrintIdentified("drift correlation time", g.drift_tau_s, "s", 1.0);
    if (!id.drift_detection.empty()) {
      std::printf(
          "    drift detection (a known drift added to the fixes, the batch re-run; %.1f s):\n",
          drift_limit_s);
      for (const DriftDetection& d : id.drift_detection) {
        std::printf(
            "      tau %6.4g s: %3.0f %% horizontal, %3.0f %% vertical survives the batch "
            "(seen from %.3g m, %.3g m); the identification saw %s%.3g m, %s%.3g m\n",
            d.tau_s, 100.0 * d.batch_gain.horizontal, 100.0 * d.batch_gain.vertical,
            d.gain_limit_sigma_horizontal_m, d.gain_limit_sigma_vertical_m,
            d.confirmed_horizontal ? "" : "none up to ", d.detectable_sigma_horizontal_m,
            d.confirmed_vertical ? "" : "none up to ", d.detectable_sigma_vertical_m);
      }
    }
    if (!drift_limit_failures.empty()) {
      std::printf("    drift detection not measured%s\n", drift_limit_failures.c_str());
    }
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
    std::vector<std::uint64_t> seeds, held_out;
    for (int k = 0; k < o.calibration_twins; ++k) seeds.push_back(prov.seed + 1000 + k);
    // Held-out seeds, twice as many (at least 8): the search picks among many models on its few
    // seeds and can fit their particular noise.
    for (int k = 0; k < std::max(8, 2 * o.calibration_twins); ++k) {
      held_out.push_back(prov.seed + 2000 + k);
    }
    auto objective_on = [&](const std::vector<std::uint64_t>& on, const sim::TwinModel& model) {
      const TwinRuns t = run_twins(model, on);
      // A model whose twins the estimator gives up on is not the recording's.
      if (!t.failed.empty() || t.runs.size() < 2) return 1e9;
      return CalibrationObjective(real_run, t.runs);
    };
    auto objective = [&](const sim::TwinModel& model) { return objective_on(seeds, model); };
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
    // The calibrated model stands only if it is also closer on the held-out seeds.
    calibration->validation_twins = static_cast<int>(held_out.size());
    calibration->validation_before = objective_on(held_out, identified);
    calibration->validation_after = objective_on(held_out, calibration->model);
    calibration->validated = calibration->validation_after < calibration->validation_before;
    id.model = calibration->validated ? calibration->model : identified;
    if (!o.quiet) {
      std::printf("  calibration: objective %.5f -> %.5f in %d evaluations\n",
                  calibration->objective_before, calibration->objective_after,
                  calibration->evaluations);
      for (const TwinCalibrationStep& st : calibration->steps) {
        if (st.kept)
          std::printf("    %-40s -> %.4g (%.4f)\n", st.parameter.c_str(), st.value, st.objective);
      }
      std::printf("  held out (%d other twins): %.5f identified, %.5f calibrated: %s\n",
                  calibration->validation_twins, calibration->validation_before,
                  calibration->validation_after,
                  calibration->validated ? "the calibrated model is kept"
                                         : "the calibration did not hold, the identified model "
                                           "is kept");
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
      // A twin the estimator gave up on is replaced by one of a further seed (at most as many
      // again), so that the rank test keeps its power: with one twin fewer of 19 its smallest
      // p is 2/19 > 0.1 and it could reject nothing. The test is then one among twins the
      // estimator held, and the count left out is reported beside it.
      std::uint64_t extra = seeds.back() + 1;
      for (size_t round = 0;
           round < 3 && !kept->failed.empty() && kept->runs.size() < seeds.size() &&
           extra < seeds.back() + 1 + seeds.size();
           ++round) {
        std::vector<std::uint64_t> more;
        for (size_t k = kept->runs.size(); k < seeds.size(); ++k) more.push_back(extra++);
        const TwinRuns t = run_twins(model, more);
        for (size_t i = 0; i < t.runs.size(); ++i) {
          kept->runs.push_back(t.runs[i]);
          kept->seeds.push_back(t.seeds[i]);
        }
        kept->failed.insert(kept->failed.end(), t.failed.begin(), t.failed.end());
      }
      for (const std::string& f : kept->failed) {
        std::fprintf(stderr, "skerry twin: %s: %s (replaced in the test by a further seed)\n",
                     title, f.c_str());
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
    const bool calibrated = calibration && calibration->validated;
    if (calibrated) before = test(identified, "identified model", &kept);
    fidelity = test(id.model, calibrated ? "calibrated model" : "identified model", &kept);
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
  cmd->add_option(
         "--config", o->config,
         "Estimator preset or YAML for the batch and the runs, optionally with keys changed "
         "as --set changes them: SOURCE,KEY=VALUE,... (docs/compare.md)")
      ->capture_default_str();
  cmd->add_option("--seed", o->seed, "The twin's seed; the fidelity twins take the next ones")
      ->capture_default_str()
      ->check(SeedNumber());
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
  cmd->add_flag("--no-drift-limit", o->no_drift_limit,
                "Skip measuring the smallest GNSS drift the identification could see (a few "
                "batch runs; docs/twin.md)");
  cmd->add_flag("-q,--quiet", o->quiet, "No summary on the terminal");
  Subcommand s;
  s.app = cmd;
  s.run = [o]() { return RunTwin(*o); };
  return s;
}

}  // namespace skerry::cli
