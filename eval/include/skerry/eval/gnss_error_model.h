#pragma once
/// \file
/// A GNSS receiver's error model identified from a recording, for the digital twin
/// (sim/twin.h, TwinGnssModel): latency, white noise, a first-order Gauss-Markov drift and gross
/// errors, each with a bootstrap uncertainty.
///
/// The caller holds a smoothed trajectory (the truth) and gives, for every fix, the residual
/// e = fix position - truth antenna position at the fix's stamp in local ENU metres, and the
/// antenna's true velocity v there. The model, per axis a:
///
///   e_a(t) = -v_a(t) L + w_a(t) + d_a(t) (+ a gross error with probability p)
///
/// with L the latency (a fix stamped L late shows where the antenna was L earlier), w white of
/// variance sw^2, and d a first-order Gauss-Markov process of stationary variance sd^2 and
/// correlation time T, whose autocovariance is sd^2 exp(-|tau| / T) (Gelb, Applied Optimal
/// Estimation, 1974, table 3.1-1; Brown and Hwang, Introduction to Random Signals and Applied
/// Kalman Filtering, 4th ed. 2012, sec. 2.9). East and north share sw, sd (the "horizontal" values,
/// per axis); up has its own; T is shared.
///
/// The fit, in order:
///   (a) Latency: least squares of e on -v over the horizontal axes, with an intercept per axis,
///       refitted once without the fixes whose residual exceeds 5 robust sigmas (1.4826 MAD).
///       Identified when the velocity excites it (the RMS horizontal velocity about its mean above
///       0.5 m/s, or the bootstrap sigma below |L|); otherwise reported as 0 and not removed.
///       An identified latency is removed from all three axes: e + v L.
///   (b) Gross errors: each axis' robust white scale from the first differences within contiguous
///       stretches (differences cancel the slow drift): s = 1.4826 MAD / sqrt(2). A fix is an
///       outlier when its horizontal deviation from the running median of 11 fixes (per axis,
///       within its stretch), in units of s, exceeds `outlier_threshold_sigma` (a 2-D norm; gross
///       errors are judged on the horizontal only, as the twin draws them). outlier_share is their
///       fraction of all fixes, outlier_sigma_horizontal_m the RMS horizontal norm of their
///       deviations (the twin draws a gross error as N(0, (sigma / sqrt(2))^2) per axis).
///   (c) On the other fixes, each axis less its mean: the empirical autocovariance C(k) at lags of
///       k median periods dt, k = 0..K (K dt = max_lag), from every pair whose time difference
///       rounds to k dt (gaps are fine; lag 0 is each fix with itself); east and north pooled.
///       Removing the sample mean biases every C(k) by -Var(mean) (Priestley, Spectral Analysis
///       and Time Series, 1981, sec. 5.3.3), which for the drift over a stretch of length S is
///       sd^2 b, b = 2 (T/S)^2 (S/T - 1 + exp(-S/T)) (summed over the stretches, weighted by the
///       squared share of fixes). The model
///
///         C(0) = sw^2 + sd^2 (1 - b),   C(k) = sd^2 (exp(-k dt / T) - b),  k >= 1,
///
///       is linear in sd^2 for a given T, so T is found by a log grid (dt/2 .. 20 K dt) refined
///       by golden section, each point with its least-squares sd^2 >= 0 per axis pair (T shared).
///       First a pilot weighting each lag by its pair count (each axis pair's error relative to
///       its C(0)^2); then, 3 times, generalised least squares on lags 1, 2, ... growing by 15 %
///       (neighbouring lags carry nearly the same information), weighted by the inverse of the
///       estimates' covariance under the previous fit, Bartlett's approximation
///       cov(C(k), C(l)) = S(k, l) / max(n_k, n_l), S(k, l) = sum_m [C(m) C(m + l - k) +
///       C(m + l) C(m - k)] (Bartlett, J. R. Stat. Soc. Suppl. 8, 1946; Priestley 1981,
///       eq. 5.3.21, there with 1/n for n even samples), n_k the pairs at lag k (with gaps, and in
///       the bootstrap's short blocks, lags have very different counts: a lag reached only by a
///       few pairs across a gap must weigh as little), with a ridge of 1e-3 of S's largest
///       variance. The sample autocovariances of a drift are strongly correlated across lags:
///       this weighting cuts the spread of T by a third against the pilot's.
///       The white variance is then read off the shortest lag's variogram (half the mean squared
///       difference of its pairs, C(0) - C(k) in expectation), gamma(k) = sw^2 + sd^2 (1 -
///       exp(-k dt / T)): C(0) - sd^2 (1 - b) would inherit the whole error of sd^2, often larger
///       than sw^2 itself, where this keeps only the error of the drift's increment over one lag.
///       The drift is identified when T lies within [2 dt, 10 K dt], its bootstrap sigma is below
///       T (the replicas of a series without drift scatter over the whole grid), and
///       sd >= 0.1 sw on that axis pair; otherwise the drift's value is reported 0 and the white
///       sigma is sqrt(C(0)) (all the variance). T is reported (the best fit) even when not
///       identified.
///   (d) Uncertainty: a moving block bootstrap (Kunsch, Ann. Statist. 17(3), 1989) of the whole
///       chain (a)-(c): replicas of N fixes built from blocks of consecutive fixes of
///       max(10 dt, 3 T) (capped at N / 5) drawn uniformly with replacement, blocks set apart in
///       time so that no pair spans two blocks; every IdentifiedValue.sigma is the standard
///       deviation over the replicas (of the quantity as reported: the white sigma with or
///       without the drift model as in the value). The replicas always remove their own latency
///       estimate. Deterministic in `seed`.
///
/// A stretch is a run of fixes without an interval longer than 10 median periods.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "skerry/eval/identified_value.h"

namespace skerry {

/// Per-fix residuals against the truth. All three vectors have one entry per fix.
struct GnssResidualSeries {
  std::vector<double> t_s;                 ///< fix stamps, strictly increasing, may have gaps
  std::vector<Eigen::Vector3d> e_enu_m;    ///< fix - truth antenna position: east, north, up
  std::vector<Eigen::Vector3d> v_enu_m_s;  ///< true antenna velocity at the stamp
};

struct GnssErrorModelFit {
  int samples = 0;   ///< fixes
  int outliers = 0;  ///< fixes flagged as gross errors
  /// e ~ -v latency: a fix stamped late shows where the antenna was `latency` earlier.
  IdentifiedValue latency_s;
  IdentifiedValue white_sigma_horizontal_m;  ///< per axis (east, north)
  IdentifiedValue white_sigma_vertical_m;
  IdentifiedValue drift_sigma_horizontal_m;  ///< Gauss-Markov, per axis, stationary
  IdentifiedValue drift_sigma_vertical_m;
  IdentifiedValue drift_tau_s;                 ///< its correlation time, shared by the axes
  IdentifiedValue outlier_share;               ///< fraction of the fixes that are gross errors
  IdentifiedValue outlier_sigma_horizontal_m;  ///< RMS horizontal norm of the gross errors
  double period_s = 0;                         ///< median fix interval
};

struct GnssFitOptions {
  double outlier_threshold_sigma = 5.0;  ///< > 0; a 2-D deviation in units of the white scale
  /// >= 0; 0: no bootstrap, every sigma 0 but the latency's, which is then its least-squares
  /// formal sigma (optimistic: it ignores the drift's correlation).
  int bootstrap_replicas = 200;
  std::uint64_t seed = 1;  ///< of the bootstrap's block draws
  double max_lag_s = 0;    ///< >= 0; 0: min(span / 10, 300 periods)
};

/// The error model of `series` (see the file comment). Throws std::invalid_argument on fewer than
/// 30 fixes, vectors of unequal length, a non-increasing or non-finite stamp, a non-finite
/// residual or velocity (naming the index and field), or an invalid option.
GnssErrorModelFit FitGnssErrorModel(const GnssResidualSeries& series,
                                    const GnssFitOptions& options = {});

}  // namespace skerry
