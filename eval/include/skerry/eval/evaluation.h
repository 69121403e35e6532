#pragma once
/// \file
/// Accuracy of an estimate against ground truth. No alignment: GNSS fixes the world frame, so
/// errors are taken in the local ENU frame directly.

#include <string>
#include <vector>

#include "skerry/io/estimate_io.h"
#include "skerry/io/trajectory.h"

namespace skerry {

/// Per-epoch error of one estimate against interpolated ground truth.
struct EpochError {
  TimeNs t_ns = 0;
  Eigen::Vector3d p_err_w = Eigen::Vector3d::Zero();    ///< estimate - truth, ENU m
  Eigen::Vector3d rot_err_w = Eigen::Vector3d::Zero();  ///< Log(R_est R_true^T), rad (world)
  double heading_err_deg = 0.0;                         ///< estimate - truth, wrapped
  bool has_nees = false;
  double nees_pos = 0.0;   ///< 3-DOF position NEES
  double nees_pose = 0.0;  ///< 6-DOF rotation+position NEES
  /// 2-DOF horizontal (east, north) position NEES: what 2-D position aids observe, apart from a
  /// vertical channel they leave to the IMU.
  double nees_horizontal = 0.0;
};

struct Stats {
  int count = 0;
  double rmse = 0.0;
  double mean = 0.0;
  double median = 0.0;
  double max = 0.0;
};

struct EvaluationResult {
  std::vector<EpochError> epochs;
  Stats horizontal;       ///< |dE, dN| m
  Stats vertical;         ///< |dU| m
  Stats position3d;       ///< |dp| m
  Stats east, north, up;  ///< signed components: rmse/mean/max(|.|)
  Stats heading_deg;      ///< |heading error| deg
  Stats roll_pitch_deg;   ///< tilt error |(rot_err_e, rot_err_n)| deg
  Stats rpe_trans_m;      ///< relative pose error over rpe_delta_s, translation m
  Stats rpe_rot_deg;      ///< relative pose error over rpe_delta_s, rotation deg
  double rpe_delta_s = 1.0;
  int nees_count = 0;
  double anees_pos = 0.0;   ///< average 3-DOF position NEES
  double anees_pose = 0.0;  ///< average 6-DOF NEES
  /// How many independent epochs the position NEES series is worth (EffectiveSampleSize): what
  /// AneesBounds needs, since consecutive keyframes' errors are strongly correlated.
  double nees_effective_count = 0.0;
  int unmatched = 0;  ///< estimate epochs outside the ground-truth span
};

Stats ComputeStats(std::vector<double> values);

/// Percentile `p` in [0, 100] with linear interpolation between order statistics (Hyndman and
/// Fan 1996, type 7, as numpy and R by default); NaN if empty. The one order statistic of
/// skerry's outputs, benchmarks and reports.
double Percentile(std::vector<double> values, double p);

EvaluationResult Evaluate(const std::vector<EstimateRecord>& estimate,
                          const std::vector<StampedPose>& groundtruth,
                          double rpe_delta_s = 1.0);

/// Two-sided chi-square bounds for an average NEES of `count` independent samples of `dof` each,
/// at confidence `p` (e.g. 0.95): the returned pair is (lower, upper) on the ANEES. `count` may
/// be an effective number of samples (EffectiveSampleSize): the average of correlated NEES is
/// then taken as chi-square with dof * count degrees of freedom over count, the distribution with
/// its mean and (inflated) variance. (NaN, NaN) when there is no sample (count <= 0).
std::pair<double, double> AneesBounds(int dof, double count, double p = 0.95);

/// The number of independent samples a correlated, stationary series is worth for its mean:
/// N / tau, tau = 1 + 2 sum_k rho_k the integrated autocorrelation time, summed with Geyer's
/// initial positive sequence (Geyer, "Practical Markov chain Monte Carlo", Statistical Science
/// 7(4), 1992: pairs rho_2m + rho_2m+1 while positive and non-increasing). In [1, N]; N for a
/// constant series. The NEES of one run's consecutive keyframes is such a series: its plain
/// chi-square bounds treat 6000 epochs as independent when they are worth about 100.
double EffectiveSampleSize(const std::vector<double>& series);

/// The Monte-Carlo NEES test (Bar-Shalom, Li and Kirubarajan 2001, sec. 5.4.2) over several runs
/// of one scenario: at each epoch the position NEES averaged over the N runs that have one lies,
/// for a consistent estimator, inside the two-sided bounds AneesBounds(3, N, p). Unlike one
/// ANEES pooled over all epochs, whose bounds assume independent epochs, this holds however
/// correlated consecutive epochs are.
struct NeesTest {
  int epochs = 0;             ///< epochs tested
  double time_average = 0.0;  ///< mean over those epochs of the run-averaged NEES
  double inside = 0.0;        ///< share of epochs inside the bounds (ideal: p)
  double above = 0.0;         ///< above: overconfident
  double below = 0.0;         ///< below: underconfident
};

/// Epochs are matched by time, to the nearest multiple of `bin_ns` when it is > 0 (runs of
/// different seeds start their keyframe grids a few milliseconds apart when the first fix they
/// start from is stamped with jitter: pass the keyframe period); those with a NEES in fewer than
/// `min_runs` runs are left out (pass the number of runs to test only the epochs every run
/// shares).
/// `horizontal`: test the 2-DOF horizontal position NEES instead of the 3-DOF one.
NeesTest MonteCarloNeesTest(const std::vector<const EvaluationResult*>& runs,
                            int min_runs = 1,
                            double p = 0.95,
                            TimeNs bin_ns = 0,
                            bool horizontal = false);

}  // namespace skerry
