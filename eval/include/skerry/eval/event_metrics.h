#pragma once
/// \file
/// Accuracy around simulated GNSS events (events.csv): RMSE outside outages, the error at the end
/// of every outage, and the largest error while a jump is on.

#include <vector>

#include "skerry/core/gnss_event.h"
#include "skerry/eval/evaluation.h"

namespace skerry {

struct OutageMetric {
  double t_start_s = 0.0;
  double duration_s = 0.0;
  // Both NaN when no estimate lies in the outage (the watchdog withdrew them).
  double horizontal_error_at_end_m = 0.0;  ///< at the last estimate before the outage ends
  double max_horizontal_error_m = 0.0;
};

struct JumpMetric {
  double t_start_s = 0.0;
  double duration_s = 0.0;
  double offset_m = 0.0;                ///< |offset| of the fixes
  double max_horizontal_error_m = 0.0;  ///< of the estimate, while the jump is on; NaN if none
};

struct EventMetrics {
  Stats horizontal_outside_outages;
  /// |dE,dN| over epochs not inside an outage nor within settle_after_outage_s of its end
  Stats heading_outside_outages_deg;
  std::vector<OutageMetric> outages;
  std::vector<JumpMetric> jumps;
};

/// `settle_s`: epochs closer than this to the start of the estimate are left out of the
/// outside-outage statistics (initial convergence); so are those within
/// `settle_after_outage_s` of the end of an outage (re-convergence after re-acquisition).
EventMetrics ComputeEventMetrics(const EvaluationResult& evaluation,
                                 const std::vector<GnssEvent>& events,
                                 double settle_s = 0.0,
                                 double settle_after_outage_s = 10.0);

}  // namespace skerry
