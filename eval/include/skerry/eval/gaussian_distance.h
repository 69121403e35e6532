#pragma once
/// \file
/// Distances between two Gaussians N(mu1, P1) and N(mu2, P2), given the mean difference
/// Delta = mu2 - mu1 in a common tangent space.
///
/// Bhattacharyya distance (Bhattacharyya 1943; closed form for Gaussians e.g. Kailath 1967,
/// IEEE Trans. Commun. Technol. 15(1), or Pardo 2006, "Statistical Inference Based on
/// Divergence Measures"):
///   D_B = 1/8 Delta^T Pbar^-1 Delta + 1/2 ln( |Pbar| / sqrt(|P1| |P2|) ),  Pbar = (P1 + P2) / 2
/// Hellinger distance: HED^2 = 1 - BC with the Bhattacharyya coefficient BC = exp(-D_B), i.e.
///   HED^2 = 1 - |P1|^1/4 |P2|^1/4 / |Pbar|^1/2 * exp(-1/8 Delta^T Pbar^-1 Delta).
/// HED is 0 for identical Gaussians and tends to 1 as they separate.

#include <Eigen/Core>

namespace skerry {

struct GaussianDistance {
  bool valid = false;         ///< false: a covariance is not finite symmetric positive definite
  double hellinger_sq = 0.0;  ///< HED^2 in [0, 1]
  double hellinger = 0.0;     ///< HED in [0, 1]
  double covdiff = 0.0;       ///< HED with Delta = 0: the covariance-only part, in [0, 1]
  /// HED with P1 = P2 = Pbar: the mean-only part, sqrt(1 - exp(-Delta^T Pbar^-1 Delta / 8)).
  /// BC = BC_mean BC_cov, so HED^2 = 1 - (1 - meandiff^2)(1 - covdiff^2).
  double meandiff = 0.0;
  double bhattacharyya = 0.0;  ///< D_B >= 0 (unbounded)
};

/// The distances, with log-determinants and Pbar^-1 Delta from Cholesky factorisations (never a
/// determinant, which under- or overflows for 15-D states). HED^2 is computed as -expm1(-D_B),
/// accurate for nearly identical Gaussians. Returns valid = false (all distances 0) when a
/// covariance has non-finite entries, is not symmetric to 1e-9 relative, or is not positive
/// definite; never NaN.
GaussianDistance CompareGaussians(const Eigen::VectorXd& delta,
                                  const Eigen::MatrixXd& p1,
                                  const Eigen::MatrixXd& p2);

/// True when `p` is finite, symmetric to 1e-9 relative and its Cholesky factorisation succeeds.
bool IsCovariance(const Eigen::MatrixXd& p);

}  // namespace skerry
