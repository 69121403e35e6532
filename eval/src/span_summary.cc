#include "skerry/eval/span_summary.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace skerry {

SpanSummary SummariseSpan(const EvaluationResult& evaluation,
                          TimeNs from_ns,
                          TimeNs to_ns,
                          double edge_s) {
  if (to_ns < from_ns) throw std::invalid_argument("SummariseSpan: the span ends before it starts");
  if (!(edge_s > 0.0)) throw std::invalid_argument("SummariseSpan: edge_s must be > 0");
  SpanSummary out;
  out.from_s = NsToSeconds(from_ns);
  out.to_s = NsToSeconds(to_ns);
  out.edge_s = edge_s;
  const TimeNs edge_ns = SecondsToNs(edge_s);
  std::vector<double> h, psi, first, last, nees_h, nees_p;
  for (const EpochError& e : evaluation.epochs) {
    if (e.t_ns < from_ns || e.t_ns > to_ns) continue;
    const double d = e.p_err_w.head<2>().norm();
    h.push_back(d);
    psi.push_back(e.heading_err_deg);
    if (e.t_ns < from_ns + edge_ns) first.push_back(d);
    if (e.t_ns > to_ns - edge_ns) last.push_back(d);
    if (e.has_nees) {
      nees_h.push_back(e.nees_horizontal);
      nees_p.push_back(e.nees_pos);
    }
  }
  if (h.empty()) {
    throw std::invalid_argument("SummariseSpan: no estimate between " + std::to_string(out.from_s) +
                                " s and " + std::to_string(out.to_s) + " s");
  }
  out.count = static_cast<int>(h.size());
  out.horizontal = ComputeStats(h);
  out.heading_rmse_deg = ComputeStats(psi).rmse;
  // ComputeStats' mean, NaN for an empty stretch (its own is 0 there).
  const auto mean = [](const std::vector<double>& v) {
    return v.empty() ? std::numeric_limits<double>::quiet_NaN() : ComputeStats(v).mean;
  };
  out.first_mean_m = mean(first);
  out.last_mean_m = mean(last);
  out.growth = out.last_mean_m / out.first_mean_m;
  out.nees_count = static_cast<int>(nees_p.size());
  if (!nees_p.empty()) {
    out.anees_horizontal = mean(nees_h);
    out.anees_pos = mean(nees_p);
    out.nees_effective_count = EffectiveSampleSize(nees_p);
    out.bounds_horizontal = AneesBounds(2, out.nees_effective_count);
    out.bounds_pos = AneesBounds(3, out.nees_effective_count);
  }
  return out;
}

}  // namespace skerry
