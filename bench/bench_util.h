#pragma once
/// \file
/// Small helpers shared by the CLI benchmarks (window_benchmark, batch_benchmark): order
/// statistics, peak memory, CPU pinning and a strict command-line parser (unknown flags and
/// malformed values are errors, reported at the CLI boundary).

#include <cstdint>
#include <functional>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "skerry/eval/evaluation.h"

namespace skerry::bench {

using skerry::Percentile;  // core/evaluation.h: p in [0, 100], linear interpolation
/// Median of the values (NaN if empty).
inline double Median(std::vector<double> values) { return Percentile(std::move(values), 50.0); }
double Max(const std::vector<double>& values);

/// Peak resident set size of this process so far (getrusage ru_maxrss), MiB.
double PeakRssMiB();

/// CPU time consumed by this process so far (all threads), s.
double ProcessCpuSeconds();

/// The first three fields of /proc/loadavg ("?" if unreadable): on a shared machine, wall-time
/// figures only mean something next to it.
std::string LoadAverage();

/// Pins the calling thread and its future children to one CPU; throws std::runtime_error.
void PinToCpu(int cpu);

/// Thrown on a bad command line.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// `--name value` / `--name=value` / `--switch` parser. Declare every flag, then Parse().
class Flags {
 public:
  void Declare(const std::string& name,
               const std::string& default_value,
               const std::string& help,
               bool is_switch = false);
  /// Throws UsageError on unknown flags, missing values or positional arguments.
  void Parse(int argc, char** argv);
  bool help_requested() const { return help_; }
  std::string Usage(const std::string& program, const std::string& summary) const;

  std::string String(const std::string& name) const;
  /// All values given for a repeatable flag (in order), or {default} if none.
  std::vector<std::string> Strings(const std::string& name) const;
  std::int64_t Int(const std::string& name, std::int64_t min_value) const;
  double Double(const std::string& name, double min_value) const;
  bool Switch(const std::string& name) const;

 private:
  struct Spec {
    std::string default_value;
    std::string help;
    bool is_switch = false;
    std::vector<std::string> values;
  };
  const Spec& Get(const std::string& name) const;
  std::map<std::string, Spec> specs_;
  std::vector<std::string> order_;
  bool help_ = false;
};

/// Every benchmark's main: parses `argv` into `flags`, prints the usage for --help, else runs
/// `body`. A UsageError (unknown flag, malformed value, also when `body` reads a flag) prints the
/// error and the usage and returns 2; any other exception prints its message and returns 1.
int RunMain(Flags& flags,
            int argc,
            char** argv,
            const std::string& summary,
            const std::function<int()>& body);

}  // namespace skerry::bench
