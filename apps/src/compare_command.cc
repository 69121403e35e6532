#include "compare_command.h"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "command_line_time.h"
#include "comparison.h"
#include "run_outputs.h"
#include "seed_number.h"
#include "skerry/core/input_error.h"
#include "skerry/core/time.h"
#include "skerry/eval/hellinger_floor.h"
#include "skerry/eval/run_fidelity.h"
#include "skerry/io/estimate_io.h"

namespace skerry::cli {

namespace {

namespace fs = std::filesystem;

struct CompareOptions {
  std::vector<std::string> datasets;
  std::vector<std::string> configs;
  int seeds = 1;
  std::int64_t first_seed = 1;
  int jobs = 0;  ///< 0: every core
  std::string out;
  bool plan_only = false;
  std::string collect;
  int job = -1;
  std::string skerry_binary;
  bool quiet = false;
  bool overwrite = false;
};

std::string SelfPath() {
  std::error_code ec;
  const fs::path p = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string("skerry") : p.string();
}

/// "12/30 runs [#######       ] 40%  ETA 1:05" on a terminal; a line per tenth otherwise.
class JobProgress {
 public:
  explicit JobProgress(bool quiet)
      : quiet_(quiet),
        tty_(isatty(fileno(stderr)) != 0),
        start_(std::chrono::steady_clock::now()) {}

  void operator()(int done, int total) {
    if (quiet_) return;
    const double elapsed =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
    const double eta = done > 0 ? elapsed / done * (total - done) : 0.0;
    const int percent = total > 0 ? done * 100 / total : 100;
    if (tty_) {
      const int width = 30, filled = percent * width / 100;
      std::fprintf(stderr, "\rcompare %d/%d runs [%s%s] %3d%%  ETA %d:%02d ", done, total,
                   std::string(filled, '#').c_str(), std::string(width - filled, ' ').c_str(),
                   percent, static_cast<int>(eta) / 60, static_cast<int>(eta) % 60);
      if (done == total) std::fprintf(stderr, "\n");
    } else if (percent / 10 != last_tenth_ || done == total) {
      last_tenth_ = percent / 10;
      std::fprintf(stderr, "compare: %d/%d runs done (%.0f s, ETA %.0f s)\n", done, total, elapsed,
                   eta);
    }
    std::fflush(stderr);
  }

 private:
  bool quiet_;
  bool tty_;
  std::chrono::steady_clock::time_point start_;
  int last_tenth_ = -1;
};

int PrintCollected(const CollectResult& r, const std::string& out, bool quiet) {
  if (!quiet) {
    std::printf("%s", FormatTable(r.table).c_str());
    std::printf(
        "table: %s/table.csv and table.json; per run: %s/runs.csv; report: skerry report "
        "--run %s --out report.html\n",
        out.c_str(), out.c_str(), out.c_str());
  }
  if (r.failed > 0) {
    std::fprintf(stderr, "skerry compare: %d run(s) failed (see the error column of runs.csv)\n",
                 r.failed);
  }
  if (r.missing > 0) {
    std::fprintf(stderr,
                 "skerry compare: %d job(s) have no result yet; the table counts them as failed\n",
                 r.missing);
    return 3;
  }
  return 0;
}

// What the jobs of `plan` are, as "2 scenarios x 3 seeds x 2 configurations". Seeds multiply
// only the simulated scenarios: a dataset folder is one recording and runs once, so "--seeds 5"
// over folders once printed "x 5 seeds" beside 1 job.
std::string PlanShape(const ComparePlan& plan) {
  size_t scenarios = 0;
  for (const CompareDataset& d : plan.datasets) scenarios += d.simulated ? 1 : 0;
  const size_t folders = plan.datasets.size() - scenarios;
  const size_t seeds = plan.seeds.size();
  std::string datasets;
  if (folders == 0) {
    datasets = fmt::format("{} scenario(s) x {} seed(s)", scenarios, seeds);
  } else if (scenarios == 0) {
    datasets = fmt::format("{} dataset folder(s)", folders);
  } else {
    datasets = fmt::format("{} scenario(s) x {} seed(s) + {} dataset folder(s)", scenarios, seeds,
                           folders);
  }
  std::string shape = fmt::format("{} x {} configuration(s)", datasets, plan.configs.size());
  if (scenarios == 0 && seeds > 1) {
    shape += fmt::format("; --seeds {} applies to simulated scenarios, a folder runs once", seeds);
  }
  return shape;
}

int RunCompare(const CompareOptions& o) {
  // One job of a plan (what jobs.txt runs on a scheduler's node).
  if (o.job >= 0) {
    if (o.out.empty()) throw InputError(kCommandLine, 0, "--out", "--job needs --out");
    RunJob(ReadPlan(o.out), o.job, o.out);
    return 0;
  }
  // Merge the results of a plan run elsewhere.
  if (!o.collect.empty()) {
    return PrintCollected(Collect(o.collect), o.collect, o.quiet);
  }
  if (o.out.empty()) throw InputError(kCommandLine, 0, "--out", "is required");
  const ComparePlan plan =
      WritePlan(o.datasets, o.configs, o.seeds, o.first_seed, o.out, o.overwrite);
  const std::string binary = o.skerry_binary.empty() ? SelfPath() : o.skerry_binary;
  WriteSchedulerFiles(plan, o.out, binary);
  if (o.plan_only) {
    if (!o.quiet) {
      std::printf(
          "planned %zu jobs (%s) in %s:\n"
          "  jobs.txt          one command per job\n"
          "  run_parallel.sh   GNU parallel, locally or HOSTS=hosts.txt over SSH\n"
          "  slurm_array.sh    sbatch slurm_array.sh (a Slurm array job)\n"
          "then: skerry compare --collect %s\n",
          plan.jobs.size(), PlanShape(plan).c_str(), o.out.c_str(), o.out.c_str());
    }
    return 0;
  }
  const int threads =
      o.jobs > 0 ? o.jobs : std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
  if (!o.quiet) {
    std::printf("skerry compare: %zu runs (%s) on %d threads\n", plan.jobs.size(),
                PlanShape(plan).c_str(), threads);
    if (plan.resumed) {
      std::printf("  resuming the sweep in %s: %zu of %zu runs have their results already\n",
                  o.out.c_str(), plan.jobs.size() - PendingJobs(plan, o.out).size(),
                  plan.jobs.size());
    }
    std::fflush(stdout);
  }
  JobProgress progress(o.quiet);
  RunJobs(plan, o.out, threads, [&progress](int done, int total) { progress(done, total); });
  return PrintCollected(Collect(o.out), o.out, o.quiet);
}

struct FidelityOptions {
  std::string a, b;
  std::string csv;
  double tolerance_s = 1e-3;
  double offset_s = 0.0;
  bool align_start = false;
};

int RunFidelity(const FidelityOptions& o) {
  const TimeNs offset_ns = CommandLineTime(o.offset_s, "--offset");
  // CompareRuns' own range, said of the option (its std::invalid_argument exited 1).
  if (!(o.tolerance_s >= 0.0 && o.tolerance_s <= 3600.0)) {
    throw InputError(kCommandLine, 0, "--tolerance", "must be in [0, 3600] s");
  }
  const std::vector<EstimateRecord> a = ReadRunEstimate(o.a);
  std::vector<EstimateRecord> b = ReadRunEstimate(o.b);
  // Real and simulated recordings of one scenario rarely share a clock: B's times can be moved
  // by a given offset, or so that its first epoch falls on A's.
  TimeNs shift = offset_ns;
  if (o.align_start && !a.empty() && !b.empty())
    shift = a.front().state.t_ns - b.front().state.t_ns;
  for (EstimateRecord& r : b) r.state.t_ns += shift;
  if (shift != 0) std::printf("B's times moved by %+.6f s\n", NsToSeconds(shift));
  const FidelityResult r = CompareRuns(a, b, o.tolerance_s);
  std::printf("fidelity of %s vs %s: %d epochs, both valid at %d, only one at %d (%.1f%%)\n",
              o.b.c_str(), o.a.c_str(), r.total, r.both_valid, r.only_a + r.only_b,
              100.0 * r.share_one_valid);
  // The floor: what two independent noise realisations through one consistent estimator score
  // (hellinger_floor.h); an AHED near it says nothing differs but the noise.
  std::printf("  %-9s %8s %8s %8s %8s %8s %8s\n", "block", "AHED", "max HED", "MEANDIFF", "COVDIFF",
              "Bhatt.", "floor");
  for (int b = 0; b < kNumFidelityBlocks; ++b) {
    const FidelityBlockSummary& s = r.blocks[b];
    const auto block = static_cast<FidelityBlock>(b);
    std::printf("  %-9s %8.4f %8.4f %8.4f %8.4f %8.4f %8.4f\n", FidelityBlockName(block), s.ahed,
                s.max_hed, s.mean_meandiff, s.mean_covdiff, s.mean_bhattacharyya,
                ConsistentRunsHellingerFloor(FidelityBlockDimension(block)).mean_hed);
  }
  std::printf(
      "  (MEANDIFF, COVDIFF: the HED of the means alone and of the covariances alone; floor: the "
      "mean HED of two independent noise realisations through one consistent estimator, "
      "docs/fidelity.md)\n");
  if (!o.csv.empty()) {
    WriteFidelityCsv(o.csv, r);
    std::printf("per-epoch distances in %s\n", o.csv.c_str());
  }
  return 0;
}

}  // namespace

Subcommand AddFidelityCommand(CLI::App& app) {
  auto o = std::make_shared<FidelityOptions>();
  CLI::App* cmd = app.add_subcommand(
      "fidelity",
      "Hellinger distance per state block between two runs (two configurations, or real vs "
      "simulated data of one scenario; docs/fidelity.md)");
  cmd->add_option("--a", o->a, "Reference run folder (states.csv, covariances.csv)")->required();
  cmd->add_option("--b", o->b, "Other run folder")->required();
  cmd->add_option("--csv", o->csv, "Write the per-epoch distances here");
  cmd->add_option("--offset", o->offset_s, "Add this to B's times (s) before matching epochs");
  cmd->add_flag("--align-start", o->align_start,
                "Move B's times so its first epoch falls on A's (recordings on other clocks)");
  cmd->add_option("--tolerance", o->tolerance_s, "Epochs this close (s) are the same epoch")
      ->capture_default_str();
  Subcommand s;
  s.app = cmd;
  s.run = [o]() { return RunFidelity(*o); };
  return s;
}

Subcommand AddCompareCommand(CLI::App& app) {
  auto o = std::make_shared<CompareOptions>();
  CLI::App* cmd = app.add_subcommand(
      "compare",
      "Run every configuration on every dataset (over seeds for simulated scenarios) and tabulate "
      "accuracy, consistency, speed and Hellinger fidelity (docs/compare.md)");
  cmd->add_option("--dataset", o->datasets,
                  "Dataset folder, or scenario name / YAML file to simulate (repeatable)");
  cmd->add_option("--config", o->configs,
                  "Preset name or YAML file, optionally with keys changed as --set changes them: "
                  "SOURCE,KEY=VALUE,... (e.g. default,skyline.dem_sharpening_sigma=1, named "
                  "default-dem_sharpening_sigma-1 unless a name= is given); repeatable, the "
                  "first is the reference");
  cmd->add_option("--seeds", o->seeds, "Seeds per simulated scenario")->capture_default_str();
  cmd->add_option("--first-seed", o->first_seed, "First seed")
      // Half the int64 range, so that first + count seeds stay within it.
      ->check(SeedNumber(std::numeric_limits<std::int64_t>::max() / 2))
      ->capture_default_str();
  cmd->add_option("-j,--jobs", o->jobs, "Parallel runs (default: every core)");
  cmd->add_option("--out", o->out, "Compare folder");
  cmd->add_flag("--plan", o->plan_only,
                "Only write the plan, jobs.txt and runners for GNU parallel / Slurm");
  cmd->add_option("--collect", o->collect, "Merge the results of a plan's jobs in this folder");
  cmd->add_option("--job", o->job, "Run job ID of the plan in --out (used by jobs.txt)");
  cmd->add_option("--skerry-binary", o->skerry_binary,
                  "skerry path written into jobs.txt (default: this binary)");
  cmd->add_flag("-q,--quiet", o->quiet, "No progress or table on the terminal");
  cmd->add_flag("--overwrite", o->overwrite,
                "Replace a comparison of another plan in --out (the same plan is resumed)");
  Subcommand s;
  s.app = cmd;
  s.run = [o]() { return RunCompare(*o); };
  return s;
}

}  // namespace skerry::cli
