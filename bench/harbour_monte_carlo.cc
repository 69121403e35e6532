// Monte-Carlo consistency of the sliding window on the harbour scenario: N seeds (default 20),
// each simulated and estimated; per keyframe epoch the position NEES of the window's latest state
// is averaged over the runs (ANEES_k) and compared with its two-sided 95% chi-square bounds
// chi2(3N)/N (Bar-Shalom, Li, Kirubarajan, "Estimation with Applications to Tracking and
// Navigation", 2001, sec. 5.4.2). Also prints, per seed, the accuracy figures of the harbour
// requirements and their medians, and at the end of the first outage the best causal estimate
// (SmoothUntil: the batch smoother over the data up to then) beside the window's, to show how
// much of the outage error any live estimator with this IMU and these fixes must make.
//
//   ./build/bench/skerry_harbour_monte_carlo [--seeds 20] [--config default] [--threads 2]
//       [--scenario harbour] [--matched] [--earth wgs84|flat] [--imu-grade navigation] [--batch]
//       [--skip-best-causal]
//
// --matched runs the scenario in the world of the configuration's model (sim::MatchedToEstimator:
// no error the estimator lacks, its own GNSS drift); without it the scenario's real-receiver and
// real-IMU errors are on (docs/simulator.md). --batch also smooths each whole run (SmoothBatch)
// and reports its accuracy and NEES beside the window's. A figure a run does not have (no
// estimate at an outage's end, the best causal estimate skipped or unusable) prints as "-" and is
// left out of medians and counts; a run the watchdog gave up on is listed and left out of all.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <future>
#include <limits>
#include <map>
#include <string>
#include <vector>

#include "bench_util.h"
#include "skerry/eval/evaluation.h"
#include "skerry/eval/event_metrics.h"
#include "skerry/frontends/dataset_sensors.h"
#include "skerry/io/estimate_io.h"
#include "skerry/sim/scenario.h"
#include "skerry/sim/simulator.h"
#include "skerry/solvers/batch_smoother.h"
#include "skerry/solvers/pipeline.h"

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::vector<double> Finite(const std::vector<double>& v) {
  std::vector<double> out;
  for (double x : v) {
    if (std::isfinite(x)) out.push_back(x);
  }
  return out;
}

double Mean(const std::vector<double>& v) {
  double sum = 0.0;
  for (double x : v) sum += x;
  return v.empty() ? kNaN : sum / static_cast<double>(v.size());
}

// Median / max / count under `limit` of the finite values.
double FiniteMedian(const std::vector<double>& v) { return skerry::bench::Median(Finite(v)); }
double FiniteMax(const std::vector<double>& v) {
  const std::vector<double> f = Finite(v);
  return f.empty() ? kNaN : skerry::bench::Max(f);
}
int CountUnder(const std::vector<double>& v, double limit) {
  int n = 0;
  for (double x : Finite(v)) n += x < limit;
  return n;
}

// A right-aligned table cell: the value, or "-" when there is none.
std::string Cell(double x, int width, int precision) {
  char buf[64];
  if (std::isfinite(x)) {
    std::snprintf(buf, sizeof(buf), "%*.*f", width, precision, x);
  } else {
    std::snprintf(buf, sizeof(buf), "%*s", width, "-");
  }
  return buf;
}

struct SeedResult {
  std::uint64_t seed = 0;
  double rmse_outside_m = 0.0;
  double heading_rmse_deg = 0.0;
  bool diverged = false;  ///< the watchdog gave up: not a result
  double outage_end_m = kNaN;
  std::vector<double> outage_ends_m;  ///< every outage's, in order (NaN: no estimate at its end)
  double outage_sigma_m = kNaN;
  double jump_max_m = kNaN;
  double bound_end_m = kNaN;        ///< best causal estimate at the outage end: horizontal error
  double bound_sigma_m = kNaN;      ///< and its horizontal 1-sigma
  double window_vs_bound_m = kNaN;  ///< horizontal distance between the two estimates
  double anees_pos = kNaN;
  double realtime_factor = 0.0;
  skerry::EvaluationResult evaluation;  ///< per-epoch errors and NEES
  // Sensors beyond IMU and GNSS (pose fixes): accuracy where GNSS is denied (inside outages),
  // and the gate against the simulator's list of gross fixes.
  bool has_sensors = false;
  double rmse_denied_m = kNaN;
  double heading_rmse_denied_deg = kNaN;
  double batch_rmse_denied_m = kNaN;
  double batch_heading_rmse_denied_deg = kNaN;
  int outliers = 0, outliers_rejected = 0, inliers = 0, inliers_rejected = 0;
  bool has_batch = false;
  double batch_rmse_outside_m = 0.0;
  double batch_heading_rmse_deg = 0.0;
  double batch_outage_end_m = kNaN;
  skerry::EvaluationResult batch_evaluation;
};

// Horizontal and heading RMSE over the epochs inside GNSS outages.
std::pair<double, double> DeniedRmse(const skerry::EvaluationResult& ev,
                                     const std::vector<skerry::GnssEvent>& events) {
  double h2 = 0.0, psi2 = 0.0;
  int n = 0;
  for (const skerry::EpochError& e : ev.epochs) {
    const bool denied = std::any_of(events.begin(), events.end(), [&](const skerry::GnssEvent& o) {
      return o.type == "outage" && e.t_ns >= o.t_start_ns && e.t_ns < o.t_end_ns;
    });
    if (!denied) continue;
    h2 += e.p_err_w.head<2>().squaredNorm();
    psi2 += e.heading_err_deg * e.heading_err_deg;
    ++n;
  }
  if (n == 0) return {kNaN, kNaN};
  return {std::sqrt(h2 / n), std::sqrt(psi2 / n)};
}

SeedResult RunSeed(const skerry::sim::ScenarioConfig& scenario,
                   const skerry::EstimatorConfig& config,
                   std::uint64_t seed,
                   bool batch,
                   bool best_causal) {
  using namespace skerry;
  const Dataset data = sim::Simulate(scenario, seed);
  const WindowRun run = RunWindow(data, config, {}, nullptr, DatasetSensors(data, config));
  const EvaluationResult ev = Evaluate(run.records, data.groundtruth);
  const EventMetrics m = ComputeEventMetrics(ev, data.events, 30.0, 10.0);
  SeedResult r;
  if (!run.sensors.measurements.empty()) {
    r.has_sensors = true;
    std::tie(r.rmse_denied_m, r.heading_rmse_denied_deg) = DeniedRmse(ev, data.events);
    for (const SensorRecord& d : run.sensors.decisions) {
      if (run.sensors.sensors.at(d.sensor).name != "pose_fixes") continue;
      const bool outlier =
          std::binary_search(data.pose_fix_outliers.begin(), data.pose_fix_outliers.end(), d.t_ns);
      const bool rejected = d.decision == SensorDecision::kRejectedByGate;
      if (d.decision == SensorDecision::kDropped) continue;
      (outlier ? r.outliers : r.inliers)++;
      (outlier ? r.outliers_rejected : r.inliers_rejected) += rejected;
    }
  }
  r.seed = seed;
  r.diverged = run.diverged;
  r.rmse_outside_m = m.horizontal_outside_outages.rmse;
  r.heading_rmse_deg = m.heading_outside_outages_deg.rmse;
  if (!m.outages.empty()) r.outage_end_m = m.outages[0].horizontal_error_at_end_m;
  for (const OutageMetric& o : m.outages) r.outage_ends_m.push_back(o.horizontal_error_at_end_m);
  if (!m.jumps.empty()) r.jump_max_m = m.jumps[0].max_horizontal_error_m;
  if (ev.nees_count > 0) r.anees_pos = ev.anees_pos;
  r.realtime_factor = run.data_s / run.wall_s;
  r.evaluation = ev;
  for (const GnssEvent& evn : data.events) {
    if (evn.type != "outage") continue;
    const EstimateRecord* last = nullptr;  // the window's last estimate inside the outage
    for (const EstimateRecord& rec : run.records) {
      if (rec.state.t_ns < evn.t_end_ns) last = &rec;
    }
    if (last == nullptr) break;
    r.outage_sigma_m = HorizontalSigmaM(last->covariance);
    if (!best_causal) break;
    const BatchResult bound = SmoothUntil(data, config, run, last->state.t_ns);
    if (bound.usable && !bound.records.empty()) {
      const EstimateRecord& b = bound.records.back();
      r.bound_end_m = Evaluate({b}, data.groundtruth).horizontal.max;
      r.bound_sigma_m = HorizontalSigmaM(b.covariance);
      r.window_vs_bound_m = (b.state.p_w_b - last->state.p_w_b).head<2>().norm();
    }
    break;  // the first outage
  }
  if (batch) {
    const BatchResult b = SmoothBatch(data, config, run.records, run.decisions, run.sensors);
    if (b.usable) {
      r.has_batch = true;
      r.batch_evaluation = Evaluate(b.records, data.groundtruth);
      std::tie(r.batch_rmse_denied_m, r.batch_heading_rmse_denied_deg) =
          DeniedRmse(r.batch_evaluation, data.events);
      const EventMetrics mb = ComputeEventMetrics(r.batch_evaluation, data.events, 30.0, 10.0);
      r.batch_rmse_outside_m = mb.horizontal_outside_outages.rmse;
      r.batch_heading_rmse_deg = mb.heading_outside_outages_deg.rmse;
      if (!mb.outages.empty()) r.batch_outage_end_m = mb.outages[0].horizontal_error_at_end_m;
    }
  }
  return r;
}

int Main(const skerry::bench::Flags& flags) {
  using namespace skerry;
  const int n = static_cast<int>(flags.Int("seeds", 1));
  const int threads = static_cast<int>(flags.Int("threads", 1));
  const EstimatorConfig config = LoadPreset(flags.String("config"));
  sim::ScenarioConfig scenario = sim::LoadScenario(flags.String("scenario"));
  const std::string grade = flags.String("imu-grade");
  if (!grade.empty()) {
    const std::map<std::string, sim::ImuGrade> grades = {
        {"consumer", sim::ImuGrade::kConsumer},
        {"tactical", sim::ImuGrade::kTactical},
        {"navigation", sim::ImuGrade::kNavigation}};
    if (grades.count(grade) == 0)
      throw bench::UsageError("--imu-grade: consumer, tactical or navigation");
    scenario.imu.grade = grade;
    scenario.imu.errors = sim::ImuGradePreset(grades.at(grade));
  }
  const std::string earth = flags.String("earth");
  if (!earth.empty() && !ParseEarthKind(earth, &scenario.earth.kind)) {
    throw bench::UsageError("--earth: wgs84 or flat");
  }
  if (flags.Switch("matched")) {
    const GnssDriftParams& d = config.gnss_drift;
    scenario =
        sim::MatchedToEstimator(scenario, {d.sigma_horizontal_m, d.sigma_vertical_m, d.tau_s});
  }
  const bool batch = flags.Switch("batch");
  const bool best_causal = !flags.Switch("skip-best-causal");

  std::vector<SeedResult> results;
  for (int first = 1; first <= n; first += threads) {
    std::vector<std::future<SeedResult>> jobs;
    for (int s = first; s < first + threads && s <= n; ++s) {
      jobs.push_back(
          std::async(std::launch::async, RunSeed, scenario, config, s, batch, best_causal));
    }
    for (auto& j : jobs) results.push_back(j.get());
  }

  std::printf("scenario %s (%s Earth, IMU %s), config %s, %d seeds\n\n", scenario.name.c_str(),
              EarthKindName(scenario.earth.kind).c_str(), scenario.imu.grade.c_str(),
              config.name.c_str(), n);
  std::printf("%5s %11s %11s %11s %11s %11s %11s %11s %10s %8s %6s\n", "seed", "rmse_out_m",
              "heading_deg", "outage_end", "outage_1sig", "best_end", "best_1sig", "win-best_m",
              "jump_max_m", "ANEES", "xRT");
  std::vector<double> rmse, heading, outage, sigma, best, best_sigma, gap, jump, anees;
  std::vector<const SeedResult*> kept;
  std::string diverged;
  for (const SeedResult& r : results) {
    std::printf("%5llu%s%s%s%s%s%s%s%s%s%s%s\n", static_cast<unsigned long long>(r.seed),
                Cell(r.rmse_outside_m, 12, 3).c_str(), Cell(r.heading_rmse_deg, 12, 3).c_str(),
                Cell(r.outage_end_m, 12, 2).c_str(), Cell(r.outage_sigma_m, 12, 2).c_str(),
                Cell(r.bound_end_m, 12, 2).c_str(), Cell(r.bound_sigma_m, 12, 2).c_str(),
                Cell(r.window_vs_bound_m, 12, 3).c_str(), Cell(r.jump_max_m, 11, 2).c_str(),
                Cell(r.anees_pos, 9, 2).c_str(), Cell(r.realtime_factor, 7, 0).c_str(),
                r.diverged ? "  diverged" : "");
    if (r.diverged) {
      diverged += " " + std::to_string(r.seed);
      continue;
    }
    kept.push_back(&r);
    rmse.push_back(r.rmse_outside_m);
    heading.push_back(r.heading_rmse_deg);
    outage.push_back(r.outage_end_m);
    sigma.push_back(r.outage_sigma_m);
    best.push_back(r.bound_end_m);
    best_sigma.push_back(r.bound_sigma_m);
    gap.push_back(r.window_vs_bound_m);
    jump.push_back(r.jump_max_m);
    anees.push_back(r.anees_pos);
  }
  std::printf("%6s%s%s%s%s%s%s%s%s%s\n", "median", Cell(FiniteMedian(rmse), 11, 3).c_str(),
              Cell(FiniteMedian(heading), 12, 3).c_str(), Cell(FiniteMedian(outage), 12, 2).c_str(),
              Cell(FiniteMedian(sigma), 12, 2).c_str(), Cell(FiniteMedian(best), 12, 2).c_str(),
              Cell(FiniteMedian(best_sigma), 12, 2).c_str(), Cell(FiniteMedian(gap), 12, 3).c_str(),
              Cell(FiniteMedian(jump), 11, 2).c_str(), Cell(FiniteMedian(anees), 9, 2).c_str());
  if (!diverged.empty()) {
    std::printf("diverged (the watchdog gave up; left out of every figure below):%s\n",
                diverged.c_str());
  }
  const size_t n_outage = Finite(outage).size();
  if (best_causal) {
    std::printf(
        "outage end error < 5 m in %d of %zu runs (window), %d of %zu (best causal); max %.2f m\n",
        CountUnder(outage, 5.0), n_outage, CountUnder(best, 5.0), Finite(best).size(),
        FiniteMax(outage));
    std::printf("best causal = batch smoother over the data up to the outage end (SmoothUntil)\n");
  } else {
    std::printf(
        "outage end error < 5 m in %d of %zu runs (window); max %.2f m; best causal not "
        "computed (--skip-best-causal)\n",
        CountUnder(outage, 5.0), n_outage, FiniteMax(outage));
  }
  const size_t n_outages = kept.empty() ? 0 : kept.front()->outage_ends_m.size();
  for (size_t o = 0; o < n_outages; ++o) {
    std::vector<double> ends;
    for (const SeedResult* r : kept) {
      if (o < r->outage_ends_m.size()) ends.push_back(r->outage_ends_m[o]);
    }
    const std::vector<double> f = Finite(ends);
    std::printf("outage %zu: end error median %.2f m, mean %.2f m, max %.2f m over %zu runs\n",
                o + 1, bench::Median(f), Mean(f), FiniteMax(f), f.size());
  }
  std::printf("\n");
  if (!kept.empty() && kept.front()->has_sensors) {
    std::vector<double> denied, denied_heading, b_denied, b_denied_heading;
    int outliers = 0, outliers_rejected = 0, inliers = 0, inliers_rejected = 0;
    for (const SeedResult* r : kept) {
      denied.push_back(r->rmse_denied_m);
      denied_heading.push_back(r->heading_rmse_denied_deg);
      b_denied.push_back(r->batch_rmse_denied_m);
      b_denied_heading.push_back(r->batch_heading_rmse_denied_deg);
      outliers += r->outliers;
      outliers_rejected += r->outliers_rejected;
      inliers += r->inliers;
      inliers_rejected += r->inliers_rejected;
    }
    std::printf("pose fixes, inside the GNSS outages (GNSS denied):\n");
    std::printf(
        "  window: horizontal RMSE median %.3f m (max %.3f), heading RMSE median %.3f deg "
        "(max %.3f)\n",
        FiniteMedian(denied), FiniteMax(denied), FiniteMedian(denied_heading),
        FiniteMax(denied_heading));
    if (batch) {
      std::printf(
          "  batch:  horizontal RMSE median %.3f m (max %.3f), heading RMSE median %.3f "
          "deg (max %.3f)\n",
          FiniteMedian(b_denied), FiniteMax(b_denied), FiniteMedian(b_denied_heading),
          FiniteMax(b_denied_heading));
    }
    std::printf("  gate: %d of %d gross fixes rejected, %d of %d good fixes rejected\n",
                outliers_rejected, outliers, inliers_rejected, inliers);
  }

  // Per-epoch ANEES over the runs, on the keyframe times all runs share.
  std::vector<const EvaluationResult*> evaluations;
  for (const SeedResult* r : kept) evaluations.push_back(&r->evaluation);
  const int nk = static_cast<int>(kept.size());
  const TimeNs period = SecondsToNs(1.0 / config.keyframe_rate_hz);
  const NeesTest test = MonteCarloNeesTest(evaluations, nk, 0.95, period);
  const auto bounds = AneesBounds(3, nk);
  std::printf("position NEES of the latest state, averaged over %d runs at each of %d epochs:\n",
              nk, test.epochs);
  std::printf("  time-average ANEES %.2f (ideal 3); 95%% bounds per epoch [%.2f, %.2f]\n",
              test.time_average, bounds.first, bounds.second);
  std::printf("  epochs inside the bounds %.1f%%, above (over-confident) %.1f%%, below %.1f%%\n",
              100.0 * test.inside, 100.0 * test.above, 100.0 * test.below);
  if (!kept.empty() && kept.front()->has_sensors) {
    // 2-D pose fixes observe the horizontal; the vertical channel is the IMU's alone.
    const NeesTest h = MonteCarloNeesTest(evaluations, nk, 0.95, period, /*horizontal=*/true);
    const auto hb = AneesBounds(2, nk);
    std::printf(
        "horizontal position NEES (2 DOF): time-average %.2f (ideal 2); bounds [%.2f, "
        "%.2f]; epochs inside %.1f%%, above %.1f%%, below %.1f%%\n",
        h.time_average, hb.first, hb.second, 100.0 * h.inside, 100.0 * h.above, 100.0 * h.below);
  }
  if (batch) {
    std::vector<double> b_rmse, b_heading, b_outage;
    std::vector<const EvaluationResult*> b_evals;
    for (const SeedResult* r : kept) {
      if (!r->has_batch) continue;
      b_rmse.push_back(r->batch_rmse_outside_m);
      b_heading.push_back(r->batch_heading_rmse_deg);
      b_outage.push_back(r->batch_outage_end_m);
      b_evals.push_back(&r->batch_evaluation);
    }
    const int nb = static_cast<int>(b_evals.size());
    const NeesTest bt = MonteCarloNeesTest(b_evals, nb, 0.95, period);
    std::printf("\nbatch (SmoothBatch over each whole run), %d of %d runs usable:\n", nb, nk);
    std::printf(
        "  median rmse outside outages %.3f m (max %.3f), heading %.3f deg, outage end "
        "%.2f m (max %.2f)\n",
        FiniteMedian(b_rmse), FiniteMax(b_rmse), FiniteMedian(b_heading), FiniteMedian(b_outage),
        FiniteMax(b_outage));
    std::printf(
        "  position NEES: time-average %.2f; epochs inside %.1f%%, above %.1f%%, below "
        "%.1f%%\n",
        bt.time_average, 100.0 * bt.inside, 100.0 * bt.above, 100.0 * bt.below);
    if (!kept.empty() && kept.front()->has_sensors) {
      const NeesTest bh = MonteCarloNeesTest(b_evals, nb, 0.95, period, /*horizontal=*/true);
      std::printf(
          "  horizontal NEES (2 DOF): time-average %.2f; epochs inside %.1f%%, above "
          "%.1f%%, below %.1f%%\n",
          bh.time_average, 100.0 * bh.inside, 100.0 * bh.above, 100.0 * bh.below);
    }
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  using namespace skerry;
  bench::Flags flags;
  flags.Declare("seeds", "20", "Number of Monte-Carlo runs (seeds 1..N)");
  flags.Declare("scenario", "harbour", "Scenario name or YAML file");
  flags.Declare("config", "default", "Estimator preset or YAML file");
  flags.Declare("threads", "2", "Runs in parallel");
  flags.Declare("matched", "", "The world of the configuration's model (sim::MatchedToEstimator)",
                true);
  flags.Declare("earth", "", "wgs84 or flat: override the scenario's Earth");
  flags.Declare("imu-grade", "", "consumer, tactical or navigation: override the scenario's IMU");
  flags.Declare("batch", "", "Also smooth each whole run and report the batch", true);
  flags.Declare("skip-best-causal", "",
                "Leave out the best causal estimate at the first outage's end (SmoothUntil)", true);
  return bench::RunMain(flags, argc, argv, "Monte-Carlo NEES and accuracy of the window",
                        [&flags]() { return Main(flags); });
}
