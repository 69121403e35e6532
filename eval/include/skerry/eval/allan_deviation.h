#pragma once
/// \file
/// IMU noise identification by Allan deviation, for the digital twin (docs/twin.md): the
/// overlapping Allan deviation of a rate signal, the noise terms read off its slopes, rest found
/// anywhere in a recording, and a CSV / SVG report of the curves.
///
/// The Allan variance of a rate y sampled every tau0 = 1/rate, with cluster time tau = m tau0 and
/// the angle (integrated rate) theta_k = tau0 sum_{i<k} y_i, k = 0..N (IEEE Std 952-1997 Annex C;
/// El-Sheimy, Hou and Niu, IEEE Trans. Instrum. Meas. 57(1), 2008):
///
///   sigma^2(tau) = 1 / (2 tau^2 (N - 2m + 1)) sum_{k=0}^{N-2m} (theta_{k+2m} - 2 theta_{k+m}
///                                                               + theta_k)^2
///
/// which every overlapping pair of clusters enters. The noise terms add in variance
/// (IEEE 952 C.1): white rate noise of density N gives sigma = N / sqrt(tau) (slope -1/2), flicker
/// (bias instability B) a floor sigma = B sqrt(2 ln 2 / pi) = 0.664 B (slope 0), rate random walk
/// of density K gives sigma = K sqrt(tau / 3) (slope +1/2).

#include <array>
#include <cstddef>
#include <string>
#include <vector>

#include "skerry/core/measurements.h"
#include "skerry/eval/identified_value.h"

namespace skerry {

/// One point of an Allan deviation curve.
struct AllanPoint {
  double tau_s = 0.0;       ///< cluster time m / rate
  double adev = 0.0;        ///< overlapping Allan deviation, in the signal's units
  double adev_sigma = 0.0;  ///< 1-sigma of adev: adev / sqrt(2 (N/m - 1)) (El-Sheimy 2008's
                            ///< percentage error of a cluster size m)
  long clusters = 0;        ///< independent (non-overlapping) clusters in the data, N / m
};

/// The fully overlapping Allan deviation of `x`, a rate signal sampled at `rate_hz`, from the
/// cumulative sum (O(N) per tau). Taus m / rate_hz with m on a logarithmic grid of
/// `points_per_decade` from 1 to N / 9 (each m once). Throws std::invalid_argument on fewer than 20
/// samples, a non-positive or non-finite rate, points_per_decade < 1, or a non-finite sample.
std::vector<AllanPoint> OverlappingAllanDeviation(const std::vector<double>& x,
                                                  double rate_hz,
                                                  int points_per_decade = 10);

/// The noise terms read off one Allan deviation curve.
struct AllanFit {
  /// N, units / sqrt(Hz) (rad/s/sqrt(Hz) for a gyro): sigma = N / sqrt(tau) fitted over the slope
  /// -1/2 +- 0.2 region, a run that starts among the first 3 points; identified when there is
  /// one, else adev sqrt(tau) at the shortest tau.
  IdentifiedValue white_density;
  /// B, units: min(sigma) / 0.664; identified when the minimum is not at the longest tau.
  IdentifiedValue bias_instability;
  /// K, units / s / sqrt(Hz) (rad/s^2/sqrt(Hz)): sigma = K sqrt(tau / 3) fitted over the slope
  /// +1/2 region beyond the minimum; identified when at least 2 points rise there, else 0.
  IdentifiedValue random_walk;
  double min_tau_s = 0.0;  ///< where the curve has its minimum
};

/// The slopes of `curve` (as OverlappingAllanDeviation returns it, at least 1 point; throws
/// std::invalid_argument when empty). Sigmas are propagated treating the points' errors as fully
/// correlated, since every point is computed from the same data.
AllanFit FitAllan(const std::vector<AllanPoint>& curve);

/// Samples [begin, end) of a recording during which the platform does not move.
struct RestSegment {
  size_t begin = 0, end = 0;
  double duration_s = 0;  ///< t[end - 1] - t[begin] plus one median sample interval
};

constexpr double kRestSegmentBlockS = 0.5;   ///< the blocks whose means are compared
constexpr double kRestSegmentMaxGapS = 0.1;  ///< a longer gap between samples ends a rest

/// Rest anywhere in `imu` (samples in time order): the samples are cut into blocks of
/// kRestSegmentBlockS, and a run of consecutive blocks is at rest while each block's mean gyro and
/// mean specific force stay within `gyro_tol_rad_s` and `accel_tol_m_s2` (per axis) of the run's
/// first block's means, and no gap longer than kRestSegmentMaxGapS lies within or between its
/// blocks (as DetectRestAtStart, solvers/rest_detection.h, does for the start of the data). Every
/// block starts a run as long as it stays at rest; of those lasting at least `min_duration_s`,
/// the longest that overlap no longer one are returned, longest first (so a block half in a
/// motion does not cut the rest beside it). Empty for an empty `imu`.
std::vector<RestSegment> FindRestSegments(const std::vector<ImuSample>& imu,
                                          double min_duration_s,
                                          double gyro_tol_rad_s = 0.3 * 3.14159265358979323846 /
                                                                  180.0,
                                          double accel_tol_m_s2 = 0.1);

/// The Allan analysis of an IMU at rest.
struct ImuAllanReport {
  RestSegment rest;
  double rate_hz = 0.0;  ///< from the median sample interval within `rest`
  std::array<std::vector<AllanPoint>, 3> gyro, accel;  ///< per axis, rad/s and m/s^2
  std::array<AllanFit, 3> gyro_fit, accel_fit;
  /// Per sensor: each parameter the RMS over the three axes, its sigma propagated from the axes'
  /// (independent); identified when it is on every axis.
  AllanFit gyro_combined, accel_combined;
};

/// Allan curves and fits of the samples `rest` of `imu`. Throws std::invalid_argument when `rest`
/// is not within `imu`, has fewer than 20 samples or no positive sample interval.
ImuAllanReport AnalyseImuAtRest(const std::vector<ImuSample>& imu, const RestSegment& rest);

/// Writes the curves as CSV: tau_s, gyro_{x,y,z}_adev, accel_{x,y,z}_adev, then the same nine
/// columns' `_sigma`, one row per tau of the gyro curves. Throws std::runtime_error naming `path`
/// when it cannot be written.
void WriteAllanCsv(const std::string& path, const ImuAllanReport& report);

/// Writes a self-contained SVG: two log-log panels (gyro rad/s, accelerometer m/s^2), the three
/// axes with their 1-sigma band, the fitted N / sqrt(tau) and K sqrt(tau / 3) lines dashed, decade
/// grid and labels, a legend. Throws std::runtime_error naming `path` when it cannot be written.
void WriteAllanSvg(const std::string& path, const ImuAllanReport& report, const std::string& title);

}  // namespace skerry
