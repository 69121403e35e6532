#include "skerry/twin/gnss_statistics.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "median.h"
#include "skerry/twin/gnss_track.h"
#include "skerry/twin/solve_pattern.h"
#include "skerry/twin/twin_fidelity.h"

namespace skerry {
using twin_internal::Median;

namespace {
constexpr const char* kGrossShareName = "share of gross fixes";
}  // namespace

GnssStatistics MeasureGnssStatistics(const std::vector<GnssFix>& fixes, double solve_period_s) {
  if (fixes.size() < 30) {
    throw std::invalid_argument("MeasureGnssStatistics: needs at least 30 fixes, got " +
                                std::to_string(fixes.size()));
  }
  const GnssTrack track = SmoothGnssTrack(fixes);
  GnssStatistics s;
  s.white_sigma_horizontal_m = track.white_sigma_horizontal_m.value;
  s.white_sigma_vertical_m = track.white_sigma_vertical_m.value;
  s.vertical_identified = track.white_sigma_vertical_m.identified;
  s.accel_psd_horizontal = track.accel_psd_horizontal;
  const size_t n = fixes.size();
  s.rate_hz = (n - 1) / NsToSeconds(fixes.back().t_ns - fixes.front().t_ns);
  // Horizontal residuals against the track; gross when beyond 5 robust scales of them.
  std::vector<Eigen::Vector2d> e(n);
  std::vector<double> east(n), north(n);
  for (size_t i = 0; i < n; ++i) {
    e[i] = (fixes[i].p_w - track.states[i].p_w_b).head<2>();
    east[i] = e[i].x();
    north[i] = e[i].y();
  }
  const Eigen::Vector2d med(Median(east), Median(north));
  for (size_t i = 0; i < n; ++i) {
    east[i] = std::abs(east[i] - med.x());
    north[i] = std::abs(north[i] - med.y());
  }
  const double scale = std::max(1.4826 * std::max(Median(east), Median(north)), 1e-6);
  int gross = 0;
  double c0 = 0.0, c1 = 0.0;
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d d = e[i] - med;
    gross += d.norm() > 5.0 * scale ? 1 : 0;
    c0 += d.squaredNorm();
    if (i + 1 < n) c1 += d.dot(e[i + 1] - med);
  }
  s.gross_share = static_cast<double>(gross) / static_cast<double>(n);
  s.lag1_correlation_horizontal = c0 > 0.0 ? c1 / c0 : 0.0;
  if (solve_period_s > 0.0) {
    std::vector<TimeNs> t(n);
    for (size_t i = 0; i < n; ++i) t[i] = fixes[i].t_ns;
    s.period_measured = true;
    s.period_correlation_horizontal = ResidualCorrelationAtLag(t, e, solve_period_s);
  }
  return s;
}

std::vector<StatisticComparison> CompareGnssStatistics(const GnssStatistics& real,
                                                       const std::vector<GnssStatistics>& twins,
                                                       double alpha) {
  if (twins.size() < 2) throw std::invalid_argument("CompareGnssStatistics: needs 2 twins");
  if (!(alpha > 0.0 && alpha < 1.0)) {
    throw std::invalid_argument("CompareGnssStatistics: alpha must be in (0, 1)");
  }
  const std::vector<std::pair<const char*, double GnssStatistics::*>> fields = {
      {"white sigma horizontal (m)", &GnssStatistics::white_sigma_horizontal_m},
      {"white sigma vertical (m)", &GnssStatistics::white_sigma_vertical_m},
      {"acceleration PSD horizontal (m^2/s^3)", &GnssStatistics::accel_psd_horizontal},
      {"lag-1 correlation of residuals", &GnssStatistics::lag1_correlation_horizontal},
      {"correlation at the solve period", &GnssStatistics::period_correlation_horizontal},
      {kGrossShareName, &GnssStatistics::gross_share}};
  std::vector<StatisticComparison> out;
  const double n = static_cast<double>(twins.size()) + 1.0;
  for (const auto& [name, member] : fields) {
    if (member == &GnssStatistics::white_sigma_vertical_m && !real.vertical_identified) continue;
    if (member == &GnssStatistics::period_correlation_horizontal && !real.period_measured) {
      continue;
    }
    StatisticComparison c;
    c.name = name;
    c.real = real.*member;
    c.twins_min = c.twins_max = twins.front().*member;
    for (const GnssStatistics& t : twins) {
      const double v = t.*member;
      c.twins_mean += v / static_cast<double>(twins.size());
      c.twins_min = std::min(c.twins_min, v);
      c.twins_max = std::max(c.twins_max, v);
    }
    for (const GnssStatistics& t : twins) {
      c.twins_sd += (t.*member - c.twins_mean) * (t.*member - c.twins_mean);
    }
    c.twins_sd = std::sqrt(c.twins_sd / (static_cast<double>(twins.size()) - 1.0));
    // Ranks among all K + 1 values, the recording's own included (ties against the twin).
    int hi = 1, lo = 1;
    for (const GnssStatistics& t : twins) {
      hi += t.*member >= c.real ? 1 : 0;
      lo += t.*member <= c.real ? 1 : 0;
    }
    c.p_value = TwoSidedRankP(hi, lo, static_cast<int>(n));
    c.indistinguishable = c.p_value > alpha;
    out.push_back(c);
  }
  return out;
}

std::vector<double> StatisticsScales(const std::vector<StatisticComparison>& reference,
                                     size_t fixes) {
  if (fixes == 0) throw std::invalid_argument("StatisticsScales: no fix");
  std::vector<double> scales;
  for (const StatisticComparison& c : reference) {
    double scale = c.twins_sd;
    if (c.name == kGrossShareName) {
      const double n = static_cast<double>(fixes);
      const double p = std::clamp(c.real, 1.0 / n, 1.0 - 1.0 / n);
      scale = std::max(scale, std::sqrt(p * (1.0 - p) / n));
    }
    scales.push_back(scale);
  }
  return scales;
}

double StatisticsDistance(const std::vector<StatisticComparison>& comparisons,
                          const std::vector<double>& scales) {
  if (scales.size() != comparisons.size()) {
    throw std::invalid_argument("StatisticsDistance: one scale per statistic");
  }
  double sum = 0.0;
  for (size_t i = 0; i < comparisons.size(); ++i) {
    const double d = comparisons[i].real - comparisons[i].twins_mean;
    if (scales[i] > 0.0) {
      sum += (d / scales[i]) * (d / scales[i]);
    } else if (d != 0.0) {
      sum += 1e6;  // the twins never vary and the recording differs
    }
  }
  return sum;
}

}  // namespace skerry
