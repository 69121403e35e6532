#pragma once
/// \file
/// Householder triangularisation of a stack of whitened Jacobian rows that are mostly zeros.
///
/// The square-root eliminations of nav_graph.cc (marginalising the oldest keyframe, the window's
/// newest covariance, the batch's square-root covariances) each reduce a small stack of rows:
/// the triangular rows carried from the previous elimination, a factor's own rows that are
/// dense on one or two keyframes and zero on the rest. A dense QR (Eigen::HouseholderQR) reflects
/// every row below the diagonal in every column, and for 30-50 columns its blocked variant
/// spends as much again building the block reflector's triangular factor.

#include <Eigen/Core>

namespace skerry {

/// Reduces `*M` (m x n) in place to [R; 0] with R upper triangular and R^T R = M^T M (the R of
/// a QR factorisation, Q not kept; rows of R may differ in sign from another QR's). Columns are
/// reflected one by one (Golub & Van Loan, "Matrix Computations", 4th ed., Alg. 5.2.1), each
/// reflection spanning only the rows from the diagonal to the last one that is nonzero in its
/// column: the rows below are zero in it and in every earlier column (zeroed by that column's
/// reflection or never nonzero), and a reflection would leave them unchanged. Rows are first
/// ordered by their leading nonzero column, which keeps those spans short; the result does not
/// depend on it beyond the signs. Below the diagonal `*M` holds exact zeros on return.
void HouseholderTriangularize(Eigen::MatrixXd* M);

}  // namespace skerry
