#pragma once
/// \file
/// Linear (Gaussian) prior left by marginalisation (Schur complement):
///   r = r0 + J * [ x_1 (-) x0_1 ; ... ; x_n (-) x0_n ]
/// where (-) is Log(q x0^-1) (full-angle world-frame rotation vector) for quaternion blocks and
/// x - x0 otherwise. J and r0 come from the Schur complement H* = J^T J, g* = J^T r0
/// (Sibley et al. 2010, "Sliding window filter..."; Leutenegger et al. IJRR 2015 sec. IV-E).
/// J is fixed at marginalisation: the prior's Jacobian is a first-estimate Jacobian by nature.

#include <ceres/cost_function.h>

#include <Eigen/Core>
#include <memory>
#include <vector>

namespace skerry {

class LinearPriorFactor : public ceres::CostFunction {
 public:
  /// `block_sizes`: ambient sizes (4 = quaternion); `x0`: linearisation points (ambient);
  /// `J`: rows x sum(tangent sizes); `r0`: rows.
  LinearPriorFactor(const std::vector<int>& block_sizes,
                    std::vector<Eigen::VectorXd> x0,
                    Eigen::MatrixXd J,
                    Eigen::VectorXd r0);

  bool Evaluate(double const* const* parameters,
                double* residuals,
                double** jacobians) const override;

  /// Builds the prior from the Schur complement: keeps eigen-directions of the Jacobi-scaled
  /// information diag(H)^-1/2 H diag(H)^-1/2 above `eps * max eigenvalue` (scaling makes the cut
  /// independent of units). Returns nullptr if nothing is left.
  static std::unique_ptr<LinearPriorFactor> FromInformation(const std::vector<int>& block_sizes,
                                                            std::vector<Eigen::VectorXd> x0,
                                                            const Eigen::MatrixXd& H,
                                                            const Eigen::VectorXd& g,
                                                            double eps = 1e-12);

  /// A Gaussian prior on the blocks at x0 with tangent-space covariance C:
  /// r = L^-1 (x (-) x0), C = L L^T (Cholesky), so that r^T r = (x (-) x0)^T C^-1 (x (-) x0).
  /// C is symmetrised first. Returns nullptr unless C is finite and positive definite.
  static std::unique_ptr<LinearPriorFactor> FromCovariance(const std::vector<int>& block_sizes,
                                                           std::vector<Eigen::VectorXd> x0,
                                                           const Eigen::MatrixXd& C);

  const Eigen::MatrixXd& J() const { return J_; }
  const Eigen::VectorXd& r0() const { return r0_; }
  const std::vector<Eigen::VectorXd>& x0() const { return x0_; }

 private:
  std::vector<int> block_sizes_;
  std::vector<Eigen::VectorXd> x0_;
  Eigen::MatrixXd J_;
  Eigen::VectorXd r0_;
};

}  // namespace skerry
