#pragma once
/// \file
/// A receiver that solves once a period and propagates between (docs/twin.md: the Furuno logs'
/// 129025 rapid updates at ~7 Hz from 1 Hz solutions), seen in its fixes' horizontal residuals
/// against a smooth truth: a sawtooth locked to the receiver's clock. Within each period the
/// residual ramps (offset + v_err (t - t_solution), v_err the propagation velocity error), and
/// at each new solution it jumps. This is the model of sim/twin.h's solve_period_s and the
/// values it needs.
///
/// Detection: for each candidate period P the receiver could solve at (at least three fixes per
/// period on average) and each phase phi on a grid, the fixes' first differences are split into
/// those that cross a solution time phi + k P and those within one period; the jump shows as the
/// mean square difference across being larger than within; each period's phase is that of the
/// largest ratio. A candidate passes when that ratio and its z-score (difference of means over
/// their standard errors) pass their thresholds and the residuals are more correlated one period
/// apart than half a period apart (a sawtooth, not a slow drift, whose correlation falls with
/// the lag); of those passing, the largest ratio is kept (a multiple or a fraction of the true
/// period dilutes it).
///
/// Estimates, from a least-squares line per period and axis, a + b s (s = t - t_solution):
/// white noise sigma^2 = the lines' pooled residual variance; offset and velocity sigmas from
/// the spread of a and b less the white noise's share in them (the regression's
/// sigma^2 (1/n + s_mean^2 / Sxx) and sigma^2 / Sxx); the velocity error's correlation time from
/// the lag-1 correlation rho of consecutive slopes, tau = -P / ln(rho) (a first-order
/// Gauss-Markov process stepped once a period). Sigmas: a variance over N values correlated
/// as AR(1) with rho has relative sd sqrt(2 (1 + rho^2) / ((1 - rho^2) N)) (Bartlett 1946), the
/// lag-1 correlation sd sqrt((1 - rho^2) / N), carried to tau by its derivative.

#include <Eigen/Core>
#include <vector>

#include "skerry/core/time.h"
#include "skerry/eval/identified_value.h"

namespace skerry {

struct SolvePatternOptions {
  std::vector<double> candidate_periods_s = {0.5, 1.0, 2.0};
  double phase_step_s = 0.01;
  double min_jump_ratio = 1.5;  ///< mean square first difference across / within
  double min_jump_z = 6.0;
  /// Correlation one period apart less that half a period apart.
  double min_periodicity = 0.1;
};

struct SolvePattern {
  bool detected = false;
  double period_s = 0.0;  ///< of the best candidate, detected or not
  double phase_s = 0.0;   ///< solutions at stamps phase + k period (stamps' time scale)
  double jump_ratio = 0.0;
  double jump_z = 0.0;
  double period_correlation = 0.0;       ///< residuals' correlation one period apart
  double half_period_correlation = 0.0;  ///< ... half a period apart
  int periods = 0;                       ///< periods with enough fixes for a line
  /// Identified only when detected.
  IdentifiedValue white_sigma_horizontal_m;        ///< per axis, about the lines
  IdentifiedValue offset_sigma_m;                  ///< per axis, at the solution
  IdentifiedValue propagation_velocity_sigma_m_s;  ///< per axis
  IdentifiedValue propagation_velocity_tau_s;
};

/// The solve pattern of horizontal residuals `e_m` (east, north) at stamps `t_ns` (strictly
/// increasing); fixes with `gross` set (empty: none) are left out. Fewer than 30 fixes: not
/// detected. Throws std::invalid_argument when the sizes differ.
SolvePattern IdentifySolvePattern(const std::vector<TimeNs>& t_ns,
                                  const std::vector<Eigen::Vector2d>& e_m,
                                  const std::vector<bool>& gross = {},
                                  const SolvePatternOptions& options = {});

/// The correlation of horizontal residuals `lag_s` apart: each fix paired with the one nearest
/// to its stamp + lag (within half the median fix interval), sum e_i . e_j over sum |e_i|^2 of
/// all fixes, the residuals' median removed first. 0 without a pair.
double ResidualCorrelationAtLag(const std::vector<TimeNs>& t_ns,
                                const std::vector<Eigen::Vector2d>& e_m,
                                double lag_s);

}  // namespace skerry
