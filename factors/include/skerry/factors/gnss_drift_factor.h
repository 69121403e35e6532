#pragma once
/// \file
/// GNSS position drift: a slowly varying bias b_w (m, ENU) on every position fix, modelled per
/// axis as a first-order Gauss-Markov process
///   db/dt = -b / tau + w(t),   stationary standard deviation sigma (sigma_h for east and north,
///                              sigma_v for up), correlation time tau.
/// Exact discretisation over dt between consecutive keyframes (Maybeck, "Stochastic Models,
/// Estimation and Control", vol. 1, 1979, sec. 4.9; Brown & Hwang, "Introduction to Random
/// Signals and Applied Kalman Filtering", 4th ed., sec. 3.9 and 4.2):
///   b_j = phi b_i + w_d,   phi = exp(-dt / tau),   Var(w_d) = sigma^2 (1 - phi^2).
/// GnssDriftFactor whitens that transition; GnssDriftPriorFactor is the stationary distribution
/// N(0, diag(sigma_h^2, sigma_h^2, sigma_v^2)) used on the first keyframe.

#include <ceres/sized_cost_function.h>

#include <Eigen/Core>

namespace skerry {

/// Parameters of the drift model. sigma 0 (both axes) switches the model off: the bias blocks
/// then stay constant at zero.
struct GnssDriftParams {
  double sigma_horizontal_m = 0.15;  ///< stationary sigma, east and north
  double sigma_vertical_m = 0.3;     ///< stationary sigma, up
  double tau_s = 300.0;              ///< correlation time

  bool enabled() const { return sigma_horizontal_m > 0.0 || sigma_vertical_m > 0.0; }
  /// Stationary sigmas (e, n, u). An axis with sigma 0 gets a tiny sigma (1 mm), so it stays
  /// pinned near zero while the other axes drift.
  Eigen::Vector3d StationarySigma() const;
};

/// Transition between consecutive keyframes (tangent = ambient, Jacobians analytic):
///   r = diag(1 / sigma_w) (b_j - phi b_i),  sigma_w = sigma sqrt(1 - phi^2) per axis.
/// Parameter blocks: b_w(i)[3], b_w(j)[3].
class GnssDriftFactor : public ceres::SizedCostFunction<3, 3, 3> {
 public:
  GnssDriftFactor(const GnssDriftParams& params, double dt_s);
  bool Evaluate(double const* const* parameters,
                double* residuals,
                double** jacobians) const override;

  double phi() const { return phi_; }
  const Eigen::Vector3d& sqrt_info() const { return sqrt_info_; }

 private:
  double phi_;
  Eigen::Vector3d sqrt_info_;  ///< 1 / sigma_w per axis
};

/// Zero-mean prior r = diag(1 / sigma) b_w with the stationary sigmas. Parameter block: b_w[3].
class GnssDriftPriorFactor : public ceres::SizedCostFunction<3, 3> {
 public:
  explicit GnssDriftPriorFactor(const GnssDriftParams& params);
  bool Evaluate(double const* const* parameters,
                double* residuals,
                double** jacobians) const override;

 private:
  Eigen::Vector3d sqrt_info_;
};

}  // namespace skerry
