#pragma once
/// \file
/// The timing of one sensor stream of a recording, for the digital twin (docs/twin.md): its
/// rate, the jitter of its stamps, and where and how much of it is missing.
///
/// The nominal period p is the median interval (robust to the gaps themselves). An interval above
/// 1.5 p is a gap; it stands for round(interval / p) - 1 missing epochs. The jitter is the robust
/// standard deviation 1.4826 MAD of the other intervals.

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace skerry {

struct StreamTiming {
  std::string name;
  long samples = 0;
  double duration_s = 0;       ///< last stamp - first stamp
  double rate_hz = 0;          ///< 1 / median interval
  double period_jitter_s = 0;  ///< 1.4826 MAD of the intervals that are not gaps
  int gaps = 0;                ///< intervals > 1.5 nominal periods
  double longest_gap_s = 0;    ///< the longest such interval; 0 without gaps
  double dropout_share = 0;    ///< missing epochs / (samples + missing epochs)
  /// (start, end) of each gap longer than 2 s, in seconds since the first stamp.
  std::vector<std::pair<double, double>> gap_spans_s;
};

/// The timing of a stream with stamps `stamps_ns` (nanoseconds, any epoch). Throws
/// std::invalid_argument, naming the stream (and the index), on fewer than 2 stamps or a stamp not
/// after its predecessor.
StreamTiming AnalyseStreamTiming(const std::string& name,
                                 const std::vector<std::int64_t>& stamps_ns);

}  // namespace skerry
