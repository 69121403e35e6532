#pragma once
/// \file
/// A step in the GNSS receiver's drift: the Gauss-Markov transition of gnss_drift_factor.h with a
/// jump s between the two keyframes,
///   b_j = phi b_i + s + w_d,   Var(w_d) = sigma^2 (1 - phi^2) per axis,
/// where s is the receiver's jump as measured from its fixes' innovations, with covariance C_s.
/// The jump becomes part of the state the fixes are measured against instead of a reason to
/// refuse them: the fixes after it keep their relative information (the motion between them),
/// and their absolute information is only as good as the jump's estimate. This is the
/// generalised likelihood ratio's "jump in a linear system" taken into the state once detected
/// (Willsky and Jones 1976, IEEE TAC 21(1), sec. III: the estimate of the jump's size and its
/// covariance incremented into the filter's state and covariance).
/// Residual r = L^T (b_j - phi b_i - s) with L L^T = (Q_w + C_s)^-1, Q_w = diag(sigma_w^2).

#include <ceres/sized_cost_function.h>

#include <Eigen/Core>

#include "skerry/factors/gnss_drift_factor.h"

namespace skerry {

/// Parameter blocks: b_w(i)[3], b_w(j)[3] (tangent = ambient, Jacobians analytic).
class GnssDriftStepFactor : public ceres::SizedCostFunction<3, 3, 3> {
 public:
  /// `step_m` the jump s (m, in the drift's frame: world ENU), `step_cov` its covariance C_s
  /// (symmetric, positive semi-definite). Throws std::invalid_argument when Q_w + C_s is not
  /// positive definite or either is not finite.
  GnssDriftStepFactor(const GnssDriftParams& params,
                      double dt_s,
                      const Eigen::Vector3d& step_m,
                      const Eigen::Matrix3d& step_cov);
  bool Evaluate(double const* const* parameters,
                double* residuals,
                double** jacobians) const override;

  double phi() const { return phi_; }
  /// Covariance of b_j given b_i: Q_w + C_s.
  const Eigen::Matrix3d& covariance() const { return covariance_; }

 private:
  double phi_;
  Eigen::Vector3d step_m_;
  Eigen::Matrix3d covariance_;
  Eigen::Matrix3d sqrt_info_;  ///< L^T, upper triangular
};

}  // namespace skerry
