#include "comparison.h"

#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <regex>
#include <sstream>
#include <thread>

#include "config_variant.h"
#include "run_outputs.h"
#include "skerry/core/input_error.h"
#include "skerry/eval/evaluation.h"
#include "skerry/eval/event_metrics.h"
#include "skerry/eval/run_fidelity.h"
#include "skerry/frontends/dataset_sensors.h"
#include "skerry/io/atomic_file.h"
#include "skerry/io/csv_reader.h"
#include "skerry/io/dataset.h"
#include "skerry/io/estimate_io.h"
#include "skerry/io/trajectory.h"
#include "skerry/sim/aerial_render.h"
#include "skerry/sim/lidar_scans.h"
#include "skerry/sim/scenario.h"
#include "skerry/sim/simulator.h"
#include "skerry/solvers/estimator_config.h"
#include "skerry/solvers/pipeline.h"

namespace skerry::cli {

namespace fs = std::filesystem;

namespace {

/// Names become folder names: keep them to a portable alphabet.
void CheckName(const std::string& name, const std::string& what, const std::string& field) {
  static const std::regex ok("[A-Za-z0-9._-]+");
  if (!std::regex_match(name, ok) || name == "." || name == "..") {
    throw InputError(kCommandLine, 0, field,
                     what + " name '" + name +
                         "' cannot be a folder name (letters, digits, '.', '_', '-' only)");
  }
}

std::string FolderName(const std::string& dir) {
  fs::path p = fs::path(dir).lexically_normal();
  if (p.filename().empty()) p = p.parent_path();
  return p.filename().string();
}

std::string SeedFolder(std::int64_t seed, bool simulated) {
  return simulated ? "seed-" + std::to_string(seed) : "recorded";
}

void WriteTextFile(const fs::path& path, const std::string& text) {
  fs::create_directories(path.parent_path());
  WriteFileAtomically(path.string(), text);
}

/// A required member of a plan.json object, with an error naming it when absent or mistyped.
template <typename T>
T Member(const nlohmann::json& j, const char* key, const std::string& file, const std::string& at) {
  if (!j.is_object() || !j.contains(key)) {
    throw InputError(file, 0, at + key, "missing");
  }
  try {
    return j.at(key).get<T>();
  } catch (const nlohmann::json::exception&) {
    throw InputError(file, 0, at + key, "has the wrong type");
  }
}

/// A path member of a plan.json object (a folder or file the comparison reads or writes), with an
/// error naming it when it is empty, holds a NUL byte, or names what no file system can hold (a
/// component over 255 bytes, the whole over 4095): std::filesystem would throw on such a name
/// (ENAMETOOLONG) where the plan's reader must say which field is wrong.
std::string PlanPath(const nlohmann::json& j,
                     const char* key,
                     const std::string& file,
                     const std::string& at) {
  const std::string path = Member<std::string>(j, key, file, at);
  if (path.empty()) throw InputError(file, 0, at + key, "is empty");
  if (path.find('\0') != std::string::npos) {
    throw InputError(file, 0, at + key, "holds a NUL byte");
  }
  if (path.size() > 4095) {
    throw InputError(file, 0, at + key, "is longer than a path can be (4095 bytes)");
  }
  size_t start = 0;
  while (start <= path.size()) {
    const size_t end = std::min(path.find('/', start), path.size());
    if (end - start > 255) {
      throw InputError(file, 0, at + key,
                       "has a name longer than a file system holds (255 bytes) in it");
    }
    start = end + 1;
  }
  return path;
}

fs::path Resolve(const std::string& out_dir, const std::string& path) {
  const fs::path p(path);
  return p.is_absolute() ? p : fs::path(out_dir) / p;
}

std::mutex& SimulationMutex() {
  static std::mutex m;
  return m;
}

/// Makes the simulated dataset of a job unless it exists. Jobs of other configurations (in this
/// process or on other machines) may race for it: each writes a private folder and renames it
/// into place, so the folder is either absent or complete.
void EnsureSimulated(const CompareDataset& dataset,
                     std::int64_t seed,
                     const std::string& out_dir,
                     const fs::path& dataset_dir,
                     int job_id) {
  std::lock_guard<std::mutex> lock(SimulationMutex());
  if (fs::exists(dataset_dir / "dataset.yaml")) return;
  const fs::path scenario_file = Resolve(out_dir, dataset.source);
  const sim::ScenarioConfig scenario =
      sim::LoadScenario(fs::exists(scenario_file) ? scenario_file.string() : dataset.source);
  Dataset data = sim::Simulate(scenario, static_cast<std::uint64_t>(seed));
  // Camera frames go beside the dataset folder (its folder is renamed into place below).
  if (!data.cameras.empty()) {
    sim::RenderCameraImages(scenario, static_cast<std::uint64_t>(seed), &data,
                            dataset_dir.string() + ".images");
  }
  // The harbour's photograph and LiDAR scans go there too.
  sim::RenderAerialImage(scenario, static_cast<std::uint64_t>(seed), &data,
                         dataset_dir.string() + ".images");
  if (!data.lidars.empty()) {
    sim::RenderLidarScans(scenario, static_cast<std::uint64_t>(seed), &data,
                          dataset_dir.string() + ".images");
  }
  const fs::path tmp =
      dataset_dir.string() + ".tmp-" + std::to_string(getpid()) + "-" + std::to_string(job_id);
  fs::remove_all(tmp);
  WriteDataset(data, tmp.string());
  std::error_code ec;
  fs::rename(tmp, dataset_dir, ec);
  if (ec) {
    fs::remove_all(tmp);
    if (!fs::exists(dataset_dir / "dataset.yaml")) {
      throw std::runtime_error("cannot move the simulated dataset into " + dataset_dir.string() +
                               ": " + ec.message());
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Collecting.

struct RunFigures {
  bool has_result = false;
  bool ok = false;
  std::string error;
  std::vector<EstimateRecord> records;
  std::optional<EvaluationResult> evaluation;
  std::optional<EventMetrics> events;
  std::vector<double> update_ms;
  std::vector<double> iterations;  ///< of updates that solved
  int solve_failures = 0;
  int valid_epochs = 0;
  int expected_epochs = 0;
  TimeNs keyframe_period_ns = 0;
  double wall_s = 0.0;
  std::optional<FidelityResult> fidelity;  ///< vs the reference configuration's run
};

void ReadUpdates(const fs::path& path, RunFigures& f) {
  if (!fs::exists(path)) return;
  CsvReader csv(path.string(), {"t", "update_ms", "solved", "solve_ms", "iterations", "usable"});
  while (csv.Next()) {
    f.update_ms.push_back(csv.GetDouble(1));
    if (csv.GetDouble(2) != 0.0) {
      f.iterations.push_back(csv.GetDouble(4));
      if (csv.GetDouble(5) == 0.0) ++f.solve_failures;
    }
  }
}

RunFigures ReadRunOf(const ComparePlan& plan, const CompareJob& job, const std::string& out_dir) {
  RunFigures f;
  const fs::path run_dir = Resolve(out_dir, job.run_dir);
  const fs::path result_path = run_dir / "result.json";
  if (!fs::exists(result_path)) return f;
  f.has_result = true;
  const nlohmann::json result = ReadJsonFile(result_path.string());
  f.ok = result.value("ok", false);
  f.error = result.value("error", std::string());
  f.wall_s = result.value("wall_s", 0.0);
  const fs::path dataset_dir = Resolve(out_dir, job.dataset_dir);
  const EstimatorConfig config =
      LoadEstimatorConfig(Resolve(out_dir, plan.configs[job.config].file).string());
  f.keyframe_period_ns = SecondsToNs(1.0 / config.keyframe_rate_hz);
  if (fs::exists(run_dir / "summary.json")) {
    const nlohmann::json summary = ReadJsonFile((run_dir / "summary.json").string());
    const double data_s = summary.value("timing", nlohmann::json::object()).value("data_s", 0.0);
    f.expected_epochs = static_cast<int>(std::floor(data_s * config.keyframe_rate_hz)) + 1;
  }
  if (!f.ok) return f;
  f.records = ReadRunEstimate(run_dir.string());
  for (const EstimateRecord& r : f.records) f.valid_epochs += IsValidEstimate(r) ? 1 : 0;
  ReadUpdates(run_dir / "updates.csv", f);
  const fs::path gt = dataset_dir / "groundtruth.tum";
  if (fs::exists(gt)) {
    f.evaluation = Evaluate(f.records, ReadTum(gt.string()));
    const fs::path events = dataset_dir / "events.csv";
    if (fs::exists(events)) {
      f.events = ComputeEventMetrics(*f.evaluation, ReadEventsCsv(events.string()), 30.0, 10.0);
    }
  }
  return f;
}

RunFigures ReadRun(const ComparePlan& plan, const CompareJob& job, const std::string& out_dir) {
  return WithJsonErrorsIn(Resolve(out_dir, job.run_dir).string(),
                          [&] { return ReadRunOf(plan, job, out_dir); });
}

/// Pools RMSE and max over runs: sqrt(sum n_i rmse_i^2 / sum n_i) is the RMSE of all epochs.
struct PooledStats {
  double sum_sq = 0.0;
  int count = 0;
  double max = 0.0;
  void Add(const Stats& s) {
    sum_sq += s.count * s.rmse * s.rmse;
    count += s.count;
    max = std::max(max, s.max);
  }
  nlohmann::json Rmse() const {
    return count > 0 ? nlohmann::json(std::sqrt(sum_sq / count)) : nlohmann::json();
  }
  nlohmann::json Max() const { return count > 0 ? nlohmann::json(max) : nlohmann::json(); }
};

/// Consistent when at least 90 % of epochs are inside their 95 % bounds (the ideal is 95 %);
/// otherwise over- or underconfident by which side the epochs fall out on.
std::string Consistency(const NeesTest& test) {
  if (test.epochs == 0) return "n/a";
  if (test.inside >= 0.90) return "consistent";
  return test.above > test.below ? "overconfident" : "underconfident";
}

nlohmann::json PerRunJson(const CompareJob& job, const RunFigures& f, bool reference) {
  nlohmann::json j;
  j["seed"] = job.seed;
  j["run_dir"] = job.run_dir;
  j["ok"] = f.ok;
  if (!f.has_result) j["error"] = "no result (job not run)";
  if (!f.error.empty()) j["error"] = f.error;
  j["wall_s"] = f.wall_s;
  j["valid_epochs"] = f.valid_epochs;
  j["expected_epochs"] = f.expected_epochs;
  j["share_valid"] = f.expected_epochs > 0
                         ? std::min(1.0, static_cast<double>(f.valid_epochs) / f.expected_epochs)
                         : 0.0;
  if (f.evaluation) {
    const EvaluationResult& ev = *f.evaluation;
    j["horizontal_rmse_m"] = ev.horizontal.rmse;
    j["horizontal_max_m"] = ev.horizontal.max;
    j["position_rmse_m"] = ev.position3d.rmse;
    j["position_max_m"] = ev.position3d.max;
    j["heading_rmse_deg"] = ev.heading_deg.rmse;
    j["heading_max_deg"] = ev.heading_deg.max;
    j["rpe_translation_m"] = ev.rpe_trans_m.rmse;
    j["rpe_rotation_deg"] = ev.rpe_rot_deg.rmse;
    if (ev.nees_count > 0) {
      j["anees_position"] = ev.anees_pos;
      j["nees_count"] = ev.nees_count;
      j["nees_effective_count"] = ev.nees_effective_count;
    }
  }
  if (f.events) {
    j["horizontal_rmse_outside_outages_m"] = f.events->horizontal_outside_outages.rmse;
    double outage_end = 0.0, jump_max = 0.0;
    for (const OutageMetric& o : f.events->outages) {
      if (std::isfinite(o.horizontal_error_at_end_m)) {
        outage_end = std::max(outage_end, o.horizontal_error_at_end_m);
      }
    }
    for (const JumpMetric& m : f.events->jumps) {
      if (std::isfinite(m.max_horizontal_error_m))
        jump_max = std::max(jump_max, m.max_horizontal_error_m);
    }
    if (!f.events->outages.empty()) j["outage_end_error_m"] = outage_end;
    if (!f.events->jumps.empty()) j["jump_max_error_m"] = jump_max;
  }
  if (!f.update_ms.empty()) {
    const nlohmann::json d = DistributionJson(f.update_ms);
    j["update_ms_median"] = d["median"];
    j["update_ms_p95"] = d["p95"];
    j["update_ms_max"] = d["max"];
  }
  if (!f.iterations.empty()) {
    double sum = 0.0;
    for (double it : f.iterations) sum += it;
    j["iterations_mean"] = sum / f.iterations.size();
  }
  j["solve_failures"] = f.solve_failures;
  for (int b = 0; b < kNumFidelityBlocks; ++b) {
    const std::string key = std::string("ahed_") + FidelityBlockName(static_cast<FidelityBlock>(b));
    j[key] = nullptr;
    if (!reference && f.fidelity && f.fidelity->blocks[b].count > 0) {
      j[key] = f.fidelity->blocks[b].ahed;
    }
  }
  j["share_one_valid"] =
      (!reference && f.fidelity) ? nlohmann::json(f.fidelity->share_one_valid) : nlohmann::json();
  return j;
}

/// One table row: every run of a configuration on a dataset, pooled over epochs.
nlohmann::json TableRow(const std::string& dataset,
                        const std::string& config,
                        bool reference,
                        const std::vector<const RunFigures*>& runs,
                        const nlohmann::json& per_run) {
  nlohmann::json row;
  row["dataset"] = dataset;
  row["config"] = config;
  row["reference"] = reference;
  row["runs"] = runs.size();
  PooledStats horizontal, position, heading, rpe_t, rpe_r, outside;
  double nees_sum = 0.0;
  int nees_count = 0, failed = 0, solve_failures = 0, valid = 0, expected = 0;
  double nees_effective = 0.0;
  std::vector<double> update_ms, outage_end, jump_max;
  double iter_sum = 0.0, iter_max = 0.0;
  int iter_count = 0;
  std::vector<double> ahed_sum(kNumFidelityBlocks, 0.0);
  std::vector<int> ahed_count(kNumFidelityBlocks, 0);
  int one_valid = 0, fidelity_total = 0;
  for (const RunFigures* f : runs) {
    if (!f->ok) ++failed;
    expected += f->expected_epochs;
    valid += f->valid_epochs;
    solve_failures += f->solve_failures;
    update_ms.insert(update_ms.end(), f->update_ms.begin(), f->update_ms.end());
    for (double it : f->iterations) {
      iter_sum += it;
      iter_max = std::max(iter_max, it);
      ++iter_count;
    }
    if (f->evaluation) {
      const EvaluationResult& ev = *f->evaluation;
      horizontal.Add(ev.horizontal);
      position.Add(ev.position3d);
      heading.Add(ev.heading_deg);
      rpe_t.Add(ev.rpe_trans_m);
      rpe_r.Add(ev.rpe_rot_deg);
      nees_sum += ev.anees_pos * ev.nees_count;
      nees_count += ev.nees_count;
      nees_effective += ev.nees_effective_count;  // runs are independent of each other
    }
    if (f->events) {
      outside.Add(f->events->horizontal_outside_outages);
      for (const OutageMetric& o : f->events->outages) {
        if (std::isfinite(o.horizontal_error_at_end_m)) {
          outage_end.push_back(o.horizontal_error_at_end_m);
        }
      }
      for (const JumpMetric& m : f->events->jumps) {
        if (std::isfinite(m.max_horizontal_error_m)) jump_max.push_back(m.max_horizontal_error_m);
      }
    }
    if (!reference && f->fidelity) {
      for (int b = 0; b < kNumFidelityBlocks; ++b) {
        ahed_sum[b] += f->fidelity->blocks[b].ahed * f->fidelity->blocks[b].count;
        ahed_count[b] += f->fidelity->blocks[b].count;
      }
      one_valid += f->fidelity->only_a + f->fidelity->only_b;
      fidelity_total += f->fidelity->total;
    }
  }
  row["failed_runs"] = failed;
  row["horizontal_rmse_m"] = horizontal.Rmse();
  row["horizontal_max_m"] = horizontal.Max();
  row["position_rmse_m"] = position.Rmse();
  row["position_max_m"] = position.Max();
  row["heading_rmse_deg"] = heading.Rmse();
  row["heading_max_deg"] = heading.Max();
  row["rpe_translation_m"] = rpe_t.Rmse();
  row["rpe_rotation_deg"] = rpe_r.Rmse();
  if (outside.count > 0) row["horizontal_rmse_outside_outages_m"] = outside.Rmse();
  if (!outage_end.empty()) {
    row["outage_end_error_m"] = {{"median", ComputeStats(outage_end).median},
                                 {"max", *std::max_element(outage_end.begin(), outage_end.end())}};
  }
  if (!jump_max.empty()) {
    row["jump_max_error_m"] = *std::max_element(jump_max.begin(), jump_max.end());
  }
  if (nees_count > 0) {
    const double anees = nees_sum / nees_count;
    const auto bounds = AneesBounds(3, nees_effective);
    row["anees_position"] = anees;
    row["nees_count"] = nees_count;
    row["nees_effective_count"] = nees_effective;
    row["anees_bounds_95"] = {bounds.first, bounds.second};
    std::vector<const EvaluationResult*> evaluations;
    TimeNs period = 0;
    for (const RunFigures* f : runs) {
      if (f->evaluation) evaluations.push_back(&*f->evaluation);
      period = std::max(period, f->keyframe_period_ns);
    }
    // Keyframes of runs on different seeds, matched to the keyframe grid.
    const NeesTest test = MonteCarloNeesTest(evaluations, 1, 0.95, period);
    row["nees_epochs"] = test.epochs;
    row["nees_inside_95"] = test.inside;
    row["nees_above_95"] = test.above;
    row["nees_below_95"] = test.below;
    row["consistency"] = Consistency(test);
  } else {
    row["anees_position"] = nullptr;
    row["anees_bounds_95"] = nullptr;
    row["consistency"] = "n/a";
  }
  const nlohmann::json d = DistributionJson(update_ms);
  row["update_ms"] = {{"median", d.value("median", nlohmann::json())},
                      {"p95", d.value("p95", nlohmann::json())},
                      {"max", d.value("max", nlohmann::json())}};
  row["iterations"] = {{"mean", iter_count ? nlohmann::json(iter_sum / iter_count) : nullptr},
                       {"max", iter_count ? nlohmann::json(iter_max) : nullptr}};
  row["solve_failures"] = solve_failures;
  row["share_valid"] = expected > 0 ? std::min(1.0, static_cast<double>(valid) / expected) : 0.0;
  if (reference) {
    row["ahed"] = nullptr;
    row["share_one_valid"] = nullptr;
  } else {
    nlohmann::json ahed;
    for (int b = 0; b < kNumFidelityBlocks; ++b) {
      ahed[FidelityBlockName(static_cast<FidelityBlock>(b))] =
          ahed_count[b] > 0 ? nlohmann::json(ahed_sum[b] / ahed_count[b]) : nlohmann::json();
    }
    row["ahed"] = ahed;
    row["share_one_valid"] = fidelity_total > 0
                                 ? nlohmann::json(static_cast<double>(one_valid) / fidelity_total)
                                 : nlohmann::json();
  }
  row["per_run"] = per_run;
  return row;
}

std::string CsvCell(const nlohmann::json& v) {
  if (v.is_null()) return "";
  if (v.is_boolean()) return v.get<bool>() ? "1" : "0";
  if (v.is_number_integer() || v.is_number_unsigned()) return v.dump();
  if (v.is_number()) {
    char buf[32];
    std::snprintf(buf, sizeof(buf), "%.6g", v.get<double>());
    return buf;
  }
  std::string s = v.is_string() ? v.get<std::string>() : v.dump();
  if (s.find_first_of(",\"\n") != std::string::npos) {
    std::string q = "\"";
    for (char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
    return q + "\"";
  }
  return s;
}

/// A json value at a '/'-separated path ("update_ms/median"), null when absent.
nlohmann::json At(const nlohmann::json& j, const std::string& path) {
  const nlohmann::json* cur = &j;
  std::stringstream ss(path);
  std::string key;
  while (std::getline(ss, key, '/')) {
    if (cur->is_array()) {
      const size_t i = std::stoul(key);
      if (i >= cur->size()) return nullptr;
      cur = &(*cur)[i];
    } else if (cur->is_object() && cur->contains(key)) {
      cur = &(*cur)[key];
    } else {
      return nullptr;
    }
  }
  return *cur;
}

void WriteCsv(const fs::path& path,
              const std::vector<std::pair<std::string, std::string>>& columns,
              const std::vector<nlohmann::json>& rows) {
  std::ostringstream out;
  for (size_t c = 0; c < columns.size(); ++c) out << (c ? "," : "") << columns[c].first;
  out << "\n";
  for (const nlohmann::json& row : rows) {
    for (size_t c = 0; c < columns.size(); ++c) {
      out << (c ? "," : "") << CsvCell(At(row, columns[c].second));
    }
    out << "\n";
  }
  WriteTextFile(path, out.str());
}

std::vector<std::pair<std::string, std::string>> TableColumns() {
  std::vector<std::pair<std::string, std::string>> c = {
      {"dataset", "dataset"},
      {"config", "config"},
      {"reference", "reference"},
      {"runs", "runs"},
      {"failed_runs", "failed_runs"},
      {"horizontal_rmse_m", "horizontal_rmse_m"},
      {"horizontal_max_m", "horizontal_max_m"},
      {"position_rmse_m", "position_rmse_m"},
      {"position_max_m", "position_max_m"},
      {"heading_rmse_deg", "heading_rmse_deg"},
      {"heading_max_deg", "heading_max_deg"},
      {"rpe_translation_m", "rpe_translation_m"},
      {"rpe_rotation_deg", "rpe_rotation_deg"},
      {"horizontal_rmse_outside_outages_m", "horizontal_rmse_outside_outages_m"},
      {"outage_end_error_median_m", "outage_end_error_m/median"},
      {"outage_end_error_max_m", "outage_end_error_m/max"},
      {"jump_max_error_m", "jump_max_error_m"},
      {"anees_position", "anees_position"},
      {"anees_lower_95", "anees_bounds_95/0"},
      {"anees_upper_95", "anees_bounds_95/1"},
      {"nees_effective_count", "nees_effective_count"},
      {"nees_inside_95", "nees_inside_95"},
      {"nees_above_95", "nees_above_95"},
      {"nees_below_95", "nees_below_95"},
      {"consistency", "consistency"},
      {"update_ms_median", "update_ms/median"},
      {"update_ms_p95", "update_ms/p95"},
      {"update_ms_max", "update_ms/max"},
      {"iterations_mean", "iterations/mean"},
      {"iterations_max", "iterations/max"},
      {"solve_failures", "solve_failures"},
      {"share_valid", "share_valid"}};
  for (int b = 0; b < kNumFidelityBlocks; ++b) {
    const std::string name = FidelityBlockName(static_cast<FidelityBlock>(b));
    c.emplace_back("ahed_" + name, "ahed/" + name);
  }
  c.emplace_back("share_one_valid", "share_one_valid");
  return c;
}

std::vector<std::pair<std::string, std::string>> RunColumns() {
  std::vector<std::pair<std::string, std::string>> c = {
      {"dataset", "dataset"},
      {"config", "config"},
      {"seed", "seed"},
      {"ok", "ok"},
      {"error", "error"},
      {"run_dir", "run_dir"},
      {"horizontal_rmse_m", "horizontal_rmse_m"},
      {"horizontal_max_m", "horizontal_max_m"},
      {"position_rmse_m", "position_rmse_m"},
      {"position_max_m", "position_max_m"},
      {"heading_rmse_deg", "heading_rmse_deg"},
      {"heading_max_deg", "heading_max_deg"},
      {"rpe_translation_m", "rpe_translation_m"},
      {"rpe_rotation_deg", "rpe_rotation_deg"},
      {"horizontal_rmse_outside_outages_m", "horizontal_rmse_outside_outages_m"},
      {"outage_end_error_m", "outage_end_error_m"},
      {"jump_max_error_m", "jump_max_error_m"},
      {"anees_position", "anees_position"},
      {"nees_count", "nees_count"},
      {"nees_effective_count", "nees_effective_count"},
      {"update_ms_median", "update_ms_median"},
      {"update_ms_p95", "update_ms_p95"},
      {"update_ms_max", "update_ms_max"},
      {"iterations_mean", "iterations_mean"},
      {"solve_failures", "solve_failures"},
      {"share_valid", "share_valid"},
      {"wall_s", "wall_s"}};
  for (int b = 0; b < kNumFidelityBlocks; ++b) {
    const std::string key = std::string("ahed_") + FidelityBlockName(static_cast<FidelityBlock>(b));
    c.emplace_back(key, key);
  }
  c.emplace_back("share_one_valid", "share_one_valid");
  return c;
}

}  // namespace

// ---------------------------------------------------------------------------------------------

ComparePlan WritePlan(const std::vector<std::string>& datasets,
                      const std::vector<std::string>& configs,
                      int seed_count,
                      std::int64_t first_seed,
                      const std::string& out_dir,
                      bool overwrite) {
  if (datasets.empty()) throw InputError(kCommandLine, 0, "--dataset", "give at least one");
  if (configs.empty()) throw InputError(kCommandLine, 0, "--config", "give at least one");
  if (seed_count < 1) throw InputError(kCommandLine, 0, "--seeds", "must be at least 1");
  ComparePlan plan;
  for (int i = 0; i < seed_count; ++i) plan.seeds.push_back(first_seed + i);
  fs::create_directories(out_dir);
  std::map<std::string, int> dataset_names, config_names;
  // Everything the plan consists of, written at the end unless the folder holds it already.
  std::map<std::string, std::string> files;
  for (const std::string& source : datasets) {
    CompareDataset d;
    if (fs::is_directory(source)) {
      if (!fs::exists(fs::path(source) / "dataset.yaml")) {
        throw InputError(source, 0, "--dataset",
                         "is a folder without dataset.yaml (docs/dataset-format.md)");
      }
      d.simulated = false;
      // Refused now, not in every job: a dataset without IMU (a marine log's) cannot be run.
      RequireImu(LoadDataset(source, DatasetParts::kWithoutStreams), "compare");
      d.name = FolderName(source);
      d.source = fs::absolute(source).lexically_normal().string();
    } else {
      const sim::ScenarioConfig scenario = sim::LoadScenario(source);
      d.simulated = true;
      d.name = scenario.name;
      if (fs::is_regular_file(source)) {
        // A scenario file travels with the plan, so jobs on other machines find it.
        d.source = "scenarios/" + d.name + ".yaml";
        files[d.source] = ReadTextFile(source);
      } else {
        d.source = source;
      }
    }
    CheckName(d.name, "dataset", "--dataset");
    if (dataset_names.count(d.name)) {
      throw InputError(kCommandLine, 0, "--dataset", "two datasets are named '" + d.name + "'");
    }
    dataset_names[d.name] = static_cast<int>(plan.datasets.size());
    plan.datasets.push_back(d);
  }
  for (const std::string& source : configs) {
    const EstimatorConfig config = LoadConfigVariant(source, "--config");
    CheckName(config.name, "configuration", "--config");
    if (config_names.count(config.name)) {
      throw InputError(
          kCommandLine, 0, "--config",
          "two configurations are named '" + config.name + "'; give each YAML its own `name:`");
    }
    config_names[config.name] = static_cast<int>(plan.configs.size());
    CompareConfig c{config.name, "configs/" + config.name + ".yaml"};
    files[c.file] = ToYaml(config);
    plan.configs.push_back(c);
  }
  for (int d = 0; d < static_cast<int>(plan.datasets.size()); ++d) {
    const CompareDataset& ds = plan.datasets[d];
    const std::vector<std::int64_t> seeds =
        ds.simulated ? plan.seeds : std::vector<std::int64_t>{0};
    for (std::int64_t seed : seeds) {
      for (int c = 0; c < static_cast<int>(plan.configs.size()); ++c) {
        CompareJob job;
        job.id = static_cast<int>(plan.jobs.size());
        job.dataset = d;
        job.config = c;
        job.seed = seed;
        job.dataset_dir =
            ds.simulated ? "datasets/" + ds.name + "/" + SeedFolder(seed, true) : ds.source;
        job.run_dir =
            "runs/" + ds.name + "/" + plan.configs[c].name + "/" + SeedFolder(seed, ds.simulated);
        plan.jobs.push_back(job);
      }
    }
  }
  nlohmann::json j;
  j["format"] = "skerry-compare-plan/1";
  j["reference_config"] = plan.configs.front().name;
  j["seeds"] = plan.seeds;
  for (const CompareDataset& d : plan.datasets) {
    j["datasets"].push_back({{"name", d.name}, {"source", d.source}, {"simulated", d.simulated}});
  }
  for (const CompareConfig& c : plan.configs) {
    j["configs"].push_back({{"name", c.name}, {"file", c.file}});
  }
  for (const CompareJob& job : plan.jobs) {
    j["jobs"].push_back({{"id", job.id},
                         {"dataset", plan.datasets[job.dataset].name},
                         {"config", plan.configs[job.config].name},
                         {"seed", job.seed},
                         {"dataset_dir", job.dataset_dir},
                         {"run_dir", job.run_dir}});
  }
  files["plan.json"] = j.dump(2) + "\n";
  const fs::path plan_path = fs::path(out_dir) / "plan.json";
  if (fs::exists(plan_path)) {
    bool same = true;
    for (const auto& [name, text] : files) {
      const fs::path p = fs::path(out_dir) / name;
      same = same && fs::exists(p) && ReadTextFile(p.string()) == text;
    }
    if (same) {
      plan.resumed = true;
      return plan;
    }
    if (!overwrite) {
      throw InputError(plan_path.string(), 0, "--out",
                       "the folder holds a comparison of other datasets, configurations, seeds "
                       "or files; give --overwrite to replace it, or another --out folder");
    }
    // plan.json first: a folder without it is no comparison, whatever else survives a kill.
    for (const char* name :
         {"plan.json", "table.csv", "table.json", "runs.csv", "jobs.txt", "run_parallel.sh",
          "slurm_array.sh", "runs", "datasets", "fidelity", "configs", "scenarios"}) {
      fs::remove_all(fs::path(out_dir) / name);
    }
  }
  for (const auto& [name, text] : files) {
    if (name != "plan.json") WriteTextFile(fs::path(out_dir) / name, text);
  }
  WriteTextFile(plan_path, files["plan.json"]);
  return plan;
}

std::vector<int> PendingJobs(const ComparePlan& plan, const std::string& out_dir) {
  std::vector<int> pending;
  for (const CompareJob& job : plan.jobs) {
    if (!fs::exists(Resolve(out_dir, job.run_dir) / "result.json")) pending.push_back(job.id);
  }
  return pending;
}

std::string FidelityCsvPath(const ComparePlan& plan, const CompareJob& job) {
  const CompareDataset& ds = plan.datasets[job.dataset];
  return "fidelity/" + ds.name + "/" + plan.configs[job.config].name + "/" +
         SeedFolder(job.seed, ds.simulated) + ".csv";
}

ComparePlan ReadPlan(const std::string& out_dir) {
  const fs::path path = fs::path(out_dir) / "plan.json";
  if (!fs::exists(path)) {
    throw InputError(path.string(), 0, "file",
                     "no plan here: make one with skerry compare --plan (or run skerry compare)");
  }
  const std::string file = path.string();
  const nlohmann::json j = ReadJsonFile(path.string());
  if (Member<std::string>(j, "format", file, "") != "skerry-compare-plan/1") {
    throw InputError(file, 0, "format", "expected skerry-compare-plan/1");
  }
  ComparePlan plan;
  plan.seeds = Member<std::vector<std::int64_t>>(j, "seeds", file, "");
  std::map<std::string, int> dataset_index, config_index;
  const auto datasets = Member<std::vector<nlohmann::json>>(j, "datasets", file, "");
  for (size_t i = 0; i < datasets.size(); ++i) {
    const std::string at = "datasets[" + std::to_string(i) + "].";
    CompareDataset d;
    d.name = Member<std::string>(datasets[i], "name", file, at);
    d.source = PlanPath(datasets[i], "source", file, at);
    d.simulated = Member<bool>(datasets[i], "simulated", file, at);
    dataset_index[d.name] = static_cast<int>(i);
    plan.datasets.push_back(d);
  }
  const auto configs = Member<std::vector<nlohmann::json>>(j, "configs", file, "");
  for (size_t i = 0; i < configs.size(); ++i) {
    const std::string at = "configs[" + std::to_string(i) + "].";
    CompareConfig c;
    c.name = Member<std::string>(configs[i], "name", file, at);
    c.file = PlanPath(configs[i], "file", file, at);
    config_index[c.name] = static_cast<int>(i);
    plan.configs.push_back(c);
  }
  if (plan.configs.empty()) throw InputError(file, 0, "configs", "is empty");
  const auto jobs = Member<std::vector<nlohmann::json>>(j, "jobs", file, "");
  for (size_t i = 0; i < jobs.size(); ++i) {
    const std::string at = "jobs[" + std::to_string(i) + "].";
    CompareJob job;
    job.id = Member<int>(jobs[i], "id", file, at);
    if (job.id != static_cast<int>(i)) throw InputError(file, 0, at + "id", "out of order");
    const std::string dataset = Member<std::string>(jobs[i], "dataset", file, at);
    const std::string config = Member<std::string>(jobs[i], "config", file, at);
    if (!dataset_index.count(dataset)) {
      throw InputError(file, 0, at + "dataset", "'" + dataset + "' is not in datasets");
    }
    if (!config_index.count(config)) {
      throw InputError(file, 0, at + "config", "'" + config + "' is not in configs");
    }
    job.dataset = dataset_index[dataset];
    job.config = config_index[config];
    job.seed = Member<std::int64_t>(jobs[i], "seed", file, at);
    job.dataset_dir = PlanPath(jobs[i], "dataset_dir", file, at);
    job.run_dir = PlanPath(jobs[i], "run_dir", file, at);
    plan.jobs.push_back(job);
  }
  return plan;
}

void RunJob(const ComparePlan& plan, int job_id, const std::string& out_dir) {
  if (job_id < 0 || job_id >= static_cast<int>(plan.jobs.size())) {
    throw InputError((fs::path(out_dir) / "plan.json").string(), 0, "--job",
                     "no job " + std::to_string(job_id) + " (the plan has " +
                         std::to_string(plan.jobs.size()) + ")");
  }
  const CompareJob& job = plan.jobs[job_id];
  const CompareDataset& dataset = plan.datasets[job.dataset];
  const fs::path run_dir = Resolve(out_dir, job.run_dir);
  fs::create_directories(run_dir);
  fs::remove(run_dir / "result.json");
  nlohmann::json result = {{"job", job.id},
                           {"dataset", dataset.name},
                           {"config", plan.configs[job.config].name},
                           {"seed", job.seed}};
  const auto t0 = std::chrono::steady_clock::now();
  try {
    const fs::path dataset_dir = Resolve(out_dir, job.dataset_dir);
    if (dataset.simulated) EnsureSimulated(dataset, job.seed, out_dir, dataset_dir, job.id);
    const Dataset data = LoadDataset(dataset_dir.string());
    RequireImu(data, "compare");
    const EstimatorConfig config =
        LoadEstimatorConfig(Resolve(out_dir, plan.configs[job.config].file).string());
    // The dataset's cameras, LiDARs, water surface and pose fixes as `skerry run` takes them:
    // without them a skyline or harbour dataset would be compared on its IMU and GNSS alone.
    const WindowRun run = RunWindow(data, config, {}, nullptr, DatasetSensors(data, config));
    WriteUpdatesCsv((run_dir / "updates.csv").string(), run.stats);
    WriteBlocksCsv((run_dir / "blocks.csv").string(), run.sensors);
    WriteJson((run_dir / "summary.json").string(), WindowSummaryJson(data, config, run));
    if (run.records.empty()) {
      throw std::runtime_error("the estimator never initialised");
    }
    WriteEstimateFiles(run_dir.string(), run.records);
    result["ok"] = true;
    result["wall_s"] = run.wall_s;
  } catch (const std::exception& e) {
    result["ok"] = false;
    result["error"] = e.what();
  }
  result["job_wall_s"] =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  WriteTextFile(run_dir / "result.json", result.dump(2) + "\n");
}

void RunJobs(const ComparePlan& plan,
             const std::string& out_dir,
             int threads,
             const std::function<void(int, int)>& progress) {
  const std::vector<int> pending = PendingJobs(plan, out_dir);
  const int total = static_cast<int>(plan.jobs.size());
  const int count = static_cast<int>(pending.size());
  threads = std::max(1, std::min(threads, count));
  std::atomic<int> next{0};
  std::atomic<int> done{total - count};
  std::mutex mutex;
  std::exception_ptr error;
  auto worker = [&]() {
    for (int i = next++; i < count; i = next++) {
      try {
        RunJob(plan, pending[i], out_dir);
      } catch (...) {
        std::lock_guard<std::mutex> lock(mutex);
        if (!error) error = std::current_exception();
        next = count;  // stop handing out jobs: the folder is unusable (disk full, ...)
      }
      const int d = ++done;
      std::lock_guard<std::mutex> lock(mutex);
      if (progress) progress(d, total);
    }
  };
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t) pool.emplace_back(worker);
  for (std::thread& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

void WriteSchedulerFiles(const ComparePlan& plan,
                         const std::string& out_dir,
                         const std::string& skerry_binary) {
  const std::string dir = fs::absolute(out_dir).lexically_normal().string();
  auto quote = [](const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
  };
  std::ostringstream jobs;
  for (const CompareJob& job : plan.jobs) {
    jobs << quote(skerry_binary) << " compare --out " << quote(dir) << " --job " << job.id << "\n";
  }
  WriteTextFile(fs::path(out_dir) / "jobs.txt", jobs.str());

  const int n = static_cast<int>(plan.jobs.size());
  std::ostringstream parallel;
  parallel << "#!/usr/bin/env bash\n"
              "# Runs every job of this plan with GNU parallel, here or over SSH hosts, then\n"
              "# merges the results. Usage:\n"
              "#   bash run_parallel.sh                  # all local cores\n"
              "#   HOSTS=hosts.txt bash run_parallel.sh  # GNU parallel --sshloginfile\n"
              "# The compare folder and the skerry binary must be at the same paths on every\n"
              "# host (a shared file system). Each job writes only its own run folder.\n"
              "set -euo pipefail\n"
              "cd \"$(dirname \"${BASH_SOURCE[0]}\")\"\n"
              "args=(--will-cite --jobs \"${JOBS:-100%}\" --joblog parallel.log --halt never)\n"
              "if [[ -n \"${HOSTS:-}\" ]]; then args+=(--sshloginfile \"$HOSTS\"); fi\n"
              "parallel \"${args[@]}\" < jobs.txt || true\n"
           << quote(skerry_binary) << " compare --collect " << quote(dir) << "\n";
  WriteTextFile(fs::path(out_dir) / "run_parallel.sh", parallel.str());

  std::ostringstream slurm;
  slurm << "#!/usr/bin/env bash\n"
           "# A Slurm array job, one task per line of jobs.txt. Submit from any node that sees\n"
           "# this folder:\n"
           "#   sbatch slurm_array.sh\n"
           "# and once every task has finished:\n"
           "#   skerry compare --collect "
        << dir
        << "\n"
           "#SBATCH --job-name=skerry-compare\n"
           "#SBATCH --array=0-"
        << std::max(0, n - 1)
        << "\n"
           "#SBATCH --cpus-per-task=1\n"
           "#SBATCH --output="
        << dir
        << "/slurm-%A_%a.log\n"
           "set -euo pipefail\n"
           "line=$((SLURM_ARRAY_TASK_ID + 1))\n"
           "eval \"$(sed -n \"${line}p\" "
        << quote(dir + "/jobs.txt") << ")\"\n";
  WriteTextFile(fs::path(out_dir) / "slurm_array.sh", slurm.str());
}

CollectResult Collect(const std::string& out_dir) {
  const ComparePlan plan = ReadPlan(out_dir);
  CollectResult result;
  std::vector<RunFigures> runs(plan.jobs.size());
  for (size_t i = 0; i < plan.jobs.size(); ++i) {
    runs[i] = ReadRun(plan, plan.jobs[i], out_dir);
    if (!runs[i].has_result) ++result.missing;
    if (runs[i].has_result && !runs[i].ok) ++result.failed;
  }
  // A run that failed before writing its summary still counts the epochs it should have had: as
  // many as the other runs of the same data (same dataset and seed) expected.
  for (size_t i = 0; i < plan.jobs.size(); ++i) {
    if (runs[i].expected_epochs > 0) continue;
    for (size_t k = 0; k < plan.jobs.size(); ++k) {
      if (plan.jobs[k].dataset == plan.jobs[i].dataset && plan.jobs[k].seed == plan.jobs[i].seed) {
        runs[i].expected_epochs = std::max(runs[i].expected_epochs, runs[k].expected_epochs);
      }
    }
  }
  // Fidelity of every run against the reference configuration's run of the same data.
  std::map<std::pair<int, std::int64_t>, int> reference_job;
  for (const CompareJob& job : plan.jobs) {
    if (job.config == 0) reference_job[{job.dataset, job.seed}] = job.id;
  }
  for (const CompareJob& job : plan.jobs) {
    if (job.config == 0) continue;
    const auto it = reference_job.find({job.dataset, job.seed});
    if (it == reference_job.end()) continue;
    const RunFigures& ref = runs[it->second];
    RunFigures& run = runs[job.id];
    if (!ref.has_result || !run.has_result || (!ref.ok && !run.ok)) continue;
    run.fidelity = CompareRuns(ref.records, run.records, 1e-3);
    const fs::path csv = fs::path(out_dir) / FidelityCsvPath(plan, job);
    fs::create_directories(csv.parent_path());
    WriteFidelityCsv(csv.string(), *run.fidelity);
  }

  nlohmann::json table;
  table["format"] = "skerry-compare-table/1";
  table["reference_config"] = plan.configs.front().name;
  table["datasets"] = nlohmann::json::array();
  table["configs"] = nlohmann::json::array();
  table["seeds"] = plan.seeds;
  for (const CompareDataset& d : plan.datasets) table["datasets"].push_back(d.name);
  for (const CompareConfig& c : plan.configs) table["configs"].push_back(c.name);
  table["rows"] = nlohmann::json::array();
  std::vector<nlohmann::json> run_rows;
  for (int d = 0; d < static_cast<int>(plan.datasets.size()); ++d) {
    for (int c = 0; c < static_cast<int>(plan.configs.size()); ++c) {
      std::vector<const RunFigures*> group;
      nlohmann::json per_run = nlohmann::json::array();
      for (const CompareJob& job : plan.jobs) {
        if (job.dataset != d || job.config != c) continue;
        group.push_back(&runs[job.id]);
        nlohmann::json r = PerRunJson(job, runs[job.id], c == 0);
        per_run.push_back(r);
        r["dataset"] = plan.datasets[d].name;
        r["config"] = plan.configs[c].name;
        run_rows.push_back(r);
      }
      table["rows"].push_back(
          TableRow(plan.datasets[d].name, plan.configs[c].name, c == 0, group, per_run));
    }
  }
  table["missing_runs"] = result.missing;
  WriteTextFile(fs::path(out_dir) / "table.json", table.dump(2) + "\n");
  std::vector<nlohmann::json> rows(table["rows"].begin(), table["rows"].end());
  WriteCsv(fs::path(out_dir) / "table.csv", TableColumns(), rows);
  WriteCsv(fs::path(out_dir) / "runs.csv", RunColumns(), run_rows);
  result.table = table;
  return result;
}

std::string FormatTable(const nlohmann::json& table) {
  std::ostringstream out;
  auto num = [](const nlohmann::json& v, const char* fmt) {
    if (!v.is_number()) return std::string("-");
    char buf[32];
    std::snprintf(buf, sizeof(buf), fmt, v.get<double>());
    return std::string(buf);
  };
  char line[512];
  for (const auto& dataset : table["datasets"]) {
    out << "dataset " << dataset.get<std::string>()
        << " (reference: " << table["reference_config"].get<std::string>() << ")\n";
    std::snprintf(line, sizeof(line),
                  "  %-22s %5s %4s %8s %8s %8s %8s %15s %-14s %14s %6s %6s %22s\n", "config",
                  "runs", "fail", "hRMSE m", "hmax m", "hdg deg", "hdgmax", "ANEES (NEES in)", "",
                  "update ms", "iters", "valid", "AHED pos/hdg/vel/bias");
    out << line;
    for (const auto& row : table["rows"]) {
      if (row["dataset"] != dataset) continue;
      std::string anees = num(row["anees_position"], "%.2f");
      if (row["nees_inside_95"].is_number()) {
        anees += " (" + num(100.0 * row["nees_inside_95"].get<double>(), "%.0f") + "% in)";
      }
      const std::string update =
          num(row["update_ms"]["median"], "%.2f") + "/" + num(row["update_ms"]["p95"], "%.1f");
      std::string ahed = "(reference)";
      if (row["ahed"].is_object()) {
        ahed = num(row["ahed"]["position"], "%.3f") + "/" + num(row["ahed"]["heading"], "%.3f") +
               "/" + num(row["ahed"]["velocity"], "%.3f") + "/" +
               num(row["ahed"]["biases"], "%.3f");
      }
      std::snprintf(
          line, sizeof(line), "  %-22s %5d %4d %8s %8s %8s %8s %15s %-14s %14s %6s %6s %22s\n",
          row["config"].get<std::string>().c_str(), row["runs"].get<int>(),
          row["failed_runs"].get<int>(), num(row["horizontal_rmse_m"], "%.3f").c_str(),
          num(row["horizontal_max_m"], "%.2f").c_str(),
          num(row["heading_rmse_deg"], "%.3f").c_str(), num(row["heading_max_deg"], "%.2f").c_str(),
          anees.c_str(), row["consistency"].get<std::string>().c_str(), update.c_str(),
          num(row["iterations"]["mean"], "%.1f").c_str(), num(row["share_valid"], "%.3f").c_str(),
          ahed.c_str());
      out << line;
    }
  }
  return out.str();
}

}  // namespace skerry::cli
