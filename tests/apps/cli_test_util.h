#pragma once
// Helpers of the end-to-end tests that run the real `skerry` binary (its path: SKERRY_BIN).

#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "core/test_util.h"

extern char** environ;

namespace skerry::testing {

struct CliResult {
  int status = -1;
  std::string out;
  std::string err;
};

/// Runs `skerry ARGS` (arguments are quoted by the caller where needed) and captures its output.
inline CliResult RunCli(const std::string& args) {
  const std::string dir = FreshDir("cli_io");
  const std::string out = dir + "/stdout.txt", err = dir + "/stderr.txt";
  const std::string cmd =
      std::string("'") + SKERRY_BIN + "' " + args + " > '" + out + "' 2> '" + err + "'";
  const int raw = std::system(cmd.c_str());
  CliResult r;
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  r.out = ReadText(out);
  r.err = ReadText(err);
  return r;
}

/// `skerry ARGS...` started in the background, its output thrown away.
class Child {
 public:
  explicit Child(const std::vector<std::string>& args) {
    std::vector<std::string> argv_strings = {SKERRY_BIN};
    argv_strings.insert(argv_strings.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& a : argv_strings) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, "/dev/null", O_WRONLY, 0);
    posix_spawn_file_actions_addopen(&actions, 2, "/dev/null", O_WRONLY, 0);
    const int rc = posix_spawn(&pid_, SKERRY_BIN, &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    EXPECT_EQ(rc, 0) << "cannot start " << SKERRY_BIN;
  }
  void Signal(int signal_number) const { ::kill(pid_, signal_number); }
  /// The exit status; 128 + the signal when a signal ended it (as a shell says).
  int Wait() const {
    int raw = 0;
    ::waitpid(pid_, &raw, 0);
    return WIFEXITED(raw) ? WEXITSTATUS(raw) : 128 + WTERMSIG(raw);
  }

 private:
  pid_t pid_ = -1;
};

inline std::string Quote(const std::string& s) { return "'" + s + "'"; }

/// Writes `dir`/unbudgeted.yaml, the default preset without its per-solve time budget
/// (`solver.max_time_s` 0), and returns its path. Two runs compared to the last bit use it: a
/// loaded machine can end a budgeted solve at an earlier iteration in one run than the other.
inline std::string UnbudgetedConfig(const std::string& dir) {
  const std::string path = dir + "/unbudgeted.yaml";
  WriteText(path, "name: unbudgeted\nsolver: {max_time_s: 0}\n");
  return path;
}

/// config/scenarios/harbour.yaml cut to `duration_s` and named `name`; its GNSS jump and outage
/// are replaced by `events` (YAML lines indented as under `gnss:`, e.g.
/// "  jumps:\n    - {start_s: 60, duration_s: 20, offset_enu_m: [14.5, 0, 0]}\n"; empty: none).
inline std::string ShortScenarioYaml(double duration_s,
                                     const std::string& name = "harbour-short",
                                     const std::string& events = "") {
  const std::vector<std::string> lines =
      ReadLines(std::string(SKERRY_SOURCE_DIR) + "/config/scenarios/harbour.yaml");
  std::ostringstream out;
  bool in_events = false;
  bool found_duration = false;
  for (const std::string& line : lines) {
    if (in_events && line.rfind("    - ", 0) == 0) continue;  // a jump/outage entry
    in_events = false;
    if (line.rfind("  jumps:", 0) == 0) {
      out << events;
      in_events = true;
      continue;
    }
    if (line.rfind("  outages:", 0) == 0) {
      in_events = true;
      continue;
    }
    if (line.rfind("duration_s:", 0) == 0) {
      out << "duration_s: " << duration_s << "\n";
      found_duration = true;
      continue;
    }
    if (line.rfind("name:", 0) == 0) {
      out << "name: " << name << "\n";
      continue;
    }
    out << line << "\n";
  }
  EXPECT_TRUE(found_duration);
  return out.str();
}

}  // namespace skerry::testing
