#include "report_page.h"

#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>

#include "comparison.h"
#include "run_outputs.h"
#include "skerry/core/input_error.h"
#include "skerry/eval/evaluation.h"
#include "skerry/eval/run_fidelity.h"
#include "skerry/io/csv_reader.h"
#include "skerry/io/dataset.h"
#include "skerry/io/estimate_io.h"
#include "skerry/io/trajectory.h"
#include "twin_report.h"

extern const char* const skerry_embedded_chartjs;
extern const char* const skerry_embedded_report_html;
extern const char* const skerry_embedded_report_css;
extern const char* const skerry_embedded_report_js;

namespace skerry::cli {

namespace fs = std::filesystem;

namespace {

/// Rounds for the page: millimetres / milliseconds are plenty, and short numbers keep it light.
double R(double v, double unit = 1e-3) { return std::round(v / unit) * unit; }

/// Indices of at most `max_points` evenly spread samples of `n` (always the last one).
std::vector<size_t> Thin(size_t n, int max_points) {
  std::vector<size_t> idx;
  if (n == 0) return idx;
  const size_t stride = std::max<size_t>(1, (n + max_points - 1) / max_points);
  for (size_t i = 0; i < n; i += stride) idx.push_back(i);
  if (idx.back() != n - 1) idx.push_back(n - 1);
  return idx;
}

nlohmann::json ReadJsonOrNull(const fs::path& path) {
  return fs::exists(path) ? ReadJsonFile(path.string()) : nlohmann::json();
}

/// Datasets are shared by every run of a comparison: load each once.
class DatasetCache {
 public:
  /// `dir` as any spelling of the folder (relative, absolute, with "..").
  const Dataset* Get(const std::string& dir_in) {
    if (dir_in.empty() || !fs::exists(fs::path(dir_in) / "dataset.yaml")) return nullptr;
    const std::string dir = fs::absolute(dir_in).lexically_normal().string();
    auto it = cache_.find(dir);
    if (it == cache_.end()) {
      it = cache_.emplace(dir, std::make_unique<Dataset>(LoadDataset(dir))).first;
    }
    return it->second.get();
  }

 private:
  std::map<std::string, std::unique_ptr<Dataset>> cache_;
};

/// One run folder as the page's series (times in s from the start of the data).
nlohmann::json RunSeriesOf(const fs::path& run_dir,
                           const std::string& label,
                           int max_points,
                           DatasetCache& datasets) {
  const std::vector<EstimateRecord> records = ReadRunEstimate(run_dir.string());
  // Not const: operator[] on a const json with a missing key is undefined behaviour (a
  // use-after-free under AddressSanitizer, found by fuzzing); on a mutable one it is null.
  nlohmann::json summary = ReadJsonOrNull(run_dir / "summary.json");
  std::string dataset_dir;
  if (summary.is_object() && summary.contains("dataset")) {
    dataset_dir = summary["dataset"].value("directory", std::string());
  }
  const Dataset* data = datasets.Get(dataset_dir);
  TimeNs t0 = records.empty() ? 0 : records.front().state.t_ns;
  if (data != nullptr && !data->imu_samples.empty()) t0 = data->imu_samples.front().t_ns;
  auto T = [t0](TimeNs t) { return R(NsToSeconds(t - t0), 1e-2); };

  nlohmann::json run;
  run["label"] = label;
  run["folder"] = run_dir.string();
  run["dataset"] = data ? data->name : std::string();
  run["config"] = summary.is_object() ? summary["configuration"].value("name", label) : label;
  run["summary"] = nullptr;
  if (summary.is_object()) {
    run["summary"] = {{"accuracy", summary.value("accuracy", nlohmann::json())},
                      {"timing", summary.value("timing", nlohmann::json())},
                      {"command", summary.value("command", std::string())}};
    // Sensors beyond IMU and GNSS: the window's decisions and the frontend's own figures.
    if (summary.contains("solver") && summary["solver"].is_object() &&
        summary["solver"].contains("sensors")) {
      run["summary"]["sensors"] = summary["solver"]["sensors"];
    }
  }
  // The estimate.
  nlohmann::json est = {{"t", nlohmann::json::array()},
                        {"e", nlohmann::json::array()},
                        {"n", nlohmann::json::array()}};
  for (size_t i : Thin(records.size(), max_points)) {
    const EstimateRecord& r = records[i];
    est["t"].push_back(T(r.state.t_ns));
    est["e"].push_back(R(r.state.p_w_b.x()));
    est["n"].push_back(R(r.state.p_w_b.y()));
  }
  run["estimate"] = est;
  // Ground truth, raw GNSS and events from the dataset.
  run["truth"] = nullptr;
  run["gnss"] = nullptr;
  run["events"] = nlohmann::json::array();
  if (data != nullptr) {
    if (!data->groundtruth.empty()) {
      nlohmann::json truth = {{"t", nlohmann::json::array()},
                              {"e", nlohmann::json::array()},
                              {"n", nlohmann::json::array()}};
      for (size_t i : Thin(data->groundtruth.size(), max_points)) {
        const StampedPose& p = data->groundtruth[i];
        truth["t"].push_back(T(p.t_ns));
        truth["e"].push_back(R(p.p_w_b.x()));
        truth["n"].push_back(R(p.p_w_b.y()));
      }
      run["truth"] = truth;
    }
    nlohmann::json gnss = {{"t", nlohmann::json::array()},
                           {"e", nlohmann::json::array()},
                           {"n", nlohmann::json::array()}};
    for (size_t i : Thin(data->gnss_fixes.size(), max_points)) {
      const GnssFix& f = data->gnss_fixes[i];
      gnss["t"].push_back(T(f.t_ns));
      gnss["e"].push_back(R(f.p_w.x()));
      gnss["n"].push_back(R(f.p_w.y()));
    }
    run["gnss"] = gnss;
    for (const GnssEvent& e : data->events) {
      run["events"].push_back({{"type", e.type},
                               {"t0", T(e.t_start_ns)},
                               {"t1", T(e.t_end_ns)},
                               {"offset_m", R(e.offset_enu_m.head<2>().norm(), 0.1)}});
    }
  }
  // Errors against ground truth, with the estimator's own 3-sigma.
  run["errors"] = nullptr;
  if (data != nullptr && !data->groundtruth.empty()) {
    const EvaluationResult ev = Evaluate(records, data->groundtruth);
    std::map<TimeNs, const EstimateRecord*> by_time;
    for (const EstimateRecord& r : records) by_time[r.state.t_ns] = &r;
    nlohmann::json err = {{"t", nlohmann::json::array()},   {"h", nlohmann::json::array()},
                          {"h3s", nlohmann::json::array()}, {"nees", nlohmann::json::array()},
                          {"hdg", nlohmann::json::array()}, {"hdg3s", nlohmann::json::array()}};
    for (size_t i : Thin(ev.epochs.size(), max_points)) {
      const EpochError& e = ev.epochs[i];
      const EstimateRecord* r = by_time.count(e.t_ns) ? by_time[e.t_ns] : nullptr;
      const bool cov_ok = r != nullptr && r->has_covariance;
      err["t"].push_back(T(e.t_ns));
      err["h"].push_back(R(e.p_err_w.head<2>().norm()));
      err["hdg"].push_back(R(e.heading_err_deg));
      if (cov_ok) {
        err["h3s"].push_back(R(3.0 * HorizontalSigmaM(r->covariance)));
        err["hdg3s"].push_back(R(3.0 * HeadingSigmaDeg(r->covariance)));
      } else {
        err["h3s"].push_back(nullptr);
        err["hdg3s"].push_back(nullptr);
      }
      err["nees"].push_back(e.has_nees ? nlohmann::json(R(e.nees_pos)) : nlohmann::json());
    }
    run["errors"] = err;
  }
  // Solver time per update: the maximum of each bucket, so spikes stay visible.
  run["updates"] = nullptr;
  const fs::path updates = run_dir / "updates.csv";
  if (fs::exists(updates)) {
    std::vector<std::pair<double, double>> rows;
    CsvReader csv(updates.string(),
                  {"t", "update_ms", "solved", "solve_ms", "iterations", "usable"});
    while (csv.Next()) {
      rows.emplace_back(NsToSeconds(csv.GetTimeNs(0) - t0), csv.GetDouble(1));
    }
    nlohmann::json u = {{"t", nlohmann::json::array()}, {"ms", nlohmann::json::array()}};
    const size_t bucket =
        std::max<size_t>(1, (rows.size() + max_points - 1) / static_cast<size_t>(max_points));
    for (size_t i = 0; i < rows.size(); i += bucket) {
      double t = rows[i].first, ms = rows[i].second;
      for (size_t k = i; k < std::min(rows.size(), i + bucket); ++k) {
        if (rows[k].second > ms) {
          ms = rows[k].second;
          t = rows[k].first;
        }
      }
      u["t"].push_back(R(t, 1e-2));
      u["ms"].push_back(std::max(1e-3, R(ms)));
    }
    run["updates"] = u;
  }
  return run;
}

nlohmann::json RunSeries(const fs::path& run_dir,
                         const std::string& label,
                         int max_points,
                         DatasetCache& datasets) {
  return WithJsonErrorsIn((run_dir / "summary.json").string(),
                          [&] { return RunSeriesOf(run_dir, label, max_points, datasets); });
}

/// A compare folder: its table, the first seed's run of every configuration on the first
/// dataset, and the per-epoch Hellinger distances of that seed.
void AddComparisonOf(const fs::path& dir,
                     int max_points,
                     DatasetCache& datasets,
                     nlohmann::json& page) {
  const nlohmann::json table = ReadJsonOrNull(dir / "table.json");
  const ComparePlan plan = ReadPlan(dir.string());
  nlohmann::json cmp;
  cmp["folder"] = dir.string();
  cmp["table"] = table;
  if (plan.jobs.empty()) {
    page["comparisons"].push_back(cmp);
    return;
  }
  const CompareJob& first = plan.jobs.front();
  const std::string dataset = plan.datasets[first.dataset].name;
  cmp["dataset"] = dataset;
  cmp["seed"] = first.seed;
  cmp["hed"] = nlohmann::json::array();
  // Times from the start of the data, as in RunSeries, so the spans and runs line up.
  // Without the dataset: from the first fidelity epoch.
  const Dataset* data = datasets.Get((dir / first.dataset_dir).string());
  std::optional<TimeNs> t0_ns;
  if (data != nullptr && !data->imu_samples.empty()) t0_ns = data->imu_samples.front().t_ns;
  const std::vector<std::string> blocks = {"position", "heading", "velocity", "biases"};
  const std::vector<std::string> columns = FidelityCsvColumns();
  std::vector<int> cols;  // of the plotted blocks' HED
  for (const std::string& b : blocks) {
    cols.push_back(
        static_cast<int>(std::find(columns.begin(), columns.end(), "hed_" + b) - columns.begin()));
  }
  for (const CompareJob& job : plan.jobs) {
    if (job.dataset != first.dataset || job.seed != first.seed) continue;
    const std::string config = plan.configs[job.config].name;
    const fs::path run_dir = dir / job.run_dir;
    if (fs::exists(run_dir / "states.csv")) {
      page["runs"].push_back(RunSeries(run_dir, config, max_points, datasets));
    }
    if (job.config == 0) continue;
    const fs::path csv = dir / FidelityCsvPath(plan, job);
    if (!fs::exists(csv)) continue;
    CsvReader reader(csv.string(), columns);
    std::vector<std::vector<double>> rows;
    while (reader.Next()) {
      const TimeNs t = reader.GetTimeNs(0);
      if (!t0_ns) t0_ns = t;
      std::vector<double> row = {NsToSeconds(t - *t0_ns)};
      for (int col : cols) {
        const auto v = reader.GetOptionalDouble(col);
        row.push_back(v ? *v : std::nan(""));
      }
      rows.push_back(row);
    }
    nlohmann::json h = {{"config", config}, {"t", nlohmann::json::array()}};
    for (const std::string& b : blocks) h[b] = nlohmann::json::array();
    for (size_t i : Thin(rows.size(), max_points)) {
      h["t"].push_back(R(rows[i][0], 1e-2));
      for (size_t b = 0; b < blocks.size(); ++b) {
        const double v = rows[i][b + 1];
        h[blocks[b]].push_back(std::isfinite(v) ? nlohmann::json(R(v, 1e-4)) : nlohmann::json());
      }
    }
    cmp["hed"].push_back(h);
  }
  page["comparisons"].push_back(cmp);
}

void AddComparison(const fs::path& dir,
                   int max_points,
                   DatasetCache& datasets,
                   nlohmann::json& page) {
  WithJsonErrorsIn((dir / "table.json").string(),
                   [&] { AddComparisonOf(dir, max_points, datasets, page); });
}

/// A twin folder: its test and models (twin.yaml), the distance over time, and the recording's
/// run beside its first twin's.
void AddTwin(const fs::path& dir, int max_points, DatasetCache& datasets, nlohmann::json& page) {
  // The twin is a dataset itself, and its runs' summary.json name it: times from its start.
  const Dataset* data = datasets.Get(dir.string());
  double t0_s = 0.0;
  if (data != nullptr && !data->imu_samples.empty()) {
    t0_s = NsToSeconds(data->imu_samples.front().t_ns);
  }
  nlohmann::json twin = TwinReportData(dir.string(), max_points, t0_s);
  twin["runs"] = nlohmann::json::array();
  if (fs::exists(dir / "fidelity" / "real" / "states.csv")) {
    page["runs"].push_back(RunSeries(dir / "fidelity" / "real", "recording", max_points, datasets));
    twin["runs"].push_back("recording");
  }
  const int seed = FirstTwinRunSeed(dir.string());
  if (seed >= 0) {
    const std::string label = "twin of seed " + std::to_string(seed);
    page["runs"].push_back(RunSeries(dir / "fidelity" / ("twin-" + std::to_string(seed)), label,
                                     max_points, datasets));
    twin["runs"].push_back(label);
  }
  page["twins"].push_back(twin);
}

void ReplaceOnce(std::string& text, const std::string& key, const std::string& value) {
  const size_t at = text.find(key);
  if (at == std::string::npos) {
    throw std::logic_error("report template has no " + key);
  }
  text.replace(at, key.size(), value);
}

}  // namespace

nlohmann::json ReportData(const std::vector<std::string>& dirs, int max_points) {
  nlohmann::json page;
  page["runs"] = nlohmann::json::array();
  page["comparisons"] = nlohmann::json::array();
  page["twins"] = nlohmann::json::array();
  const auto b = AneesBounds(3, 1);
  page["nees_bounds_95"] = {b.first, b.second};
  const std::time_t now = std::time(nullptr);
  char stamp[32];
  std::strftime(stamp, sizeof(stamp), "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
  page["generated"] = stamp;
  DatasetCache datasets;
  for (const std::string& d : dirs) {
    const fs::path dir(d);
    if (IsTwinFolder(d)) {
      AddTwin(dir, max_points, datasets, page);
    } else if (fs::exists(dir / "table.json") && fs::exists(dir / "plan.json")) {
      AddComparison(dir, max_points, datasets, page);
    } else if (fs::exists(dir / "states.csv")) {
      std::string label = fs::path(dir).lexically_normal().filename().string();
      if (label.empty()) label = fs::path(dir).lexically_normal().parent_path().filename().string();
      page["runs"].push_back(RunSeries(dir, label, max_points, datasets));
    } else {
      throw InputError(d, 0, "--run",
                       "neither a run folder (states.csv, from skerry run), a compare folder "
                       "(table.json, from skerry compare) nor a twin folder (twin.yaml, from "
                       "skerry twin)");
    }
  }
  return page;
}

std::string RenderReportHtml(const nlohmann::json& data) {
  // The data sit in a <script type="application/json"> element. Not only "</script>" ends one
  // early: "<!--" followed by "<script" puts the HTML tokenizer in its "double escaped" state, in
  // which the element's own end tag no longer ends it and the page is swallowed (the HTML
  // standard's tokenizer, "script data double escaped state"). In JSON, '<', '>' and '&' can only
  // occur inside strings, where the escapes \u003c, \u003e and \u0026 mean the same characters:
  // with none of them left, no string from a dataset, configuration or path can form markup here.
  std::string json;
  for (const char c : data.dump()) {
    switch (c) {
      case '<':
        json += "\\u003c";
        break;
      case '>':
        json += "\\u003e";
        break;
      case '&':
        json += "\\u0026";
        break;
      default:
        json += c;
    }
  }
  std::string html = skerry_embedded_report_html;
  ReplaceOnce(html, "/*SKERRY_CSS*/", skerry_embedded_report_css);
  ReplaceOnce(html, "/*SKERRY_CHARTJS*/", skerry_embedded_chartjs);
  ReplaceOnce(html, "/*SKERRY_REPORT_JS*/", skerry_embedded_report_js);
  ReplaceOnce(html, "/*SKERRY_DATA*/", json);
  return html;
}

}  // namespace skerry::cli
