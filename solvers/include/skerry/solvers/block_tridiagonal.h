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
/// A keyframe's coupling to the arrow (18 x m).
using ArrowBlock = Eigen::Matrix<double, 18, Eigen::Dynamic>;

/// How BlockTridiagonalSolver keeps the gains of its back substitution (G_k, and with an arrow
/// L_k^-T (L^-1 C)_k): the memory of a long batch's solve (class comment).
enum class GainPrecision { kDouble, kSingle };

/// Solves (H_s + mu I) y = S b, x = S y, where H_s = S H S is H Jacobi-scaled
/// (S = diag(H)^-1/2, 1 where a diagonal entry is not positive): the Levenberg-Marquardt step
/// of Ceres' LEVENBERG_MARQUARDT strategy, whose damping acts on the scaled problem (unit
/// diagonal) as mu = 1 / trust-region radius.
///
/// The blocks are handed over one keyframe at a time, oldest first, so that a caller can
/// assemble H keyframe by keyframe and never hold it whole: forward elimination
/// S_0 = D_0, S_k+1 = D_k+1 - O_k^T S_k^-1 O_k, c_k+1 = b_k+1 - O_k^T S_k^-1 c_k (scaled, damped),
/// keeping per keyframe only the gain G_k = S_k^-1 O_k and z_k = S_k^-1 c_k; back substitution
/// y_k = z_k - G_k y_k+1 (the Rauch-Tung-Striebel form of the same recursion). That is one 18x18
/// block per keyframe instead of the two (D and O) a whole-chain solve needs.
///
/// With an arrow (Start's `arrow_dim` m > 0: blocks every keyframe may touch, such as a sensor's
/// calibrated extrinsic or its estimated parameter), H = [H_c C; C^T E] with C one 18 x m block
/// C_k per keyframe. The arrow is eliminated last (the Schur complement on it, as for the
/// landmarks of a bundle adjustment the other way round: Triggs et al. 2000, "Bundle adjustment:
/// a modern synthesis", sec. 6.1): (E - C^T H_c^-1 C) y_e = b_e - C^T H_c^-1 b_c (dense, m x m),
/// then H_c y_c = b_c - C y_e. The forward pass carries the m columns of L^-1 C beside L^-1 b_c
/// (H_c = L L^T, L block bidiagonal) and sums both products as (L^-1 C)^T (L^-1 C) and
/// (L^-1 C)^T (L^-1 b_c) on the way; it keeps L_k^-T (L^-1 C)_k per keyframe, so that the back
/// substitution takes y_c's right-hand side as it is, with no second pass over W = H_c^-1 C.
/// All of it on the Jacobi-scaled problem, the arrow scaled by diag(E)^-1/2 and damped by mu
/// like every other column. Memory per keyframe grows by 18 x m numbers.
///
/// The stored gains are all a long chain's solve holds per keyframe beyond a few vectors:
/// 18 x (18 + m) numbers, 3.9 kB in double with the gyro's calibration as the arrow (m = 9), 140
/// MB for the 36,000 keyframes of an hour. GainPrecision::kSingle keeps them in float, half of
/// that. Everything else stays in double: the pivots, their factorisations, the forward pass and
/// the right-hand sides z_k; only the back substitution's products G_k y_k+1 (and the arrow's)
/// see the rounded gains, each entry off by at most 2^-24 of itself. The step is then an
/// inexact Newton step of Levenberg-Marquardt, whose convergence needs only a relative error of
/// the step well below one (Dembo, Eisenstat & Steihaug 1982, "Inexact Newton methods", thm.
/// 2.3). Ceres' `use_mixed_precision_solves` factors the normal equations in float for the
/// same saving and refines the solution iteratively, which needs H again: a chain assembled and
/// eliminated keyframe by keyframe does not keep it. Measured: a relative step error of about 1e-6
/// on random chains (test_chain_solver); the hour at sea takes the same iterations to estimates
/// within 2e-7 m of the double solve's.
class BlockTridiagonalSolver {
 public:
  /// Starts a solve of n keyframes with damping mu and an arrow of `arrow_dim` columns (0: none;
  /// storage is kept from solve to solve), the gains kept in `gains` precision.
  void Start(size_t n, double mu, int arrow_dim = 0, GainPrecision gains = GainPrecision::kDouble);
  /// Keyframe k's diagonal block D_k, right-hand side b_k and, for k > 0, O_{k-1} (coupling
  /// k-1 to k), for k = 0, 1, ..., n-1 in turn; with an arrow also C_k (18 x arrow_dim; null:
  /// zero). False when a pivot is not positive definite (the solve is then over: Finish returns
  /// false).
  bool Push(const ChainBlock& D,
            const ChainVector& b,
            const ChainBlock* O_prev,
            const ArrowBlock* C = nullptr);
  /// After n pushes: x (resized to n). `scaled_step_norm2` (may be null): |y|^2, and
  /// `scaled_rhs_dot` (may be null): (S b)^T y = b^T x; with b = -g the model decrease of the
  /// step is (b^T x + mu |y|^2) / 2. False when a pivot was not positive definite, or when the
  /// solve was started with an arrow (the next overload takes it).
  bool Finish(std::vector<ChainVector>* x,
              double* scaled_step_norm2 = nullptr,
              double* scaled_rhs_dot = nullptr);
  /// The same with the arrow: its block E (m x m), right-hand side b_e and step x_e; the norms
  /// and the dot product then include the arrow's share. False also when the arrow's Schur
  /// complement is not positive definite.
  bool Finish(const Eigen::MatrixXd& E,
              const Eigen::VectorXd& b_e,
              std::vector<ChainVector>* x,
              Eigen::VectorXd* x_e,
              double* scaled_step_norm2 = nullptr,
              double* scaled_rhs_dot = nullptr);

  /// Frees the per-keyframe storage Start keeps from solve to solve (the gains, the forward
  /// pass's vectors, the arrow's blocks); the next Start allocates it again.
  void Release() {
    std::vector<ChainBlock>().swap(G_);
    std::vector<Eigen::Matrix<float, 18, 18>>().swap(Gs_);
    std::vector<ChainVector>().swap(z_);
    std::vector<ChainVector>().swap(s_);
    std::vector<ChainVector>().swap(rhs_);
    zw_.resize(18, 0);
    zws_.resize(18, 0);
  }
  /// The bytes the stored gains take (all of them, whether the solve has reached them or not).
  size_t gain_bytes() const {
    return G_.size() * sizeof(ChainBlock) + Gs_.size() * sizeof(Gs_[0]) +
           sizeof(double) * static_cast<size_t>(zw_.size()) +
           sizeof(float) * static_cast<size_t>(zws_.size());
  }

 private:
  // Eliminates keyframe k_ - 1 (its pivot S_ and right-hand side c_): z_, and with O~ (O_{k-1}
  // scaled; null for the last keyframe) G_, V = L^-1 O~ and u = L^-1 c for the next pivot.
  bool EliminatePrevious(const ChainBlock* O_scaled, ChainBlock* V, ChainVector* u);
  // Back substitution from z_ (the arrow's step w: empty without one); the norms as Finish's.
  void BackSubstitute(const Eigen::VectorXd& w,
                      std::vector<ChainVector>* x,
                      double* norm2,
                      double* dot) const;

  double mu_ = 0.0;
  size_t n_ = 0;
  size_t k_ = 0;  // keyframes pushed
  bool ok_ = true;
  ChainBlock S_;         // pivot of keyframe k_ - 1, scaled, not yet damped or eliminated
  ChainVector c_;        // its scaled right-hand side
  bool single_ = false;  // the gains in float (Gs_, zws_) instead of double (G_, zw_)
  std::vector<ChainBlock> G_;
  std::vector<Eigen::Matrix<float, 18, 18>> Gs_;
  std::vector<ChainVector> z_, s_, rhs_;  // z_k, the scaling s_k, the scaled rhs s_k b_k
  // The arrow: its width, the current pivot's right-hand sides for it (c_ for C), z_k's
  // counterpart L_k^-T (L^-1 C)_k per keyframe (18 x m each, side by side in one matrix), and
  // the sums C^T H_c^-1 C and C^T H_c^-1 b_c of the forward pass (scaled).
  int m_ = 0;
  ArrowBlock cw_;
  ArrowBlock zw_;
  Eigen::Matrix<float, 18, Eigen::Dynamic> zws_;
  Eigen::MatrixXd CtW_;
  Eigen::VectorXd Cty_;
};

/// The same solve over whole vectors: `D` the n diagonal blocks, `O` the n-1 upper
/// off-diagonal blocks (O[k] couples keyframe k to k+1), `b` the right-hand side, overwritten
/// by x. Returns false when a pivot is not positive definite (then b holds garbage).
bool SolveBlockTridiagonal(const std::vector<ChainBlock>& D,
                           const std::vector<ChainBlock>& O,
                           std::vector<ChainVector>* b,
                           double mu,
                           double* scaled_step_norm2 = nullptr,
                           double* scaled_rhs_dot = nullptr);

}  // namespace skerry
