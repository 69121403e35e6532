#pragma once
/// \file
/// Simulated GNSS events (events.csv): outages and position jumps, kept for reports.

#include <Eigen/Core>
#include <string>

#include "skerry/core/time.h"

namespace skerry {

/// One event over [t_start_ns, t_end_ns). `type` is "outage" (no fixes) or "jump" (every fix in
/// the interval is offset by offset_enu_m; zero for outages).
struct GnssEvent {
  TimeNs t_start_ns = 0;
  TimeNs t_end_ns = 0;
  std::string type;
  Eigen::Vector3d offset_enu_m = Eigen::Vector3d::Zero();
};

}  // namespace skerry
