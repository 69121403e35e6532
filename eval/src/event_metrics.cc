#include "skerry/eval/event_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace skerry {

EventMetrics ComputeEventMetrics(const EvaluationResult& evaluation,
                                 const std::vector<GnssEvent>& events,
                                 double settle_s,
                                 double settle_after_outage_s) {
  EventMetrics m;
  if (evaluation.epochs.empty()) return m;
  const TimeNs t_first = evaluation.epochs.front().t_ns;
  const TimeNs settle_after_ns = SecondsToNs(settle_after_outage_s);
  auto in_outage = [&events, settle_after_ns](TimeNs t) {
    return std::any_of(events.begin(), events.end(), [t, settle_after_ns](const GnssEvent& e) {
      return e.type == "outage" && t >= e.t_start_ns && t < e.t_end_ns + settle_after_ns;
    });
  };
  std::vector<double> horizontal, heading;
  for (const EpochError& e : evaluation.epochs) {
    if (NsToSeconds(e.t_ns - t_first) < settle_s || in_outage(e.t_ns)) continue;
    horizontal.push_back(e.p_err_w.head<2>().norm());
    heading.push_back(std::abs(e.heading_err_deg));
  }
  m.horizontal_outside_outages = ComputeStats(horizontal);
  m.heading_outside_outages_deg = ComputeStats(heading);
  for (const GnssEvent& ev : events) {
    // NaN when no estimate lies in the event (withdrawn by the watchdog, or before the start).
    double max_err = std::numeric_limits<double>::quiet_NaN(), last_err = max_err;
    for (const EpochError& e : evaluation.epochs) {
      if (e.t_ns < ev.t_start_ns || e.t_ns >= ev.t_end_ns) continue;
      last_err = e.p_err_w.head<2>().norm();
      max_err = std::isnan(max_err) ? last_err : std::max(max_err, last_err);
    }
    if (ev.type == "outage") {
      m.outages.push_back({NsToSeconds(ev.t_start_ns), NsToSeconds(ev.t_end_ns - ev.t_start_ns),
                           last_err, max_err});
    } else if (ev.type == "jump") {
      m.jumps.push_back({NsToSeconds(ev.t_start_ns), NsToSeconds(ev.t_end_ns - ev.t_start_ns),
                         ev.offset_enu_m.norm(), max_err});
    }
  }
  return m;
}

}  // namespace skerry
