#pragma once
/// \file
/// A time given on the command line (--until, --from, --to, fidelity's --offset).

#include "skerry/core/time.h"

namespace skerry::cli {

/// `t_s` in nanoseconds: finite and within kMaxDurationS of zero, else an InputError naming
/// `option` (1e300 came out as a negative time and a message about the data's start; nan was
/// taken as "not given").
TimeNs CommandLineTime(double t_s, const char* option);

}  // namespace skerry::cli
