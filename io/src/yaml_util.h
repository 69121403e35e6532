#pragma once
// Private helpers for reading YAML configuration with errors that name the file, the key path
// (e.g. `sensors.imu.rate_hz`) and the line (yaml-cpp marks are 0-based; we report 1-based).

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "skerry/core/input_error.h"
#include "skerry/io/csv_reader.h"

namespace skerry {
namespace yaml_util {

inline int Line(const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  return mark.is_null() ? 0 : mark.line + 1;
}

inline std::string Join(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

/// Parses YAML text; syntax errors become InputError with yaml-cpp's line.
inline YAML::Node Parse(const std::string& text, const std::string& file) {
  try {
    return YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    throw InputError(file, e.mark.is_null() ? 0 : e.mark.line + 1, "", "YAML syntax: " + e.msg);
  }
}

/// Reads a file whole; InputError if it cannot be opened.
inline std::string ReadFileText(const std::string& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file, 0, "", "cannot open file");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}
  const std::string& file() const { return file_; }

  [[noreturn]] void Fail(const YAML::Node& node,
                         const std::string& path,
                         const std::string& message) const {
    throw InputError(file_, Line(node), path, message);
  }

  /// `map` (at `path`) must be a mapping.
  void RequireMap(const YAML::Node& map, const std::string& path) const {
    if (!map.IsMap()) Fail(map, path.empty() ? "(document)" : path, "expected a mapping");
  }

  /// Child `key` of mapping `map` at `path`; error (on the mapping's line) if absent.
  YAML::Node Require(const YAML::Node& map, const std::string& path, const std::string& key) const {
    RequireMap(map, path);
    const YAML::Node child = map[key];
    if (!child.IsDefined() || child.IsNull()) Fail(map, Join(path, key), "missing required key");
    return child;
  }

  /// A mapping's key as a name; a key that is itself a list or mapping (YAML's "? " complex
  /// key) is an error at `path`.
  std::string Key(const YAML::Node& key, const std::string& path) const {
    if (!key.IsScalar())
      Fail(key, path.empty() ? "(document)" : path, "a key must be a plain name");
    return key.Scalar();
  }

  /// Every key of `map` must be in `allowed`.
  void RejectUnknownKeys(const YAML::Node& map,
                         const std::string& path,
                         const std::set<std::string>& allowed) const {
    for (const auto& kv : map) {
      const std::string key = Key(kv.first, path);
      if (allowed.count(key) == 0) Fail(kv.first, Join(path, key), "unknown key");
    }
  }

  std::string String(const YAML::Node& node, const std::string& path) const {
    if (!node.IsScalar()) Fail(node, path, "expected a string");
    return node.Scalar();
  }

  double Double(const YAML::Node& node, const std::string& path) const {
    if (!node.IsScalar()) Fail(node, path, "expected a number");
    double v = 0.0;
    if (!ParseDouble(node.Scalar(), &v)) {
      Fail(node, path, "expected a finite number, got \"" + node.Scalar() + "\"");
    }
    return v;
  }

  double PositiveDouble(const YAML::Node& node, const std::string& path) const {
    const double v = Double(node, path);
    if (!(v > 0.0)) Fail(node, path, "must be positive");
    return v;
  }

  double NonNegativeDouble(const YAML::Node& node, const std::string& path) const {
    const double v = Double(node, path);
    if (!(v >= 0.0)) Fail(node, path, "must be >= 0");
    return v;
  }

  std::vector<double> Doubles(const YAML::Node& node, const std::string& path, int size) const {
    if (!node.IsSequence() || static_cast<int>(node.size()) != size) {
      Fail(node, path, "expected a list of " + std::to_string(size) + " numbers");
    }
    std::vector<double> out;
    for (int i = 0; i < size; ++i) {
      out.push_back(Double(node[i], path + "[" + std::to_string(i) + "]"));
    }
    return out;
  }

  Eigen::Vector3d Vector3(const YAML::Node& node, const std::string& path) const {
    const std::vector<double> v = Doubles(node, path, 3);
    return Eigen::Vector3d(v[0], v[1], v[2]);
  }

 private:
  std::string file_;
};

}  // namespace yaml_util
}  // namespace skerry
