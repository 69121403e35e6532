#include "run_outputs.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "skerry/core/input_error.h"
#include "skerry/core/so3.h"
#include "skerry/eval/evaluation.h"
#include "skerry/eval/event_metrics.h"
#include "skerry/io/atomic_file.h"
#include "skerry/io/trajectory.h"

namespace skerry::cli {

UpdatesCsvWriter::UpdatesCsvWriter(const std::string& path) : file_(path) {
  file_.stream() << "t,update_ms,solved,solve_ms,iterations,usable\n";
}

void UpdatesCsvWriter::Append(const std::vector<UpdateStats>& stats) {
  char line[160];
  for (const UpdateStats& s : stats) {
    std::snprintf(line, sizeof(line), "%.9f,%.4f,%d,%.4f,%d,%d\n", NsToSeconds(s.t_ns), s.update_ms,
                  s.solved ? 1 : 0, s.solve_ms, s.iterations, s.solve_usable ? 1 : 0);
    file_.stream() << line;
  }
}

void WriteUpdatesCsv(const std::string& path, const std::vector<UpdateStats>& stats) {
  UpdatesCsvWriter writer(path);
  writer.Append(stats);
  writer.Commit();
}

namespace {

// A text cell as RFC 4180 writes it: quoted, quotes doubled, when it holds a comma, a quote or a
// line break (a sensor's name is the user's).
std::string CsvText(const std::string& s) {
  if (s.find_first_of(",\"\r\n") == std::string::npos) return s;
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + '"';
}

}  // namespace

bool WriteBlocksCsv(const std::string& path, const SensorLog& log) {
  return WriteBlocksCsv(path, log, log.decisions);
}

bool WriteBlocksCsv(const std::string& path,
                    const SensorLog& log,
                    const std::vector<SensorRecord>& decisions) {
  if (decisions.empty()) return false;
  // The frontends' tables, and the union of their columns in the sensors' order.
  std::vector<FrontendBlockTable> tables(log.sensors.size());
  std::vector<std::string> columns;
  std::vector<std::vector<size_t>> at(log.sensors.size());  // a table's column -> its place
  for (size_t k = 0; k < log.sensors.size(); ++k) {
    const auto live = log.live_frontend_blocks.find(log.sensors[k].name);
    if (live == log.live_frontend_blocks.end()) continue;
    tables[k] = live->second();
    for (const std::string& c : tables[k].columns) {
      const auto it = std::find(columns.begin(), columns.end(), c);
      at[k].push_back(static_cast<size_t>(it - columns.begin()));
      if (it == columns.end()) columns.push_back(c);
    }
  }
  AtomicFile file(path);
  std::ostream& out = file.stream();
  out << "t,sensor,decision,reacquired,dim,d2";
  for (const std::string& c : columns) out << ',' << c;
  out << '\n';
  char number[64];
  std::vector<double> cells(columns.size());
  for (const SensorRecord& d : decisions) {
    const auto k = static_cast<size_t>(d.sensor);
    const char* decision = d.decision == SensorDecision::kAccepted         ? "accepted"
                           : d.decision == SensorDecision::kRejectedByGate ? "rejected"
                                                                           : "dropped";
    std::snprintf(number, sizeof(number), "%.9f", NsToSeconds(d.t_ns));
    out << number << ',' << CsvText(k < log.sensors.size() ? log.sensors[k].name : "?") << ','
        << decision << ',' << (d.reacquired ? 1 : 0) << ',' << d.dim << ',';
    std::snprintf(number, sizeof(number), "%.6g", d.d2);
    out << number;
    std::fill(cells.begin(), cells.end(), std::numeric_limits<double>::quiet_NaN());
    if (k < tables.size()) {
      const auto row = tables[k].rows.find(d.t_ns);
      if (row != tables[k].rows.end()) {
        for (size_t c = 0; c < row->second.size() && c < at[k].size(); ++c) {
          cells[at[k][c]] = row->second[c];
        }
      }
    }
    for (const double v : cells) {
      out << ',';
      if (std::isfinite(v)) {
        std::snprintf(number, sizeof(number), "%.6g", v);
        out << number;
      }
    }
    out << '\n';
  }
  file.Commit();
  return true;
}

void UpdateFigures::Add(size_t records, const std::vector<UpdateStats>& stats) {
  keyframes += records;
  for (const UpdateStats& s : stats) {
    update_ms.push_back(static_cast<float>(s.update_ms));
    if (!s.solved) continue;
    solve_ms.push_back(static_cast<float>(s.solve_ms));
    iterations.push_back(static_cast<uint16_t>(std::clamp(s.iterations, 0, 65535)));
    if (!s.solve_usable) ++solve_failures;
  }
}

std::vector<EstimateRecord> ReadRunEstimate(const std::string& run_dir) {
  const std::filesystem::path dir(run_dir);
  const std::filesystem::path states = dir / "states.csv";
  if (!std::filesystem::exists(states)) {
    throw InputError(states.string(), 0, "file", "not found: give a run folder of skerry run");
  }
  return ReadEstimate(states.string(), (dir / "covariances.csv").string());
}

nlohmann::json DatasetJson(const Dataset& data) {
  nlohmann::json j;
  j["name"] = data.name;
  j["directory"] = data.directory.empty()
                       ? ""
                       : std::filesystem::absolute(data.directory).lexically_normal().string();
  j["origin"] = {{"lat_deg", data.origin.lat_deg},
                 {"lon_deg", data.origin.lon_deg},
                 {"height_m", data.origin.height_m}};
  j["imu_samples"] = data.imu_samples.size();
  j["gnss_fixes"] = data.gnss_fixes.size();
  j["has_groundtruth"] = !data.groundtruth.empty();
  if (data.imu_samples.size() > 1) {
    j["duration_s"] = NsToSeconds(data.imu_samples.back().t_ns - data.imu_samples.front().t_ns);
  }
  return j;
}

namespace {
nlohmann::json StatsJson(const Stats& s) {
  return {
      {"count", s.count}, {"rmse", s.rmse}, {"mean", s.mean}, {"median", s.median}, {"max", s.max}};
}
}  // namespace

nlohmann::json AccuracyJson(const Dataset& data, const std::vector<EstimateRecord>& records) {
  // No estimate (a run stopped before its first keyframe): no figures, rather than zeros.
  if (data.groundtruth.empty() || records.empty()) return nullptr;
  return AccuracyJson(Evaluate(records, data.groundtruth), data.events);
}

nlohmann::json AccuracyJson(const EvaluationResult& ev, const std::vector<GnssEvent>& events) {
  nlohmann::json j;
  j["epochs"] = ev.epochs.size();
  j["horizontal_m"] = StatsJson(ev.horizontal);
  j["vertical_m"] = StatsJson(ev.vertical);
  j["position_3d_m"] = StatsJson(ev.position3d);
  j["heading_deg"] = StatsJson(ev.heading_deg);
  j["roll_pitch_deg"] = StatsJson(ev.roll_pitch_deg);
  j["rpe"] = {{"delta_s", ev.rpe_delta_s},
              {"translation_m", StatsJson(ev.rpe_trans_m)},
              {"rotation_deg", StatsJson(ev.rpe_rot_deg)}};
  if (ev.nees_count > 0) {
    // Consecutive keyframes' errors are correlated: the bounds are those of the number of
    // independent epochs the NEES series is worth, not of every epoch (EffectiveSampleSize).
    const auto bounds3 = AneesBounds(3, ev.nees_effective_count);
    const auto bounds6 = AneesBounds(6, ev.nees_effective_count);
    j["nees"] = {{"count", ev.nees_count},
                 {"effective_count", ev.nees_effective_count},
                 {"anees_position", ev.anees_pos},
                 {"anees_position_bounds_95", {bounds3.first, bounds3.second}},
                 {"anees_pose", ev.anees_pose},
                 {"anees_pose_bounds_95", {bounds6.first, bounds6.second}}};
  }
  if (!events.empty()) {
    const EventMetrics m = ComputeEventMetrics(ev, events, 30.0, 10.0);
    nlohmann::json e;
    e["settle_s"] = 30.0;
    e["settle_after_outage_s"] = 10.0;
    e["horizontal_outside_outages_m"] = StatsJson(m.horizontal_outside_outages);
    e["heading_outside_outages_deg"] = StatsJson(m.heading_outside_outages_deg);
    e["outages"] = nlohmann::json::array();
    for (const OutageMetric& o : m.outages) {
      e["outages"].push_back({{"t_start_s", o.t_start_s},
                              {"duration_s", o.duration_s},
                              {"horizontal_error_at_end_m", o.horizontal_error_at_end_m},
                              {"max_horizontal_error_m", o.max_horizontal_error_m}});
    }
    e["jumps"] = nlohmann::json::array();
    for (const JumpMetric& jm : m.jumps) {
      e["jumps"].push_back({{"t_start_s", jm.t_start_s},
                            {"duration_s", jm.duration_s},
                            {"offset_m", jm.offset_m},
                            {"max_horizontal_error_m", jm.max_horizontal_error_m}});
    }
    j["events"] = e;
  }
  return j;
}

nlohmann::json DistributionJson(std::vector<double> v) {
  if (v.empty()) return {{"count", 0}};
  return {{"count", v.size()},
          {"median", Percentile(v, 50.0)},
          {"p95", Percentile(v, 95.0)},
          {"max", *std::max_element(v.begin(), v.end())}};
}

nlohmann::json WindowStatsJson(const WindowRun& run, const UpdateFigures* updates) {
  UpdateFigures own;
  if (updates == nullptr) {
    own.Add(run.records.size(), run.stats);
    updates = &own;
  }
  const auto list = [](const auto& v) { return std::vector<double>(v.begin(), v.end()); };
  nlohmann::json j;
  j["keyframes"] = updates->keyframes;
  j["solves"] = updates->solve_ms.size();
  j["solve_failures"] = updates->solve_failures;
  j["update_ms"] = DistributionJson(list(updates->update_ms));
  j["solve_ms"] = DistributionJson(list(updates->solve_ms));
  j["iterations"] = DistributionJson(list(updates->iterations));
  j["gnss"] = {
      {"accepted", run.gnss.accepted},
      {"rejected_by_gate", run.gnss.rejected},
      {"rejected_as_jump", run.gnss.rejected_as_jump},
      {"drift_steps", run.gnss.drift_steps},
      {"accepted_on_reacquisition", run.gnss.reacquired},
      {"reacquired_back_from_jump", run.gnss.reacquired_back_from_jump},
      {"dropped", run.gnss.dropped},
      {"heading_accepted", run.gnss.heading_accepted},
      {"heading_rejected", run.gnss.heading_rejected},
      // Mean normalised innovation squared of the accepted position fixes: 3 when the
      // estimator's covariance matches its errors (needs no ground truth).
      {"nis_mean_accepted", run.gnss.accepted > 0
                                ? nlohmann::json(run.gnss.nis_sum_accepted / run.gnss.accepted)
                                : nlohmann::json(nullptr)}};
  // Per sensor beyond IMU and GNSS: its blocks' decisions, and the mean NIS per degree of
  // freedom of the accepted ones (1 when the covariance and the sensor's noise match the errors).
  nlohmann::json& sensors = j["sensors"] = nlohmann::json::object();
  for (size_t k = 0; k < run.sensors.sensors.size() && k < run.sensor_stats.size(); ++k) {
    const SensorStats& st = run.sensor_stats[k];
    sensors[run.sensors.sensors[k].name] = {
        {"blocks", std::count_if(run.sensors.decisions.begin(), run.sensors.decisions.end(),
                                 [k](const SensorRecord& r) {
                                   return r.sensor == static_cast<SensorId>(k);
                                 })},
        {"accepted", st.accepted},
        {"rejected_by_gate", st.rejected},
        {"dropped", st.dropped},
        {"reacquired", st.reacquired},
        {"nis_per_dof_mean_accepted",
         st.accepted > 0 ? nlohmann::json(st.nis_per_dof_sum_accepted / st.accepted)
                         : nlohmann::json(nullptr)}};
    const auto f = run.sensors.frontend_stats.find(run.sensors.sensors[k].name);
    if (f != run.sensors.frontend_stats.end()) {
      sensors[run.sensors.sensors[k].name]["frontend"] = f->second;
    }
  }
  return j;
}

nlohmann::json BatchSensorsJson(const std::vector<SensorSpec>& sensors, const BatchResult& batch) {
  nlohmann::json j = nlohmann::json::object();
  for (size_t k = 0; k < sensors.size() && k < batch.sensor_used.size(); ++k) {
    j[sensors[k].name] = {
        {"used", batch.sensor_used[k]},
        {"rejected_after_solve", batch.sensor_rejected_after_solve[k]},
        {"unplaced", k < batch.sensor_unplaced.size() ? batch.sensor_unplaced[k] : 0}};
  }
  return j;
}

nlohmann::json GyroCalibrationJson(const GyroCalibrationEstimate& x, const ImuConfig& imu) {
  nlohmann::json scale = nlohmann::json::array(), scale_sigma = nlohmann::json::array();
  nlohmann::json mis = nlohmann::json::array(), mis_sigma = nlohmann::json::array();
  for (int r = 0; r < 3; ++r) {
    nlohmann::json row = nlohmann::json::array(), row_sigma = nlohmann::json::array();
    for (int c = 0; c < 3; ++c) {
      const int k = 3 * c + r;  // vec(E), column-major
      const nlohmann::json sigma =
          x.has_covariance ? nlohmann::json(std::sqrt(std::max(0.0, x.covariance(k, k)))) : nullptr;
      if (r == c) {
        scale.push_back(x.E(r, c) * 1e6);
        scale_sigma.push_back(x.has_covariance ? nlohmann::json(sigma.get<double>() * 1e6)
                                               : nullptr);
        row.push_back(0.0);
        row_sigma.push_back(0.0);
      } else {
        row.push_back(x.E(r, c) * 1e3);
        row_sigma.push_back(x.has_covariance ? nlohmann::json(sigma.get<double>() * 1e3) : nullptr);
      }
    }
    mis.push_back(row);
    mis_sigma.push_back(row_sigma);
  }
  return {{"scale_factor_ppm", scale},
          {"scale_factor_sigma_ppm", scale_sigma},
          {"misalignment_mrad", mis},
          {"misalignment_sigma_mrad", mis_sigma},
          {"prior_scale_factor_sigma_ppm", imu.gyro_scale_factor_sigma_ppm},
          {"prior_misalignment_sigma_mrad", imu.gyro_misalignment_sigma_mrad}};
}

nlohmann::json SensorParametersJson(const std::vector<SensorSpec>& sensors,
                                    const std::vector<SensorParameterEstimate>& parameters) {
  nlohmann::json j = nlohmann::json::object();
  for (const SensorParameterEstimate& x : parameters) {
    const SensorSpec& spec = sensors.at(x.sensor);
    j[spec.name] = {{"name", spec.parameter_name},
                    {"value", x.value},
                    {"sigma", x.has_variance ? nlohmann::json(std::sqrt(x.variance)) : nullptr},
                    {"prior", spec.parameter},
                    {"prior_sigma", spec.parameter_prior_sigma}};
  }
  return j;
}

nlohmann::json ExtrinsicsJson(const std::vector<SensorSpec>& sensors,
                              const std::vector<ExtrinsicEstimate>& extrinsics) {
  nlohmann::json j = nlohmann::json::object();
  for (const ExtrinsicEstimate& x : extrinsics) {
    const SensorSpec& spec = sensors.at(x.sensor);
    const Eigen::Vector3d drot = LogQ<double>(x.q_b_s * spec.q_b_s.conjugate());
    nlohmann::json e = {{"q_xyzw", {x.q_b_s.x(), x.q_b_s.y(), x.q_b_s.z(), x.q_b_s.w()}},
                        {"p_m", {x.p_b_s.x(), x.p_b_s.y(), x.p_b_s.z()}},
                        {"rotation_from_prior_deg", drot.norm() * 180.0 / M_PI},
                        {"translation_from_prior_m", (x.p_b_s - spec.p_b_s).norm()}};
    if (x.has_covariance) {
      const Eigen::Matrix<double, 6, 1> sd = x.covariance.diagonal().cwiseSqrt();
      e["sigma_rotation_deg"] = {sd[0] * 180.0 / M_PI, sd[1] * 180.0 / M_PI, sd[2] * 180.0 / M_PI};
      e["sigma_p_m"] = {sd[3], sd[4], sd[5]};
    } else {
      e["sigma_rotation_deg"] = nullptr;
      e["sigma_p_m"] = nullptr;
    }
    j[spec.name] = e;
  }
  return j;
}

void AddStatusJson(const WindowRun& run, nlohmann::json* summary) {
  (*summary)["status"] = run.diverged ? "diverged" : "ok";
  if (run.diverged) (*summary)["failure"] = run.failure;
  nlohmann::json& events = (*summary)["events"] = nlohmann::json::array();
  for (const EstimatorEvent& e : run.events) {
    const char* kind = e.kind == EstimatorEvent::Kind::kFellBackToAlign ? "fell_back_to_align"
                       : e.kind == EstimatorEvent::Kind::kRestarted     ? "restarted"
                                                                        : "gave_up";
    events.push_back({{"t", NsToSeconds(e.t_ns)}, {"kind", kind}, {"reason", e.reason}});
  }
}

void MarkInterrupted(const std::string& signal, TimeNs fed_until_ns, nlohmann::json* summary) {
  (*summary)["status"] = "interrupted";
  (*summary)["interrupted"] = {{"signal", signal}, {"data_until_s", NsToSeconds(fed_until_ns)}};
}

nlohmann::json WindowSummaryJson(const Dataset& data,
                                 const EstimatorConfig& config,
                                 const WindowRun& run,
                                 const UpdateFigures* updates,
                                 const std::vector<EstimateRecord>* records) {
  nlohmann::json summary;
  summary["command"] = "run";
  summary["dataset"] = DatasetJson(data);
  if (updates != nullptr) {
    // Streamed: the dataset's files were read as the run went.
    summary["dataset"]["imu_samples"] = run.imu_samples;
    summary["dataset"]["gnss_fixes"] = run.gnss_fixes;
    summary["dataset"]["duration_s"] = run.data_s;
  }
  summary["configuration"] = {{"name", config.name}, {"yaml", ToYaml(config)}};
  summary["solver"] = WindowStatsJson(run, updates);
  if (run.align_decision_t_ns >= 0) {
    summary["align"] = {
        {"decided_after_s", NsToSeconds(run.align_decision_t_ns - run.align_start_t_ns)},
        {"kept_start_yaw_deg", run.align_yaw0_deg},
        {"kept_weight", run.align_weight},
        {"clear_winner", !run.align_undecided},
        {"hypotheses", config.init.align_hypotheses}};
  }
  AddStatusJson(run, &summary);
  summary["timing"] = {{"wall_s", run.wall_s},
                       {"data_s", run.data_s},
                       {"realtime_factor", run.wall_s > 0 ? run.data_s / run.wall_s : 0.0}};
  summary["accuracy"] = AccuracyJson(data, records != nullptr ? *records : run.records);
  if (!run.extrinsics.empty()) {
    summary["extrinsics"] = ExtrinsicsJson(run.sensors.sensors, run.extrinsics);
  }
  if (!run.parameters.empty()) {
    summary["sensor_parameters"] = SensorParametersJson(run.sensors.sensors, run.parameters);
  }
  if (run.gyro_calibration.estimated) {
    summary["gyro_calibration"] = GyroCalibrationJson(run.gyro_calibration, data.imu);
  }
  return summary;
}

void WriteJson(const std::string& path, const nlohmann::json& json) {
  WriteFileAtomically(path, json.dump(2) + "\n");
}

std::string ReadTextFile(const std::string& path) {
  std::ifstream f(path);
  if (!f) throw InputError(path, 0, "file", "cannot be opened");
  std::ostringstream s;
  s << f.rdbuf();
  return s.str();
}

nlohmann::json ReadJsonFile(const std::string& path) {
  const std::string text = ReadTextFile(path);
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    // parse_error, and out_of_range for a number beyond a double (1e999): both bad input.
    throw InputError(path, 0, "json", e.what());
  }
}

}  // namespace skerry::cli
