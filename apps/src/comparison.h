#pragma once
/// \file
/// Comparing estimator configurations: a plan of jobs (every configuration on every dataset,
/// over seeds for simulated scenarios), running one job, and collecting the results into one
/// table. The layout of a compare folder is in docs/compare.md:
///
///   plan.json, configs/NAME.yaml, scenarios/NAME.yaml  the plan (what `--plan` writes)
///   jobs.txt, run_parallel.sh, slurm_array.sh          runners for a scheduler
///   datasets/DATASET/seed-N/                           simulated datasets
///   runs/DATASET/CONFIG/seed-N/                        one run folder per job, + result.json
///   table.csv, table.json, runs.csv                    what `--collect` writes
///   fidelity/DATASET/CONFIG/seed-N.csv                 per-epoch Hellinger vs the reference

#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace skerry::cli {

struct CompareDataset {
  std::string name;
  std::string source;  ///< dataset folder (absolute), or scenario file relative to the plan
  bool simulated = false;
};

struct CompareConfig {
  std::string name;
  std::string file;  ///< configs/NAME.yaml, relative to the compare folder
};

struct CompareJob {
  int id = 0;
  int dataset = 0;          ///< index into ComparePlan::datasets
  int config = 0;           ///< index into ComparePlan::configs
  std::int64_t seed = 0;    ///< simulation seed; 0 for recorded datasets
  std::string dataset_dir;  ///< relative to the compare folder, or absolute for recorded data
  std::string run_dir;      ///< relative to the compare folder
};

struct ComparePlan {
  std::vector<CompareDataset> datasets;
  std::vector<CompareConfig> configs;  ///< the first is the reference of the fidelity metric
  std::vector<std::int64_t> seeds;
  std::vector<CompareJob> jobs;
  /// `out_dir` already held this very plan (same plan.json, configuration and scenario files):
  /// a sweep that was stopped, resumed by RunJobs with only the jobs that have no result.
  bool resumed = false;
};

/// Builds the plan and writes plan.json, configs/ and scenarios/ into `out_dir`.
/// `datasets`: dataset folders (with dataset.yaml) or scenario names / YAML files.
/// `configs`: preset names or YAML files, each optionally with overrides (config_variant.h);
/// their names must differ.
/// A folder holding the same plan is resumed (nothing rewritten); one holding another plan is
/// refused with an InputError unless `overwrite`, which first removes everything a comparison
/// writes there (plan, configs, scenarios, datasets, runs, fidelity, tables, runners).
ComparePlan WritePlan(const std::vector<std::string>& datasets,
                      const std::vector<std::string>& configs,
                      int seed_count,
                      std::int64_t first_seed,
                      const std::string& out_dir,
                      bool overwrite = false);

/// Jobs of `plan` whose run folder has no result.json yet (RunJob writes it last).
std::vector<int> PendingJobs(const ComparePlan& plan, const std::string& out_dir);

/// Reads `out_dir`/plan.json (InputError naming the file and field when it is malformed).
ComparePlan ReadPlan(const std::string& out_dir);

/// Where Collect writes the per-epoch fidelity of `job` against the reference configuration's
/// run of the same data, relative to the compare folder.
std::string FidelityCsvPath(const ComparePlan& plan, const CompareJob& job);

/// Runs one job: makes its simulated dataset if no job has yet, runs the sliding window and
/// writes the run folder and its result.json ({"ok": true|false, "error": ...}). Never throws
/// for a failing estimator run: a failure is a result.
void RunJob(const ComparePlan& plan, int job_id, const std::string& out_dir);

/// Runs every job without a result (PendingJobs) on `threads` threads; `progress(done, total)`
/// after each job, counting those done before.
void RunJobs(const ComparePlan& plan,
             const std::string& out_dir,
             int threads,
             const std::function<void(int, int)>& progress);

/// Writes jobs.txt (one `skerry compare --out DIR --job ID` line per job), run_parallel.sh
/// (GNU parallel, optionally over SSH hosts) and slurm_array.sh (a Slurm array job).
void WriteSchedulerFiles(const ComparePlan& plan,
                         const std::string& out_dir,
                         const std::string& skerry_binary);

struct CollectResult {
  nlohmann::json table;  ///< what table.json holds
  int missing = 0;       ///< jobs without a result.json
  int failed = 0;        ///< jobs whose result says ok = false
};

/// Reads every job's run folder and writes table.csv, table.json, runs.csv and the per-epoch
/// fidelity files.
CollectResult Collect(const std::string& out_dir);

/// The table as aligned text for the terminal.
std::string FormatTable(const nlohmann::json& table);

}  // namespace skerry::cli
