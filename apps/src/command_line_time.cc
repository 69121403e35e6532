#include "command_line_time.h"

#include <fmt/format.h>

#include <cmath>

#include "skerry/core/input_error.h"

namespace skerry::cli {

TimeNs CommandLineTime(double t_s, const char* option) {
  if (!std::isfinite(t_s) || std::abs(t_s) > kMaxDurationS) {
    throw InputError(
        kCommandLine, 0, option,
        fmt::format("{}: must be a finite time in seconds, within +-{:g} s", t_s, kMaxDurationS));
  }
  return SecondsToNs(t_s);
}

}  // namespace skerry::cli
