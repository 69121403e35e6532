#pragma once
/// \file
/// Does a twin's GNSS look like the recording's? For a recording without IMU (a marine logger's
/// file) no estimator runs, so the twin is judged on statistics of the fixes themselves: each
/// stream measured the same way (gnss_track.h: the maximum-likelihood white noise and
/// acceleration spectral density of a nearly-constant-velocity track through it; the lag-1
/// correlation of its horizontal residuals against that track; the share of fixes in
/// gross-error episodes), and the recording's value of each statistic ranked among the twins'
/// with the two-sided rank test of twin_fidelity.h (docs/twin.md).

#include <string>
#include <vector>

#include "skerry/core/measurements.h"

namespace skerry {

struct GnssStatistics {
  double white_sigma_horizontal_m = 0.0;
  double white_sigma_vertical_m = 0.0;
  bool vertical_identified = false;   ///< false: the fixes carry no height (a flat up axis)
  double accel_psd_horizontal = 0.0;  ///< m^2/s^3
  double lag1_correlation_horizontal = 0.0;
  double gross_share = 0.0;
  double rate_hz = 0.0;
  /// With a receiver's solve period (solve_pattern.h): the residuals' correlation one period
  /// apart, the sawtooth's signature (ResidualCorrelationAtLag).
  bool period_measured = false;
  double period_correlation_horizontal = 0.0;
};

/// The statistics of one stream of fixes (at least 30, strictly increasing in time); the
/// correlation one `solve_period_s` apart too when it is > 0.
GnssStatistics MeasureGnssStatistics(const std::vector<GnssFix>& fixes,
                                     double solve_period_s = 0.0);

struct StatisticComparison {
  std::string name;
  double real = 0.0;
  double twins_mean = 0.0, twins_sd = 0.0, twins_min = 0.0, twins_max = 0.0;
  double p_value = 1.0;  ///< two-sided rank of the recording's value among all K + 1
  bool indistinguishable = true;
};

/// Each statistic of `real` against those of the twins (at least 2); the vertical white noise
/// only when the recording's is identified, the correlation at the solve period only when
/// measured. Throws std::invalid_argument otherwise or unless
/// 0 < alpha < 1.
std::vector<StatisticComparison> CompareGnssStatistics(const GnssStatistics& real,
                                                       const std::vector<GnssStatistics>& twins,
                                                       double alpha = 0.1);

/// The fixed scales of StatisticsDistance from a reference comparison (the identified model's
/// twins): each statistic's twins' sd, except that the share of gross fixes is floored at its
/// binomial sampling sd sqrt(p (1 - p) / n) over the recording's `fixes`, p its share (at least
/// one fix): a few twins of a short or clean log often have no gross fix at all, and a zero
/// scale would make that term an unmovable 1e6.
std::vector<double> StatisticsScales(const std::vector<StatisticComparison>& reference,
                                     size_t fixes);

/// How far the recording's statistics lie from the twins': the sum over the compared statistics
/// of ((real - twins' mean) / scale)^2, with `scales` fixed (one per comparison: the twins' sd of
/// a reference model), so that a model cannot come closer by making its twins scatter more. A
/// scale of 0 counts 0 for an exact match and 1e6 otherwise. The objective of a GNSS-only twin's
/// calibration. Throws std::invalid_argument when the sizes differ.
double StatisticsDistance(const std::vector<StatisticComparison>& comparisons,
                          const std::vector<double>& scales);

}  // namespace skerry
