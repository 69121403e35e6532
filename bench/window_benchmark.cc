/// \file
/// Sliding-window timing: simulates a scenario (harbour by default), runs the window estimator
/// (RunWindow) over it N times per preset on one thread, and prints
///   - the real-time factor (data seconds / wall seconds), median over runs, and its ratio to
///     the requirement (>= 100x real time on one core); also the same factor on process CPU
///     time, which does not move with other load on a shared machine (the load average is
///     printed with the header);
///   - the window update time (UpdateStats::update_ms): median, p95 and max of each run, then
///     the median of those over runs;
///   - the number of solves and the median iterations per solve;
///   - the horizontal RMSE against ground truth (so a faster preset is not a less accurate one
///     in disguise);
///   - with several presets, the ratio of each one's median real-time factor to the first
///     preset's. Runs are interleaved (run r of every preset, then run r+1) so that machine load
///     drifts affect every preset alike.

#include <algorithm>
#include <cstdio>
#include <exception>
#include <string>
#include <thread>
#include <vector>

#include "bench_util.h"
#include "skerry/eval/evaluation.h"
#include "skerry/sim/scenario.h"
#include "skerry/sim/simulator.h"
#include "skerry/solvers/estimator_config.h"
#include "skerry/solvers/pipeline.h"

namespace skerry::bench {
namespace {

struct Options {
  std::string scenario;
  std::uint64_t seed = 1;
  int runs = 3;
  std::vector<std::string> presets;
  int cpu = -1;
  double duration_s = 0.0;
  double target_rtf = 100.0;
  bool check = false;
  bool check_on_cpu = false;
};

struct RunFigures {
  double wall_s = 0.0;
  double rtf = 0.0;
  double cpu_s = 0.0;
  double rtf_cpu = 0.0;
  double update_median_ms = 0.0;
  double update_p95_ms = 0.0;
  double update_max_ms = 0.0;
  int updates = 0;
  int solves = 0;
  double iterations_median = 0.0;
  double horizontal_rmse_m = 0.0;
};

struct PresetFigures {
  std::string name;
  EstimatorConfig config;
  std::vector<RunFigures> runs;

  std::vector<double> Column(double RunFigures::*field) const {
    std::vector<double> out;
    for (const RunFigures& r : runs) out.push_back(r.*field);
    return out;
  }
  std::vector<double> Column(int RunFigures::*field) const {
    std::vector<double> out;
    for (const RunFigures& r : runs) out.push_back(r.*field);
    return out;
  }
};

RunFigures Measure(const Dataset& data, const EstimatorConfig& config) {
  const double cpu0 = ProcessCpuSeconds();
  const WindowRun run = RunWindow(data, config);
  RunFigures f;
  f.cpu_s = ProcessCpuSeconds() - cpu0;
  f.wall_s = run.wall_s;
  f.rtf = run.wall_s > 0.0 ? run.data_s / run.wall_s : 0.0;
  f.rtf_cpu = f.cpu_s > 0.0 ? run.data_s / f.cpu_s : 0.0;
  std::vector<double> update_ms, iterations;
  for (const UpdateStats& s : run.stats) {
    update_ms.push_back(s.update_ms);
    if (s.solved) {
      ++f.solves;
      iterations.push_back(s.iterations);
    }
  }
  f.updates = static_cast<int>(run.stats.size());
  f.update_median_ms = Median(update_ms);
  f.update_p95_ms = Percentile(update_ms, 95.0);
  f.update_max_ms = Max(update_ms);
  f.iterations_median = Median(iterations);
  if (!data.groundtruth.empty() && !run.records.empty()) {
    f.horizontal_rmse_m = Evaluate(run.records, data.groundtruth).horizontal.rmse;
  }
  return f;
}

int Main(const Options& o) {
  if (o.cpu >= 0) PinToCpu(o.cpu);
  sim::ScenarioConfig scenario = sim::LoadScenario(o.scenario);
  if (o.duration_s > 0.0) scenario.duration_s = o.duration_s;
  const Dataset data = sim::Simulate(scenario, o.seed);

  std::vector<PresetFigures> presets;
  for (const std::string& name : o.presets) {
    PresetFigures p;
    p.name = name;
    p.config = LoadPreset(name);
    // One core: the requirement is stated for a single thread.
    p.config.ceres.num_threads = 1;
    p.config.batch_ceres.num_threads = 1;
    presets.push_back(std::move(p));
  }

  std::printf(
      "window_benchmark: scenario %s (%.0f s, seed %llu), %zu IMU samples, %zu GNSS fixes; %d "
      "run(s) per preset; ceres num_threads=1; cpu %s; hardware threads %u; load average %s\n",
      scenario.name.c_str(), scenario.duration_s, static_cast<unsigned long long>(o.seed),
      data.imu_samples.size(), data.gnss_fixes.size(), o.runs,
      o.cpu >= 0 ? std::to_string(o.cpu).c_str() : "not pinned",
      std::thread::hardware_concurrency(), LoadAverage().c_str());
  for (int r = 0; r < o.runs; ++r) {
    for (PresetFigures& p : presets) {
      p.runs.push_back(Measure(data, p.config));
      const RunFigures& f = p.runs.back();
      std::printf(
          "  run %d %-20s wall %7.3f s  RTF %7.1fx  cpu %7.3f s  RTF_cpu %7.1fx  update median "
          "%.3f ms  p95 %.3f ms  max %.2f ms  solves %d/%d  hRMSE %.3f m\n",
          r + 1, p.name.c_str(), f.wall_s, f.rtf, f.cpu_s, f.rtf_cpu, f.update_median_ms,
          f.update_p95_ms, f.update_max_ms, f.solves, f.updates, f.horizontal_rmse_m);
      std::fflush(stdout);
    }
  }

  std::printf(
      "\nMedians over %d run(s). RTF = data s / wall s; RTF_cpu = data s / process CPU s. Update "
      "times (wall) are each run's statistic, then the median over runs; max(all) is the worst "
      "over all runs. load average now: %s\n",
      o.runs, LoadAverage().c_str());
  const char* fmt_head = "%-20s %8s %8s %8s %8s %8s %8s %8s %9s %7s %6s %8s %8s\n";
  std::printf(fmt_head, "preset", "RTF", "RTF_cpu", "x100", "x100cpu", "upd_med", "upd_p95",
              "upd_max", "max(all)", "solves", "iters", "hRMSE", "RTF/ref");
  std::printf(fmt_head, "", "(x)", "(x)", "(wall)", "(cpu)", "(ms)", "(ms)", "(ms)", "(ms)", "",
              "(med)", "(m)", "(cpu)");
  const double ref_rtf_cpu = Median(presets.front().Column(&RunFigures::rtf_cpu));
  for (const PresetFigures& p : presets) {
    const double rtf = Median(p.Column(&RunFigures::rtf));
    const double rtf_cpu = Median(p.Column(&RunFigures::rtf_cpu));
    std::printf("%-20s %8.1f %8.1f %8.2f %8.2f %8.3f %8.3f %8.2f %9.2f %7.0f %6.1f %8.3f %8.3f\n",
                p.name.c_str(), rtf, rtf_cpu, rtf / o.target_rtf, rtf_cpu / o.target_rtf,
                Median(p.Column(&RunFigures::update_median_ms)),
                Median(p.Column(&RunFigures::update_p95_ms)),
                Median(p.Column(&RunFigures::update_max_ms)),
                Max(p.Column(&RunFigures::update_max_ms)), Median(p.Column(&RunFigures::solves)),
                Median(p.Column(&RunFigures::iterations_median)),
                Median(p.Column(&RunFigures::horizontal_rmse_m)), rtf_cpu / ref_rtf_cpu);
  }

  std::printf("\nrequirement: >= %.0fx real time on one core (x100 >= 1)\n", o.target_rtf);
  bool pass = true;
  for (const PresetFigures& p : presets) {
    const double rtf = Median(p.Column(&RunFigures::rtf));
    const double rtf_cpu = Median(p.Column(&RunFigures::rtf_cpu));
    const bool ok_wall = rtf >= o.target_rtf, ok_cpu = rtf_cpu >= o.target_rtf;
    if (&p == &presets.front()) pass = o.check_on_cpu ? ok_cpu : ok_wall;
    std::printf("  %-20s wall %7.1fx (%.2f): %s   cpu %7.1fx (%.2f): %s\n", p.name.c_str(), rtf,
                rtf / o.target_rtf, ok_wall ? "PASS" : "FAIL", rtf_cpu, rtf_cpu / o.target_rtf,
                ok_cpu ? "PASS" : "FAIL");
  }
  return o.check && !pass ? 1 : 0;
}

}  // namespace
}  // namespace skerry::bench

int main(int argc, char** argv) {
  using skerry::bench::Flags;
  Flags flags;
  flags.Declare("scenario", "harbour", "built-in scenario name or YAML path");
  flags.Declare("seed", "1", "simulation seed");
  flags.Declare("runs", "3", "timed runs per preset (figures are medians over runs)");
  flags.Declare("preset", "default",
                "preset name or YAML path; repeat to compare, the first is the reference");
  flags.Declare("compare", "", "also run lm-dense-qr and dogleg-sparse (ratio table)", true);
  flags.Declare("cpu", "-1", "pin the process to this CPU (-1: no pinning)");
  flags.Declare("duration-s", "0", "override the scenario duration (0: keep)");
  flags.Declare("target-rtf", "100", "required real-time factor");
  flags.Declare("check", "", "exit 1 if the reference preset misses the target", true);
  flags.Declare("check-on", "wall", "what --check judges: wall or cpu (a shared machine)");
  const char* summary =
      "Times the sliding-window estimator on a simulated scenario, one thread, and prints the "
      "real-time factor and window update times (see bench/README.md).";
  return skerry::bench::RunMain(flags, argc, argv, summary, [&flags]() {
    skerry::bench::Options o;
    o.scenario = flags.String("scenario");
    o.seed = static_cast<std::uint64_t>(flags.Int("seed", 0));
    o.runs = static_cast<int>(flags.Int("runs", 1));
    o.presets = flags.Strings("preset");
    if (flags.Switch("compare")) {
      for (const char* extra : {"lm-dense-qr", "dogleg-sparse"}) {
        if (std::find(o.presets.begin(), o.presets.end(), extra) == o.presets.end()) {
          o.presets.push_back(extra);
        }
      }
    }
    o.cpu = static_cast<int>(flags.Int("cpu", -1));
    o.duration_s = flags.Double("duration-s", 0.0);
    o.target_rtf = flags.Double("target-rtf", 1e-9);
    o.check = flags.Switch("check");
    const std::string check_on = flags.String("check-on");
    if (check_on != "wall" && check_on != "cpu") {
      throw skerry::bench::UsageError("--check-on: '" + check_on + "' is not wall or cpu");
    }
    o.check_on_cpu = check_on == "cpu";
    return skerry::bench::Main(o);
  });
}
