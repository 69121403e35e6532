#include "skerry/eval/stream_timing.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <stdexcept>

namespace skerry {
namespace {

constexpr double kGapPeriods = 1.5;  // an interval above this many periods is a gap
constexpr double kSpanGapS = 2.0;    // gaps above this are listed in gap_spans_s
constexpr double kMadToSigma = 1.4826;

double Median(std::vector<double> v) {
  const std::size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + m, v.end());
  const double hi = v[m];
  if (v.size() % 2 == 1) return hi;
  return 0.5 * (hi + *std::max_element(v.begin(), v.begin() + m));
}

}  // namespace

StreamTiming AnalyseStreamTiming(const std::string& name,
                                 const std::vector<std::int64_t>& stamps_ns) {
  const std::string where = "AnalyseStreamTiming(" + name + "): ";
  if (stamps_ns.size() < 2) {
    throw std::invalid_argument(where + std::to_string(stamps_ns.size()) +
                                " stamps, at least 2 needed");
  }
  std::vector<double> intervals(stamps_ns.size() - 1);
  for (std::size_t i = 1; i < stamps_ns.size(); ++i) {
    if (stamps_ns[i] <= stamps_ns[i - 1]) {
      throw std::invalid_argument(where + "stamp " + std::to_string(i) + " (" +
                                  std::to_string(stamps_ns[i]) + " ns) not after stamp " +
                                  std::to_string(i - 1) + " (" + std::to_string(stamps_ns[i - 1]) +
                                  " ns)");
    }
    intervals[i - 1] = 1e-9 * static_cast<double>(stamps_ns[i] - stamps_ns[i - 1]);
  }
  StreamTiming out;
  out.name = name;
  out.samples = static_cast<long>(stamps_ns.size());
  out.duration_s = 1e-9 * static_cast<double>(stamps_ns.back() - stamps_ns.front());
  const double period = Median(intervals);
  out.rate_hz = 1.0 / period;
  std::vector<double> regular;
  regular.reserve(intervals.size());
  double missing = 0.0;
  for (std::size_t i = 0; i < intervals.size(); ++i) {
    const double d = intervals[i];
    if (d <= kGapPeriods * period) {
      regular.push_back(d);
      continue;
    }
    ++out.gaps;
    out.longest_gap_s = std::max(out.longest_gap_s, d);
    missing += std::max(0.0, std::round(d / period) - 1.0);
    if (d > kSpanGapS) {
      const double start = 1e-9 * static_cast<double>(stamps_ns[i] - stamps_ns.front());
      out.gap_spans_s.emplace_back(start, start + d);
    }
  }
  // The median interval is a regular one, so `regular` is not empty.
  const double med = Median(regular);
  for (double& d : regular) d = std::abs(d - med);
  out.period_jitter_s = kMadToSigma * Median(regular);
  out.dropout_share = missing / (static_cast<double>(out.samples) + missing);
  return out;
}

}  // namespace skerry
