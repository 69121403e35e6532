#pragma once
/// \file
/// Forward and back substitution with a small dense Cholesky factor on a matrix of right-hand
/// sides held transposed.
///
/// The chain solver's elimination (block_tridiagonal.cc) solves with an 18x18 Cholesky factor L
/// for 18 and for the arrow's m right-hand sides at every keyframe. Eigen's
/// TriangularView::solveInPlace takes its blocked triangular kernel for any matrix of right-hand
/// sides, made for large sizes: at 18 it spent most of the chain solver's elimination. Held
/// transposed (Xt = X^T), row j of X is column j of Xt, and every step of the substitution (Golub &
/// Van Loan, "Matrix Computations", 4th ed., Alg. 3.1.3 and its transpose) is an axpy on a whole
/// contiguous column. (The information-form covariances keep their pivoting LDLT for S^-1: LLT with
/// these substitutions was 3x less accurate on a navigation-grade chain.)

#include <Eigen/Core>

namespace skerry {

/// Xt <- (L^-1 X)^T for Xt = X^T: L lower triangular (its strict upper triangle is not read, so
/// Eigen::LLT::matrixLLT() can be passed as it is), Xt column-major with L.rows() columns. With
/// a number of right-hand sides known only at run time (the arrow's) the axpys run on the
/// columns' raw storage: Eigen's expression for a column of dynamic length cost three times the
/// arithmetic at 9 rows. A fixed number Eigen unrolls.
template <typename Factor, typename Transposed>
void SolveLowerOnTransposed(const Eigen::MatrixBase<Factor>& L, Eigen::MatrixBase<Transposed>* Xt) {
  static_assert(!Transposed::IsRowMajor && Transposed::InnerStrideAtCompileTime == 1,
                "the right-hand sides' columns must be contiguous");
  const Eigen::Index n = L.rows();
  if constexpr (Transposed::RowsAtCompileTime != Eigen::Dynamic) {  // Eigen unrolls these
    for (Eigen::Index j = 0; j < n; ++j) {
      for (Eigen::Index i = 0; i < j; ++i) Xt->col(j) -= L(j, i) * Xt->col(i);
      Xt->col(j) /= L(j, j);
    }
    return;
  }
  const Eigen::Index m = Xt->rows();
  const Eigen::Index stride = Xt->outerStride();
  double* x = Xt->derived().data();
  for (Eigen::Index j = 0; j < n; ++j) {
    double* xj = x + j * stride;
    for (Eigen::Index i = 0; i < j; ++i) {
      const double l = L(j, i);
      const double* xi = x + i * stride;
      for (Eigen::Index r = 0; r < m; ++r) xj[r] -= l * xi[r];
    }
    const double d = L(j, j);
    for (Eigen::Index r = 0; r < m; ++r) xj[r] /= d;
  }
}

/// Xt <- (L^-T X)^T for Xt = X^T, L and Xt as above.
template <typename Factor, typename Transposed>
void SolveUpperOnTransposed(const Eigen::MatrixBase<Factor>& L, Eigen::MatrixBase<Transposed>* Xt) {
  static_assert(!Transposed::IsRowMajor && Transposed::InnerStrideAtCompileTime == 1,
                "the right-hand sides' columns must be contiguous");
  const Eigen::Index n = L.rows();
  if constexpr (Transposed::RowsAtCompileTime != Eigen::Dynamic) {
    for (Eigen::Index i = n; i-- > 0;) {
      for (Eigen::Index j = i + 1; j < n; ++j) Xt->col(i) -= L(j, i) * Xt->col(j);
      Xt->col(i) /= L(i, i);
    }
    return;
  }
  const Eigen::Index m = Xt->rows();
  const Eigen::Index stride = Xt->outerStride();
  double* x = Xt->derived().data();
  for (Eigen::Index i = n; i-- > 0;) {
    double* xi = x + i * stride;
    for (Eigen::Index j = i + 1; j < n; ++j) {
      const double l = L(j, i);
      const double* xj = x + j * stride;
      for (Eigen::Index r = 0; r < m; ++r) xi[r] -= l * xj[r];
    }
    const double d = L(i, i);
    for (Eigen::Index r = 0; r < m; ++r) xi[r] /= d;
  }
}

}  // namespace skerry
