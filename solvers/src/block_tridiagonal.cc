#include "skerry/solvers/block_tridiagonal.h"

#include <Eigen/Cholesky>
#include <cmath>

namespace skerry {

bool SolveBlockTridiagonal(std::vector<ChainBlock>* D_io,
                           const std::vector<ChainBlock>& O,
                           std::vector<ChainVector>* b_io,
                           double mu,
                           double* scaled_step_norm2,
                           double* scaled_rhs_dot) {
  std::vector<ChainBlock>& D = *D_io;
  std::vector<ChainVector>& b = *b_io;
  const size_t n = D.size();
  if (n == 0) return true;
  // Jacobi scaling, keyframe by keyframe: s_k = diag(D_k)^-1/2. The information of a
  // navigation-grade IMU's biases is ~1e20 next to ~1e2 for position; scaled, the pivots hold
  // only the conditioning of the correlations.
  std::vector<ChainVector> s(n);
  for (size_t k = 0; k < n; ++k) {
    for (int i = 0; i < 18; ++i) {
      const double d = D[k](i, i);
      s[k][i] = d > 0.0 ? 1.0 / std::sqrt(d) : 1.0;
    }
  }
  auto scaled_offdiagonal = [&](size_t k) -> ChainBlock {
    return s[k].asDiagonal() * O[k] * s[k + 1].asDiagonal();
  };
  // Forward elimination: S_0 = D_0, S_k+1 = D_k+1 - O_k^T S_k^-1 O_k; c_0 = b_0,
  // c_k+1 = b_k+1 - O_k^T S_k^-1 c_k (all scaled, damped by mu on the diagonal).
  std::vector<ChainVector> rhs(n);
  for (size_t k = 0; k < n; ++k) {
    rhs[k] = s[k].cwiseProduct(b[k]);
    b[k] = rhs[k];
  }
  Eigen::LLT<ChainBlock> llt;
  ChainBlock S = s[0].asDiagonal() * D[0] * s[0].asDiagonal();
  for (size_t k = 0; k < n; ++k) {
    S.diagonal().array() += mu;
    llt.compute(S);
    if (llt.info() != Eigen::Success) return false;
    D[k] = llt.matrixLLT();
    if (k + 1 == n) break;
    // With S_k = L L^T, V = L^-1 O_k and u = L^-1 c_k: O_k^T S_k^-1 O_k = V^T V (a symmetric
    // rank update of the lower triangle, the only one the next LLT reads) and
    // O_k^T S_k^-1 c_k = V^T u. One triangular solve instead of two, half the product.
    ChainBlock V = scaled_offdiagonal(k);
    llt.matrixL().solveInPlace(V);
    ChainVector u = b[k];
    llt.matrixL().solveInPlace(u);
    S = s[k + 1].asDiagonal() * D[k + 1] * s[k + 1].asDiagonal();
    S.selfadjointView<Eigen::Lower>().rankUpdate(V.transpose(), -1.0);
    b[k + 1].noalias() -= V.transpose() * u;
  }
  // Back substitution: y_n = S_n^-1 c_n, y_k = S_k^-1 (c_k - O_k y_k+1).
  double norm2 = 0.0, dot = 0.0;
  ChainVector y_next;
  for (size_t k = n; k-- > 0;) {
    ChainVector y = b[k];
    if (k + 1 < n) y.noalias() -= scaled_offdiagonal(k) * y_next;
    D[k].triangularView<Eigen::Lower>().solveInPlace(y);
    D[k].triangularView<Eigen::Lower>().adjoint().solveInPlace(y);
    norm2 += y.squaredNorm();
    dot += rhs[k].dot(y);
    y_next = y;
    b[k] = s[k].cwiseProduct(y);
  }
  if (scaled_step_norm2 != nullptr) *scaled_step_norm2 = norm2;
  if (scaled_rhs_dot != nullptr) *scaled_rhs_dot = dot;
  return true;
}

}  // namespace skerry
