#include "bench_util.h"

#include <sched.h>
#include <sys/resource.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <limits>
#include <sstream>

namespace skerry::bench {

int RunMain(Flags& flags,
            int argc,
            char** argv,
            const std::string& summary,
            const std::function<int()>& body) {
  try {
    flags.Parse(argc, argv);
    if (flags.help_requested()) {
      std::printf("%s", flags.Usage(argv[0], summary).c_str());
      return 0;
    }
    return body();
  } catch (const UsageError& e) {
    std::fprintf(stderr, "error: %s\n\n%s", e.what(), flags.Usage(argv[0], summary).c_str());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}

double Max(const std::vector<double>& values) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  return *std::max_element(values.begin(), values.end());
}

double PeakRssMiB() {
  rusage usage{};
  if (getrusage(RUSAGE_SELF, &usage) != 0) return std::numeric_limits<double>::quiet_NaN();
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // Linux: KiB
}

double ProcessCpuSeconds() {
  timespec ts{};
  if (clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts) != 0) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

std::string LoadAverage() {
  std::ifstream in("/proc/loadavg");
  std::string one, five, fifteen;
  if (!(in >> one >> five >> fifteen)) return "?";
  return one + " " + five + " " + fifteen;
}

void PinToCpu(int cpu) {
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  if (sched_setaffinity(0, sizeof(set), &set) != 0) {
    throw std::runtime_error("sched_setaffinity(cpu " + std::to_string(cpu) +
                             "): " + std::strerror(errno));
  }
}

void Flags::Declare(const std::string& name,
                    const std::string& default_value,
                    const std::string& help,
                    bool is_switch) {
  specs_[name] = Spec{default_value, help, is_switch, {}};
  order_.push_back(name);
}

void Flags::Parse(int argc, char** argv) {
  for (int k = 1; k < argc; ++k) {
    std::string arg = argv[k];
    if (arg == "-h" || arg == "--help") {
      help_ = true;
      continue;
    }
    if (arg.rfind("--", 0) != 0) throw UsageError("unexpected argument '" + arg + "'");
    arg = arg.substr(2);
    std::string value;
    bool has_value = false;
    const size_t eq = arg.find('=');
    if (eq != std::string::npos) {
      value = arg.substr(eq + 1);
      arg = arg.substr(0, eq);
      has_value = true;
    }
    const auto it = specs_.find(arg);
    if (it == specs_.end()) throw UsageError("unknown flag --" + arg);
    Spec& spec = it->second;
    if (spec.is_switch) {
      if (has_value) throw UsageError("--" + arg + " takes no value");
      spec.values.push_back("1");
      continue;
    }
    if (!has_value) {
      if (k + 1 >= argc) throw UsageError("--" + arg + " needs a value");
      value = argv[++k];
    }
    if (value.empty()) throw UsageError("--" + arg + " needs a non-empty value");
    spec.values.push_back(value);
  }
}

std::string Flags::Usage(const std::string& program, const std::string& summary) const {
  std::ostringstream out;
  out << "usage: " << program << " [flags]\n" << summary << "\n\nflags:\n";
  for (const std::string& name : order_) {
    const Spec& s = specs_.at(name);
    out << "  --" << name << (s.is_switch ? "" : " VALUE") << "\n      " << s.help;
    if (!s.is_switch && !s.default_value.empty()) out << " (default: " << s.default_value << ")";
    out << "\n";
  }
  return out.str();
}

const Flags::Spec& Flags::Get(const std::string& name) const {
  const auto it = specs_.find(name);
  if (it == specs_.end()) throw std::logic_error("undeclared flag --" + name);
  return it->second;
}

std::string Flags::String(const std::string& name) const {
  const Spec& s = Get(name);
  if (s.values.size() > 1) throw UsageError("--" + name + " given more than once");
  return s.values.empty() ? s.default_value : s.values.front();
}

std::vector<std::string> Flags::Strings(const std::string& name) const {
  const Spec& s = Get(name);
  if (s.values.empty()) return {s.default_value};
  return s.values;
}

std::int64_t Flags::Int(const std::string& name, std::int64_t min_value) const {
  const std::string text = String(name);
  size_t used = 0;
  long long value = 0;
  try {
    value = std::stoll(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size()) throw UsageError("--" + name + ": '" + text + "' is not an integer");
  if (value < min_value) {
    throw UsageError("--" + name + ": must be >= " + std::to_string(min_value));
  }
  return value;
}

double Flags::Double(const std::string& name, double min_value) const {
  const std::string text = String(name);
  size_t used = 0;
  double value = 0.0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || !std::isfinite(value)) {
    throw UsageError("--" + name + ": '" + text + "' is not a finite number");
  }
  if (value < min_value)
    throw UsageError("--" + name + ": must be >= " + std::to_string(min_value));
  return value;
}

bool Flags::Switch(const std::string& name) const { return !Get(name).values.empty(); }

}  // namespace skerry::bench
