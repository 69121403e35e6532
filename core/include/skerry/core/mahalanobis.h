#pragma once
/// \file
/// The squared Mahalanobis distance x^T P^-1 x, by Cholesky: what the gates (gnss_jump_test.h)
/// and the consistency figures (NEES, eval/evaluation.h) weigh an error by.

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <cmath>
#include <optional>

namespace skerry {

/// x^T P^-1 x; nullopt when P is not positive definite or the distance is not finite.
template <int N>
std::optional<double> SquaredMahalanobis(const Eigen::Matrix<double, N, 1>& x,
                                         const Eigen::Matrix<double, N, N>& P) {
  const Eigen::LLT<Eigen::Matrix<double, N, N>> llt(P);
  if (llt.info() != Eigen::Success) return std::nullopt;
  const double d2 = x.dot(llt.solve(x));
  if (!std::isfinite(d2)) return std::nullopt;
  return d2;
}

}  // namespace skerry
