/// \file
/// Whole-run smoothing cost: simulates a long scenario (open-sea, 60 min, by default), runs the
/// sliding window over it (RunWindow), then SmoothBatch over every window keyframe, and prints
/// per phase the wall time, the peak resident memory (getrusage ru_maxrss, so the figure after
/// a phase is the peak of everything up to it), the batch iterations and keyframes, and the
/// horizontal RMSE of window vs batch against ground truth. With --runs N > 1 the window and
/// batch are repeated on the same data and the medians are printed.

#include <chrono>
#include <cstdio>
#include <exception>
#include <string>
#include <vector>

#include "bench_util.h"
#include "skerry/eval/evaluation.h"
#include "skerry/sim/scenario.h"
#include "skerry/sim/simulator.h"
#include "skerry/solvers/batch_smoother.h"
#include "skerry/solvers/estimator_config.h"
#include "skerry/solvers/pipeline.h"

namespace skerry::bench {
namespace {

struct Options {
  std::string scenario;
  std::uint64_t seed = 1;
  int runs = 1;
  std::string preset;
  int cpu = -1;
  double duration_s = 0.0;
  bool accuracy = true;
};

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct RunFigures {
  double window_wall_s = 0.0;
  double window_cpu_s = 0.0;
  double batch_wall_s = 0.0;
  double batch_cpu_s = 0.0;
  double batch_solve_s = 0.0;
  double batch_covariance_s = 0.0;
  int iterations = 0;
  int keyframes = 0;
  int gnss_used = 0;
  int gnss_rejected_after_solve = 0;
  bool usable = false;
  double window_rmse_m = 0.0;
  double batch_rmse_m = 0.0;
  double rss_after_window_mib = 0.0;
  double rss_after_batch_mib = 0.0;
};

int Main(const Options& o) {
  if (o.cpu >= 0) PinToCpu(o.cpu);
  const double rss_start = PeakRssMiB();
  auto t0 = std::chrono::steady_clock::now();
  sim::ScenarioConfig scenario = sim::LoadScenario(o.scenario);
  if (o.duration_s > 0.0) scenario.duration_s = o.duration_s;
  const Dataset data = sim::Simulate(scenario, o.seed);
  const double simulate_s = Seconds(t0);
  const double rss_after_sim = PeakRssMiB();

  EstimatorConfig config = LoadPreset(o.preset);
  config.ceres.num_threads = 1;
  config.batch_ceres.num_threads = 1;

  const double data_s =
      data.imu_samples.size() > 1
          ? NsToSeconds(data.imu_samples.back().t_ns - data.imu_samples.front().t_ns)
          : 0.0;
  std::printf(
      "batch_benchmark: scenario %s (%.0f s of data, seed %llu), %zu IMU samples, %zu "
      "GNSS fixes; preset %s (batch: %s, %s, max %d iterations); ceres num_threads=1\n",
      scenario.name.c_str(), data_s, static_cast<unsigned long long>(o.seed),
      data.imu_samples.size(), data.gnss_fixes.size(), config.name.c_str(),
      config.batch_ceres.trust_region.c_str(), config.batch_ceres.linear_solver.c_str(),
      config.batch_ceres.max_iterations);
  std::printf("  load average %s\n", LoadAverage().c_str());
  std::printf("  simulate: %.2f s, peak RSS %.0f MiB (process start %.0f MiB)\n", simulate_s,
              rss_after_sim, rss_start);

  std::vector<RunFigures> runs;
  for (int r = 0; r < o.runs; ++r) {
    RunFigures f;
    double cpu0 = ProcessCpuSeconds();
    const WindowRun window = RunWindow(data, config);
    f.window_cpu_s = ProcessCpuSeconds() - cpu0;
    f.window_wall_s = window.wall_s;
    f.rss_after_window_mib = PeakRssMiB();
    cpu0 = ProcessCpuSeconds();
    t0 = std::chrono::steady_clock::now();
    const BatchResult batch = SmoothBatch(data, config, window.records, window.decisions);
    f.batch_wall_s = Seconds(t0);
    f.batch_cpu_s = ProcessCpuSeconds() - cpu0;
    f.rss_after_batch_mib = PeakRssMiB();
    f.batch_solve_s = batch.solve_s;
    f.batch_covariance_s = batch.covariance_s;
    f.iterations = batch.iterations;
    f.keyframes = static_cast<int>(batch.records.size());
    f.gnss_used = batch.gnss_used;
    f.gnss_rejected_after_solve = batch.gnss_rejected_after_solve;
    f.usable = batch.usable;
    if (o.accuracy && !data.groundtruth.empty()) {
      f.window_rmse_m = Evaluate(window.records, data.groundtruth).horizontal.rmse;
      f.batch_rmse_m = Evaluate(batch.records, data.groundtruth).horizontal.rmse;
    }
    std::printf(
        "  run %d: window %.2f s (RTF %.0fx, cpu %.2f s), batch %.2f s (cpu %.2f s, solve %.2f s, "
        "covariance "
        "%.2f s), %d iterations, %d keyframes, GNSS used %d (rejected after solve %d), "
        "usable %s, peak RSS %.0f MiB\n",
        r + 1, f.window_wall_s, data_s / f.window_wall_s, f.window_cpu_s, f.batch_wall_s,
        f.batch_cpu_s, f.batch_solve_s, f.batch_covariance_s, f.iterations, f.keyframes,
        f.gnss_used, f.gnss_rejected_after_solve, f.usable ? "yes" : "NO", f.rss_after_batch_mib);
    std::fflush(stdout);
    runs.push_back(f);
  }

  auto column = [&runs](auto field) {
    std::vector<double> out;
    for (const RunFigures& f : runs) out.push_back(static_cast<double>(f.*field));
    return out;
  };
  const double window_s = Median(column(&RunFigures::window_wall_s));
  const double batch_s = Median(column(&RunFigures::batch_wall_s));
  const double window_cpu = Median(column(&RunFigures::window_cpu_s));
  const double batch_cpu = Median(column(&RunFigures::batch_cpu_s));
  std::printf("\nMedians over %d run(s); load average now %s\n", o.runs, LoadAverage().c_str());
  std::printf("  %-34s %10.2f s  (RTF %.0fx)\n", "window wall time", window_s, data_s / window_s);
  std::printf("  %-34s %10.2f s  (RTF %.0fx)\n", "window CPU time", window_cpu,
              data_s / window_cpu);
  std::printf("  %-34s %10.2f s  (RTF %.0fx; %.2f x window)\n", "batch wall time", batch_s,
              data_s / batch_s, batch_s / window_s);
  std::printf("  %-34s %10.2f s  (RTF %.0fx; %.2f x window)\n", "batch CPU time", batch_cpu,
              data_s / batch_cpu, batch_cpu / window_cpu);
  std::printf("  %-34s %10.2f s\n", "  of which Ceres solve(s)",
              Median(column(&RunFigures::batch_solve_s)));
  std::printf("  %-34s %10.2f s\n", "  of which marginal covariances",
              Median(column(&RunFigures::batch_covariance_s)));
  std::printf("  %-34s %10.0f\n", "batch iterations", Median(column(&RunFigures::iterations)));
  std::printf("  %-34s %10.0f\n", "batch keyframes", Median(column(&RunFigures::keyframes)));
  std::printf("  %-34s %10.0f MiB\n", "peak RSS after simulate", rss_after_sim);
  std::printf("  %-34s %10.0f MiB\n", "peak RSS after window (cumul.)",
              Median(column(&RunFigures::rss_after_window_mib)));
  std::printf("  %-34s %10.0f MiB\n", "peak RSS after batch (cumul.)",
              Median(column(&RunFigures::rss_after_batch_mib)));
  if (o.accuracy && !data.groundtruth.empty()) {
    const double w = Median(column(&RunFigures::window_rmse_m));
    const double b = Median(column(&RunFigures::batch_rmse_m));
    std::printf("  %-34s %10.3f m\n", "horizontal RMSE window", w);
    std::printf("  %-34s %10.3f m  (%.2f x window)\n", "horizontal RMSE batch", b, b / w);
  }
  for (const RunFigures& f : runs) {
    if (!f.usable) {
      std::printf("\nwarning: a batch solve was not usable (see SmoothBatch's ceres_report)\n");
      return 1;
    }
  }
  return 0;
}

}  // namespace
}  // namespace skerry::bench

int main(int argc, char** argv) {
  using skerry::bench::Flags;
  Flags flags;
  flags.Declare("scenario", "open-sea", "built-in scenario name or YAML path");
  flags.Declare("seed", "1", "simulation seed");
  flags.Declare("runs", "1", "window + batch repetitions on the same data (medians printed)");
  flags.Declare("preset", "default", "preset name or YAML path (its batch_solver is used)");
  flags.Declare("cpu", "-1", "pin the process to this CPU (-1: no pinning)");
  flags.Declare("duration-s", "0", "override the scenario duration (0: keep)");
  flags.Declare("no-accuracy", "", "skip the RMSE evaluation", true);
  const char* summary =
      "Times RunWindow then SmoothBatch over a whole simulated run and prints wall times, "
      "iterations, keyframes, peak memory and window-vs-batch accuracy (see bench/README.md).";
  return skerry::bench::RunMain(flags, argc, argv, summary, [&flags]() {
    skerry::bench::Options o;
    o.scenario = flags.String("scenario");
    o.seed = static_cast<std::uint64_t>(flags.Int("seed", 0));
    o.runs = static_cast<int>(flags.Int("runs", 1));
    o.preset = flags.String("preset");
    o.cpu = static_cast<int>(flags.Int("cpu", -1));
    o.duration_s = flags.Double("duration-s", 0.0);
    o.accuracy = !flags.Switch("no-accuracy");
    return skerry::bench::Main(o);
  });
}
