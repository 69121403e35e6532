#include "twin_report.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "skerry/core/input_error.h"
#include "skerry/eval/run_fidelity.h"
#include "skerry/io/csv_reader.h"
#include "skerry/twin/twin_yaml.h"

namespace skerry::cli {

namespace fs = std::filesystem;

namespace {

/// A scalar as a JSON number when it is one (finite), a boolean when YAML 1.2's core schema says
/// so, else its text: twin.yaml writes numbers, true/false and names.
nlohmann::json ScalarToJson(const YAML::Node& n) {
  const std::string& s = n.Scalar();
  if (s == "true") return true;
  if (s == "false") return false;
  if (n.Tag() != "!" && !s.empty()) {  // "!": a quoted scalar, always a string
    try {
      size_t used = 0;
      const double v = std::stod(s, &used);
      if (used == s.size() && std::isfinite(v)) return v;
    } catch (const std::exception&) {
    }
  }
  return s;
}

nlohmann::json YamlToJson(const YAML::Node& n) {
  switch (n.Type()) {
    case YAML::NodeType::Map: {
      nlohmann::json j = nlohmann::json::object();
      for (const auto& kv : n) {
        if (!kv.first.IsScalar()) continue;  // twin.yaml has none; nothing to show
        j[kv.first.Scalar()] = YamlToJson(kv.second);
      }
      return j;
    }
    case YAML::NodeType::Sequence: {
      nlohmann::json j = nlohmann::json::array();
      for (const auto& e : n) j.push_back(YamlToJson(e));
      return j;
    }
    case YAML::NodeType::Scalar:
      return ScalarToJson(n);
    default:
      return nullptr;
  }
}

double Round(double v, double unit) { return std::round(v / unit) * unit; }

nlohmann::json OverTime(const std::string& path, int max_points, double t0_s) {
  std::vector<std::string> columns = {"t", "twins_valid"};
  std::vector<std::string> blocks;
  for (int b = 0; b < kNumFidelityBlocks; ++b) {
    blocks.push_back(FidelityBlockName(static_cast<FidelityBlock>(b)));
    columns.push_back("hed_" + blocks.back());
  }
  CsvReader reader(path, columns);
  std::vector<std::vector<double>> rows;
  while (reader.Next()) {
    std::vector<double> row = {NsToSeconds(reader.GetTimeNs(0)) - t0_s, reader.GetDouble(1)};
    for (size_t b = 0; b < blocks.size(); ++b) {
      const auto v = reader.GetOptionalDouble(static_cast<int>(b) + 2);
      row.push_back(v ? *v : std::nan(""));
    }
    rows.push_back(row);
  }
  nlohmann::json j = {{"t", nlohmann::json::array()}, {"twins_valid", nlohmann::json::array()}};
  for (const std::string& b : blocks) j[b] = nlohmann::json::array();
  const size_t n = rows.size();
  const size_t stride = std::max<size_t>(1, (n + max_points - 1) / std::max(1, max_points));
  for (size_t i = 0; i < n; i += stride) {
    j["t"].push_back(Round(rows[i][0], 1e-2));
    j["twins_valid"].push_back(rows[i][1]);
    for (size_t b = 0; b < blocks.size(); ++b) {
      const double v = rows[i][b + 2];
      j[blocks[b]].push_back(std::isfinite(v) ? nlohmann::json(Round(v, 1e-4)) : nlohmann::json());
    }
  }
  return j;
}

}  // namespace

bool IsTwinFolder(const std::string& dir) { return fs::exists(fs::path(dir) / "twin.yaml"); }

nlohmann::json TwinReportData(const std::string& dir, int max_points, double t0_s) {
  const std::string path = (fs::path(dir) / "twin.yaml").string();
  const YAML::Node root = LoadTwinYamlDocument(path);
  if (!root.IsMap()) throw InputError(path, 1, "(document)", "not a map (a twin.yaml?)");
  if (!root["twin"] || !root["twin"].IsMap()) {
    throw InputError(path, 0, "twin", "missing: not a twin.yaml written by skerry twin");
  }
  nlohmann::json j;
  j["folder"] = dir;
  j["yaml"] = YamlToJson(root);
  const fs::path over_time = fs::path(dir) / "fidelity" / "over_time.csv";
  j["over_time"] =
      fs::exists(over_time) ? OverTime(over_time.string(), max_points, t0_s) : nlohmann::json();
  return j;
}

int FirstTwinRunSeed(const std::string& dir) {
  const fs::path f = fs::path(dir) / "fidelity";
  if (!fs::is_directory(f)) return -1;
  int best = -1;
  for (const auto& e : fs::directory_iterator(f)) {
    const std::string name = e.path().filename().string();
    if (name.rfind("twin-", 0) != 0 || !fs::exists(e.path() / "states.csv")) continue;
    try {
      size_t used = 0;
      const int seed = std::stoi(name.substr(5), &used);
      if (used == name.size() - 5 && seed >= 0 && (best < 0 || seed < best)) best = seed;
    } catch (const std::exception&) {
    }
  }
  return best;
}

}  // namespace skerry::cli
