#pragma once
/// \file
/// Time inside skerry is an int64 count of nanoseconds; text files carry seconds (double).

#include <cmath>
#include <cstdint>

namespace skerry {

/// Nanoseconds since an arbitrary epoch (the dataset's clock).
using TimeNs = std::int64_t;

/// The longest duration skerry takes from a configuration (about 32 years: any value near it
/// means "never"). TimeNs holds 292 years; beyond that SecondsToNs has no meaningful result.
constexpr double kMaxDurationS = 1e9;

/// Seconds (as written in text files) to nanoseconds, rounded to the nearest ns.
inline TimeNs SecondsToNs(double seconds) {
  return static_cast<TimeNs>(std::llround(seconds * 1e9));
}

/// Nanoseconds to seconds.
inline double NsToSeconds(TimeNs ns) { return static_cast<double>(ns) * 1e-9; }

}  // namespace skerry
