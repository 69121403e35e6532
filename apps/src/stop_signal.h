#pragma once
/// \file
/// SIGINT and SIGTERM as a request to stop, not a kill: the first such signal sets a flag that
/// the estimation loops poll (RunWindow between samples, the batch between Ceres iterations), so
/// the command stops at once, writes every estimate made so far and marks its summary.json
/// "interrupted". The handler is one-shot: a second signal ends the process the default way.

#include <atomic>

namespace skerry::cli {

class StopSignal {
 public:
  /// Installs the handlers (the process' previous ones come back on destruction).
  StopSignal();
  ~StopSignal();
  StopSignal(const StopSignal&) = delete;
  StopSignal& operator=(const StopSignal&) = delete;

  /// Set from the handler; give it to RunWindow / SmoothBatch.
  const std::atomic<bool>* flag() const;
  bool stopped() const { return flag()->load(); }
  /// The signal that arrived (0: none).
  int signal_number() const;
  /// The shell's status for a process ended by that signal: 128 + its number.
  int exit_status() const { return 128 + signal_number(); }
  /// "SIGINT" / "SIGTERM" ("" when none arrived).
  const char* signal_name() const;
};

}  // namespace skerry::cli
