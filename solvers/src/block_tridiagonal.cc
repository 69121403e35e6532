#include "skerry/solvers/block_tridiagonal.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

#include "skerry/solvers/triangular_substitution.h"

namespace skerry {

void BlockTridiagonalSolver::Start(size_t n, double mu, int arrow_dim, GainPrecision gains) {
  mu_ = mu;
  n_ = n;
  k_ = 0;
  ok_ = arrow_dim >= 0;
  m_ = std::max(arrow_dim, 0);
  single_ = gains == GainPrecision::kSingle;
  // The gains of one precision; the other's storage is let go.
  const size_t num_gains = n > 0 ? n - 1 : 0;
  const auto arrow_cols = static_cast<Eigen::Index>(m_ * n);
  if (single_) {
    std::vector<ChainBlock>().swap(G_);
    zw_.resize(18, 0);
    Gs_.resize(num_gains);
    zws_.resize(18, arrow_cols);
  } else {
    std::vector<Eigen::Matrix<float, 18, 18>>().swap(Gs_);
    zws_.resize(18, 0);
    G_.resize(num_gains);
    zw_.resize(18, arrow_cols);
  }
  z_.resize(n);
  s_.resize(n);
  rhs_.resize(n);
  if (m_ > 0) {
    CtW_.setZero(m_, m_);
    Cty_.setZero(m_);
  }
}

bool BlockTridiagonalSolver::EliminatePrevious(const ChainBlock* O_scaled,
                                               ChainBlock* V,
                                               ChainVector* u) {
  const size_t k = k_ - 1;
  S_.diagonal().array() += mu_;
  const Eigen::LLT<ChainBlock> llt(S_);
  if (llt.info() != Eigen::Success) return false;
  // With S_k = L L^T and u = L^-1 c_k: z_k = L^-T u. With V = L^-1 O~_k: G_k = L^-T V, and the
  // next pivot loses O~^T S^-1 O~ = V^T V, its right-hand side O~^T S^-1 c = V^T u.
  const ChainBlock& L = llt.matrixLLT();  // L in the lower triangle
  *u = c_;
  llt.matrixL().solveInPlace(*u);
  z_[k] = *u;
  llt.matrixU().solveInPlace(z_[k]);
  if (m_ > 0) {
    // The arrow's right-hand sides go through the same elimination; cw_ keeps L^-1 c_w for the
    // next pivot's. With H_c = L L^T (block bidiagonal L), C^T H_c^-1 C = (L^-1 C)^T (L^-1 C)
    // and C^T H_c^-1 b_c = (L^-1 C)^T (L^-1 b_c): both are sums over the keyframes of this pass.
    Eigen::Matrix<double, Eigen::Dynamic, 18> t = cw_.transpose();
    SolveLowerOnTransposed(L, &t);
    cw_ = t.transpose();
    SolveUpperOnTransposed(L, &t);
    const auto first = static_cast<Eigen::Index>(k * m_);
    if (single_) {
      zws_.middleCols(first, m_) = t.transpose().cast<float>();
    } else {
      zw_.middleCols(first, m_) = t.transpose();
    }
    // m x m from 18 x m: coefficient-wise, Eigen's general product packs more than it multiplies.
    CtW_.noalias() += cw_.transpose().lazyProduct(cw_);
    Cty_.noalias() += cw_.transpose() * (*u);
  }
  if (O_scaled == nullptr) return true;
  ChainBlock t = O_scaled->transpose();
  SolveLowerOnTransposed(L, &t);
  *V = t.transpose();
  SolveUpperOnTransposed(L, &t);
  if (single_) {
    Gs_[k] = t.transpose().cast<float>();
  } else {
    G_[k] = t.transpose();
  }
  return true;
}

bool BlockTridiagonalSolver::Push(const ChainBlock& D,
                                  const ChainVector& b,
                                  const ChainBlock* O_prev,
                                  const ArrowBlock* C) {
  if (!ok_ || k_ >= n_ || (k_ > 0 && O_prev == nullptr)) return ok_ = false;
  if (C != nullptr && C->cols() != m_) return ok_ = false;
  const size_t k = k_;
  // Jacobi scaling, keyframe by keyframe: s_k = diag(D_k)^-1/2. The information of a
  // navigation-grade IMU's biases is ~1e20 next to ~1e2 for position; scaled, the pivots hold
  // only the conditioning of the correlations.
  for (int i = 0; i < 18; ++i) {
    const double d = D(i, i);
    s_[k][i] = d > 0.0 ? 1.0 / std::sqrt(d) : 1.0;
  }
  rhs_[k] = s_[k].cwiseProduct(b);
  if (k > 0) {
    const ChainBlock O_scaled = s_[k - 1].asDiagonal() * (*O_prev) * s_[k].asDiagonal();
    ChainBlock V;
    ChainVector u;
    if (!EliminatePrevious(&O_scaled, &V, &u)) return ok_ = false;
    S_ = s_[k].asDiagonal() * D * s_[k].asDiagonal();
    // S_ -= V^T V on the lower triangle (all the Cholesky factorisation reads), column dot
    // column: Eigen's rankUpdate takes its general triangular-product kernel at 18 x 18, which
    // packs its operands for more than the arithmetic costs.
    for (int c = 0; c < 18; ++c) {
      for (int r = c; r < 18; ++r) S_(r, c) -= V.col(r).dot(V.col(c));
    }
    c_ = rhs_[k];
    c_.noalias() -= V.transpose() * u;
    if (m_ > 0) {
      ArrowBlock next = C != nullptr ? ArrowBlock(s_[k].asDiagonal() * (*C))
                                     : ArrowBlock(ArrowBlock::Zero(18, m_));
      next.noalias() -= V.transpose().lazyProduct(cw_);
      cw_ = std::move(next);
    }
  } else {
    S_ = s_[k].asDiagonal() * D * s_[k].asDiagonal();
    c_ = rhs_[k];
    if (m_ > 0) {
      cw_ = C != nullptr ? ArrowBlock(s_[k].asDiagonal() * (*C))
                         : ArrowBlock(ArrowBlock::Zero(18, m_));
    }
  }
  ++k_;
  return true;
}

bool BlockTridiagonalSolver::Finish(const Eigen::MatrixXd& E,
                                    const Eigen::VectorXd& b_e,
                                    std::vector<ChainVector>* x,
                                    Eigen::VectorXd* x_e,
                                    double* scaled_step_norm2,
                                    double* scaled_rhs_dot) {
  if (m_ == 0) {
    x_e->resize(0);
    return Finish(x, scaled_step_norm2, scaled_rhs_dot);
  }
  if (!ok_ || k_ != n_ || n_ == 0 || E.rows() != m_ || E.cols() != m_ || b_e.size() != m_) {
    return ok_ = false;
  }
  x->resize(n_);
  ChainBlock V;
  ChainVector u;
  if (!EliminatePrevious(nullptr, &V, &u)) return ok_ = false;
  // The arrow's Jacobi scaling and damping, then its Schur complement and right-hand side:
  // E_s + mu I - s_e C~^T H_c^-1 C~ s_e and s_e b_e - s_e C~^T H_c^-1 b_c (C~ = S C, the rows
  // already scaled), the two products summed by the forward pass.
  Eigen::VectorXd s_e(m_);
  for (int i = 0; i < m_; ++i) s_e[i] = E(i, i) > 0.0 ? 1.0 / std::sqrt(E(i, i)) : 1.0;
  Eigen::MatrixXd schur = s_e.asDiagonal() * (E - CtW_) * s_e.asDiagonal();
  schur = 0.5 * (schur + schur.transpose()).eval();
  schur.diagonal().array() += mu_;
  const Eigen::VectorXd rhs_e = s_e.cwiseProduct(b_e - Cty_);
  const Eigen::LLT<Eigen::MatrixXd> llt(schur);
  if (llt.info() != Eigen::Success) return ok_ = false;
  const Eigen::VectorXd y_e = llt.solve(rhs_e);
  const Eigen::VectorXd w = s_e.cwiseProduct(y_e);  // C~'s columns are unscaled on the right
  double norm2 = y_e.squaredNorm();
  double dot = s_e.cwiseProduct(b_e).dot(y_e);
  // The chain's part solves H_c y = S b_c - C~ w. Its forward pass is linear in the right-hand
  // side, so z_k becomes z_k - L_k^-T (L^-1 C~)_k w (zw_); back substitution as without an arrow.
  BackSubstitute(w, x, &norm2, &dot);
  *x_e = w;
  if (scaled_step_norm2 != nullptr) *scaled_step_norm2 = norm2;
  if (scaled_rhs_dot != nullptr) *scaled_rhs_dot = dot;
  return true;
}

bool BlockTridiagonalSolver::Finish(std::vector<ChainVector>* x,
                                    double* scaled_step_norm2,
                                    double* scaled_rhs_dot) {
  if (!ok_ || k_ != n_ || m_ > 0) return false;  // an arrow needs its E and b_e
  x->resize(n_);
  if (n_ == 0) return true;
  ChainBlock V;
  ChainVector u;
  if (!EliminatePrevious(nullptr, &V, &u)) return ok_ = false;
  double norm2 = 0.0, dot = 0.0;
  BackSubstitute(Eigen::VectorXd(), x, &norm2, &dot);
  if (scaled_step_norm2 != nullptr) *scaled_step_norm2 = norm2;
  if (scaled_rhs_dot != nullptr) *scaled_rhs_dot = dot;
  return true;
}

void BlockTridiagonalSolver::BackSubstitute(const Eigen::VectorXd& w,
                                            std::vector<ChainVector>* x,
                                            double* norm2,
                                            double* dot) const {
  // y_n-1 = z_n-1, y_k = z_k - G_k y_k+1 (with an arrow, z_k less its share of w first). The
  // products take float gains to double before they multiply: the rounding is the gains' alone.
  ChainVector y_next;
  for (size_t k = n_; k-- > 0;) {
    ChainVector y = z_[k];
    if (m_ > 0) {
      const auto first = static_cast<Eigen::Index>(k * m_);
      if (single_) {
        y.noalias() -= zws_.middleCols(first, m_).cast<double>() * w;
      } else {
        y.noalias() -= zw_.middleCols(first, m_) * w;
      }
    }
    if (k + 1 < n_) {
      if (single_) {
        y.noalias() -= Gs_[k].cast<double>() * y_next;
      } else {
        y.noalias() -= G_[k] * y_next;
      }
    }
    *norm2 += y.squaredNorm();
    *dot += rhs_[k].dot(y);
    (*x)[k] = s_[k].cwiseProduct(y);
    y_next = y;
  }
}

bool SolveBlockTridiagonal(const std::vector<ChainBlock>& D,
                           const std::vector<ChainBlock>& O,
                           std::vector<ChainVector>* b,
                           double mu,
                           double* scaled_step_norm2,
                           double* scaled_rhs_dot) {
  const size_t n = D.size();
  if (O.size() + 1 != n && n > 0) return false;
  BlockTridiagonalSolver solver;
  solver.Start(n, mu);
  for (size_t k = 0; k < n; ++k) {
    if (!solver.Push(D[k], (*b)[k], k > 0 ? &O[k - 1] : nullptr)) return false;
  }
  return solver.Finish(b, scaled_step_norm2, scaled_rhs_dot);
}

}  // namespace skerry
