#pragma once
/// \file
/// How slow a GNSS drift the twin's identification can see at all (docs/twin.md).
///
/// The truth of a twin is the batch smoother through the recording's *own* fixes, so a slow GNSS
/// error that the IMU cannot tell from motion is followed by the truth and is missing from the
/// residuals the error model is fitted to (eval/gnss_error_model.h). How much of it is missing is
/// measured, not assumed: a known first-order Gauss-Markov error of correlation time T is added
/// to the fixes, the batch re-run, and the change of the residuals compared with what was added.
/// For an estimator linear in its measurements (the batch is, near its solution, inside the
/// quadratic part of its losses) the residuals are r = (I - H) z with H the smoother's hat matrix
/// (the fixes' influence on their own fitted values), so the change is (I - H) d for an added
/// error d: its size relative to d's is the batch's gain g(T), whatever the noise already in z.
///
///   g(T) = RMS(delta r - mean) / RMS(d - mean),   horizontal (east, north pooled) and vertical,
///
/// both about their means: the residuals' model is fitted about their mean, and a constant
/// offset is absorbed whole. A drift of stationary sigma s leaves about g(T) s in the residuals;
/// the identification calls a drift seen when its estimate reaches `threshold` (the larger of
/// kDriftMinShareOfWhite x the white sigma, eval/src/gnss_error_model.cc, and z bootstrap
/// sigmas of the drift estimate: below that it is inside the estimate's own scatter), so the
/// smallest drift it could have seen at T is
///
///   detectable(T) = threshold / g(T).
///
/// A drift the identification did not see is then stated as {value 0, sigma: the largest
/// detectable(T) over the probes}: what the data could not have shown.

#include <Eigen/Core>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

#include "skerry/eval/gnss_error_model.h"

namespace skerry {

/// The correlation times probed for a recording of `span_s` seconds of fixes every `period_s`
/// (both > 0): 3, 30 and 300 s, each clipped to [2 period, span / 2] (a longer correlation time
/// looks like an offset and a ramp over the span), duplicates after clipping dropped, in
/// increasing order. Throws std::invalid_argument on a span or period that is not finite and > 0.
std::vector<double> DriftProbeTaus(double span_s, double period_s);

/// A first-order Gauss-Markov error at the stamps `t_s` (non-decreasing): east and north each of
/// stationary sigma `sigma_horizontal_m`, up of `sigma_vertical_m`, correlation time `tau_s`, by
/// the exact discretisation d_k = phi d_(k-1) + sqrt(1 - phi^2) sigma w_k, phi =
/// exp(-(t_k - t_(k-1)) / tau) (Brown and Hwang 2012, sec. 2.9; the twin's own drift,
/// sim/twin.h), started from its stationary distribution. The same on every standard library for
/// a given `seed` (normals by Box-Muller from std::mt19937_64). Throws std::invalid_argument on a
/// decreasing or non-finite stamp, tau not > 0, or a negative or non-finite sigma.
std::vector<Eigen::Vector3d> GaussMarkovPerturbation(const std::vector<double>& t_s,
                                                     double tau_s,
                                                     double sigma_horizontal_m,
                                                     double sigma_vertical_m,
                                                     std::uint64_t seed);

/// The share of an injected error that survives into the residuals (see the file comment).
struct DriftBatchGain {
  double horizontal = 0.0;  ///< east and north pooled
  double vertical = 0.0;    ///< 0 when nothing was injected vertically
};

/// One batch run on the perturbed fixes: the injected error and the change it made in the
/// residuals (after - before), one entry per fix in both.
struct PerturbedBatchRun {
  std::vector<Eigen::Vector3d> injected_enu_m;
  std::vector<Eigen::Vector3d> residual_change_enu_m;
  /// Each entry's index in the residual series the identification fitted (ConfirmDetection).
  std::vector<std::size_t> index;
};

/// g pooled over independent realizations (runs) of the injected error: the sums of squares
/// about each run's own means, added over the runs, then the ratio's square root. A slow error
/// over a short span has few independent swings, and one realization's gain scatters by tens of
/// percent; pooling R of them cuts that by sqrt(R). Throws std::invalid_argument on no run, a
/// run with vectors of unequal length or fewer than 2 entries, or a non-finite entry.
DriftBatchGain MeasureBatchGain(const std::vector<PerturbedBatchRun>& runs);

/// The smallest drift sigma in the residuals that the identification calls seen: the larger of
/// `min_share_of_white` x `white_sigma_m` (kDriftMinShareOfWhite in eval/src/gnss_error_model.cc)
/// and `z` x `drift_bootstrap_sigma_m` (the scatter of the drift estimate over the bootstrap
/// replicas: a drift inside it is not told from none). All >= 0 and finite, else
/// std::invalid_argument.
double DriftSeenThreshold(double white_sigma_m,
                          double drift_bootstrap_sigma_m,
                          double min_share_of_white = 0.1,
                          double z = 2.0);

/// One probe: the batch's gain at a correlation time and the smallest drift seen there.
struct DriftDetection {
  double tau_s = 0.0;
  DriftBatchGain batch_gain;
  /// threshold / gain (+infinity when nothing survives, gain 0): what the batch leaves for an
  /// identification that needed only the drift's amplitude.
  double gain_limit_sigma_horizontal_m = 0.0;
  double gain_limit_sigma_vertical_m = 0.0;
  /// The gain's limit, raised by ConfirmDetection to the level the identification was seen to
  /// see.
  double detectable_sigma_horizontal_m = 0.0;
  double detectable_sigma_vertical_m = 0.0;
  /// ConfirmDetection: the identification, fitted to the residuals with a drift of the stated
  /// sigma added, identified it in a majority of the runs (false: not even at the last level
  /// tried, which the stated sigma then is, a lower bound of the limit).
  bool confirmed_horizontal = false;
  bool confirmed_vertical = false;
};

/// The probe at `tau_s` from its measured gain and the thresholds (DriftSeenThreshold).
DriftDetection DriftDetectionAt(double tau_s,
                                const DriftBatchGain& gain,
                                double threshold_horizontal_m,
                                double threshold_vertical_m);

/// The residuals the identification would have fitted with the injected error of `run` scaled
/// by `scale_horizontal` (east, north) and `scale_vertical` (up): before + scale * change, on the
/// fixes of `run` (`run.index` into `before`, increasing). The batch answers a drift linearly
/// (file comment), so no batch run is needed per scale. Throws std::invalid_argument on an
/// index out of range or not increasing, or vectors of unequal length.
GnssResidualSeries ScaledPerturbedResiduals(const GnssResidualSeries& before,
                                            const PerturbedBatchRun& run,
                                            double scale_horizontal,
                                            double scale_vertical);

/// The identification as run on the recording: an error model fitted to a residual series.
using GnssFitFunction = std::function<GnssErrorModelFit(const GnssResidualSeries&)>;

/// Checks `probe`'s limit against the identification itself: the threshold of DriftSeenThreshold
/// is on the drift's amplitude only, but the identification also needs the drift's correlation
/// time resolved (eval/gnss_error_model.h), which a drift the batch has partly taken (left with
/// the faster part of it) may not give. Each run's injected error (of stationary sigma
/// `injected_sigma_horizontal_m`, `injected_sigma_vertical_m`) is scaled to the stated limits
/// (ScaledPerturbedResiduals, both axis pairs at once, as a receiver's drift has both) and `fit`
/// run on it; an axis pair not identified in a majority of the runs has its limit doubled, up to
/// `max_doublings` times. Returns the probe with its confirmed limits and flags. An infinite or
/// zero limit, or a zero injected sigma, is left as it is, not confirmed.
DriftDetection ConfirmDetection(const DriftDetection& probe,
                                const std::vector<PerturbedBatchRun>& runs,
                                const GnssResidualSeries& before,
                                double injected_sigma_horizontal_m,
                                double injected_sigma_vertical_m,
                                const GnssFitFunction& fit,
                                int max_doublings = 4);

/// States the limit in `fit`: a drift sigma that was not identified gets, as its sigma, the
/// largest detectable sigma over `probes` ({value 0, sigma limit} then covers every drift the
/// data could not have shown); an identified one keeps its bootstrap sigma. No probes: unchanged.
void StateDriftDetectionLimit(const std::vector<DriftDetection>& probes, GnssErrorModelFit* fit);

}  // namespace skerry
