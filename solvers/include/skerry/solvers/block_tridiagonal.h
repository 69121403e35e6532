#pragma once
/// \file
/// The damped normal equations of a keyframe chain, solved in O(n) by block elimination.
///
/// A graph whose factors each touch one keyframe or two consecutive ones has block-tridiagonal
/// normal equations H = tridiag(O_{k-1}^T, D_k, O_k) with 18x18 blocks (nav_graph.h's tangent of
/// a keyframe). A general sparse Cholesky (Ceres' SPARSE_NORMAL_CHOLESKY through CHOLMOD) has to
/// discover that structure, assemble J^T J in compressed rows and factor it with a simplicial
/// LDL^T; the block Thomas recursion below does the same elimination in dense 18x18 blocks with
/// no symbolic phase and no fill beyond the blocks it is given (Golub & Van Loan, "Matrix
/// Computations", 4th ed., sec. 4.5.1, block tridiagonal LU; for a positive definite H the
/// pivots S_k are the Schur complements and stay positive definite).

#include <Eigen/Core>
#include <vector>

namespace skerry {

using ChainBlock = Eigen::Matrix<double, 18, 18>;
using ChainVector = Eigen::Matrix<double, 18, 1>;

/// Solves (H_s + mu I) y = S b, x = S y, where H_s = S H S is H Jacobi-scaled
/// (S = diag(H)^-1/2, 1 where a diagonal entry is not positive): the Levenberg-Marquardt step
/// of Ceres' LEVENBERG_MARQUARDT strategy, whose damping acts on the scaled problem (unit
/// diagonal) as mu = 1 / trust-region radius.
/// `D`: the n diagonal blocks, overwritten by the Cholesky factors of the pivots. `O`: the n-1
/// upper off-diagonal blocks (O[k] couples keyframe k to k+1), unchanged. `b`: the right-hand
/// side, overwritten by x. `scaled_step_norm2` (may be null): |y|^2, and `scaled_rhs_dot` (may
/// be null): (S b)^T y = b^T x; with b = -g the model decrease of the step is
/// (b^T x + mu |y|^2) / 2.
/// Returns false when a pivot is not positive definite (then D and b hold garbage).
bool SolveBlockTridiagonal(std::vector<ChainBlock>* D,
                           const std::vector<ChainBlock>& O,
                           std::vector<ChainVector>* b,
                           double mu,
                           double* scaled_step_norm2 = nullptr,
                           double* scaled_rhs_dot = nullptr);

}  // namespace skerry
