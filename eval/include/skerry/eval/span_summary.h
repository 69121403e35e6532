#pragma once
/// \file
/// Accuracy over one stretch of a run (a GNSS outage, a denied span): the horizontal error's
/// mean and max, whether it grows (the mean over the span's first and last `edge_s` seconds),
/// heading RMSE, and consistency — horizontal (2-DOF) and 3-D position ANEES, each with its
/// two-sided 95 % bounds over the effective number of independent epochs (evaluation.h).

#include "skerry/core/time.h"
#include "skerry/eval/evaluation.h"

namespace skerry {

struct SpanSummary {
  double from_s = 0.0, to_s = 0.0;  ///< the span asked for
  int count = 0;                    ///< epochs inside it
  Stats horizontal;                 ///< |dE, dN| m
  double heading_rmse_deg = 0.0;
  double edge_s = 0.0;
  double first_mean_m = 0.0;  ///< mean |dE, dN| over [from, from + edge_s)
  double last_mean_m = 0.0;   ///< mean |dE, dN| over (to - edge_s, to]
  double growth = 0.0;        ///< last / first (NaN if either edge is empty)
  int nees_count = 0;         ///< epochs with a covariance
  double anees_horizontal = 0.0, anees_pos = 0.0;
  std::pair<double, double> bounds_horizontal{0.0, 0.0}, bounds_pos{0.0, 0.0};
  double nees_effective_count = 0.0;
};

/// The epochs of `evaluation` with from <= t <= to. std::invalid_argument if to < from, edge_s
/// is not > 0, or no epoch lies in the span.
SpanSummary SummariseSpan(const EvaluationResult& evaluation,
                          TimeNs from_ns,
                          TimeNs to_ns,
                          double edge_s = 300.0);

}  // namespace skerry
