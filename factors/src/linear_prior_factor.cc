#include "skerry/factors/linear_prior_factor.h"

#include <ceres/jet.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <stdexcept>
#include <string>

#include "skerry/core/so3.h"
#include "skerry/factors/factor_linearization.h"

namespace skerry {
namespace {

// theta = Log(q * q0^-1) and its 3x4 Jacobian w.r.t. the ambient q (through Ceres Jets, exact).
void QuaternionMinus(const double* q,
                     const Eigen::VectorXd& q0,
                     Eigen::Vector3d* theta,
                     Eigen::Matrix<double, 3, 4>* J) {
  using Jet4 = ceres::Jet<double, 4>;
  Eigen::Quaternion<Jet4> qj;
  for (int k = 0; k < 4; ++k) qj.coeffs()[k] = Jet4(q[k], k);
  const Eigen::Quaternion<Jet4> q0_inv(Jet4(q0[3]), Jet4(-q0[0]), Jet4(-q0[1]), Jet4(-q0[2]));
  const Eigen::Matrix<Jet4, 3, 1> t = LogQ<Jet4>(qj * q0_inv);
  for (int r = 0; r < 3; ++r) {
    (*theta)[r] = t[r].a;
    if (J != nullptr) J->row(r) = t[r].v.transpose();
  }
}

}  // namespace

LinearPriorFactor::LinearPriorFactor(const std::vector<int>& block_sizes,
                                     std::vector<Eigen::VectorXd> x0,
                                     Eigen::MatrixXd J,
                                     Eigen::VectorXd r0)
    : block_sizes_(block_sizes), x0_(std::move(x0)), J_(std::move(J)), r0_(std::move(r0)) {
  for (int size : block_sizes_) mutable_parameter_block_sizes()->push_back(size);
  set_num_residuals(static_cast<int>(r0_.size()));
}

bool LinearPriorFactor::Evaluate(double const* const* parameters,
                                 double* residuals,
                                 double** jacobians) const {
  const int m = static_cast<int>(r0_.size());
  int n_tangent = 0;
  for (int size : block_sizes_) n_tangent += TangentSize(size);
  Eigen::VectorXd delta(n_tangent);
  std::vector<Eigen::Matrix<double, 3, 4>> quat_jacobians(block_sizes_.size());
  int col = 0;
  for (size_t k = 0; k < block_sizes_.size(); ++k) {
    const int size = block_sizes_[k];
    if (size == 4) {
      Eigen::Vector3d theta;
      QuaternionMinus(parameters[k], x0_[k], &theta,
                      jacobians != nullptr ? &quat_jacobians[k] : nullptr);
      delta.segment<3>(col) = theta;
    } else {
      delta.segment(col, size) = Eigen::Map<const Eigen::VectorXd>(parameters[k], size) - x0_[k];
    }
    col += TangentSize(size);
  }
  Eigen::Map<Eigen::VectorXd>(residuals, m) = r0_ + J_ * delta;
  if (jacobians == nullptr) return true;
  col = 0;
  for (size_t k = 0; k < block_sizes_.size(); ++k) {
    const int size = block_sizes_[k];
    const int t = TangentSize(size);
    if (jacobians[k] != nullptr) {
      Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> Jk(
          jacobians[k], m, size);
      if (size == 4) {
        Jk = J_.middleCols(col, 3) * quat_jacobians[k];
      } else {
        Jk = J_.middleCols(col, size);
      }
    }
    col += t;
  }
  return true;
}

std::unique_ptr<LinearPriorFactor> LinearPriorFactor::FromInformation(
    const std::vector<int>& block_sizes,
    std::vector<Eigen::VectorXd> x0,
    const Eigen::MatrixXd& H,
    const Eigen::VectorXd& g,
    double eps) {
  // Jacobi scaling first, H = S Hs S with S = diag(sqrt(H_ii)): the marginal information spans
  // many decades (a tactical gyro's bias random walk gives 1e17, a GNSS-only direction 1e2), and
  // an eigen-decomposition is only accurate relative to the largest eigenvalue, so unscaled the
  // weak directions would be lost to round-off (or to the eps cut). Hs has a unit diagonal.
  // Hs = V diag(l) V^T  =>  J = diag(sqrt(l)) V^T S,  r0 = diag(1/sqrt(l)) V^T S^-1 g, so that
  // J^T J = H and J^T r0 = g on the kept subspace.
  const Eigen::MatrixXd H_sym = 0.5 * (H + H.transpose());
  Eigen::VectorXd scale = H_sym.diagonal();
  for (int k = 0; k < scale.size(); ++k) scale[k] = scale[k] > 0.0 ? std::sqrt(scale[k]) : 1.0;
  const Eigen::VectorXd inv_scale = scale.cwiseInverse();
  const Eigen::MatrixXd H_scaled = inv_scale.asDiagonal() * H_sym * inv_scale.asDiagonal();
  const Eigen::VectorXd g_scaled = inv_scale.asDiagonal() * g;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(H_scaled);
  const Eigen::VectorXd& l = eig.eigenvalues();
  const double l_max = l.maxCoeff();
  if (!(l_max > 0.0)) return nullptr;
  std::vector<int> kept;
  for (int k = 0; k < l.size(); ++k) {
    if (l[k] > eps * l_max) kept.push_back(k);
  }
  if (kept.empty()) return nullptr;
  Eigen::MatrixXd J(kept.size(), H.cols());
  Eigen::VectorXd r0(kept.size());
  for (size_t row = 0; row < kept.size(); ++row) {
    const int k = kept[row];
    const double s = std::sqrt(l[k]);
    J.row(row) = s * eig.eigenvectors().col(k).transpose() * scale.asDiagonal();
    r0[row] = eig.eigenvectors().col(k).dot(g_scaled) / s;
  }
  return std::make_unique<LinearPriorFactor>(block_sizes, std::move(x0), std::move(J),
                                             std::move(r0));
}

std::unique_ptr<LinearPriorFactor> LinearPriorFactor::FromCovariance(
    const std::vector<int>& block_sizes,
    std::vector<Eigen::VectorXd> x0,
    const Eigen::MatrixXd& C) {
  int n_tangent = 0;
  for (int size : block_sizes) n_tangent += TangentSize(size);
  if (C.rows() != n_tangent || C.cols() != n_tangent) {
    throw std::invalid_argument("LinearPriorFactor::FromCovariance: the covariance is not " +
                                std::to_string(n_tangent) + " x " + std::to_string(n_tangent));
  }
  if (!C.allFinite()) return nullptr;
  const Eigen::LLT<Eigen::MatrixXd> llt(0.5 * (C + C.transpose()));
  if (llt.info() != Eigen::Success) return nullptr;
  const Eigen::Index n = C.rows();
  Eigen::MatrixXd sqrt_info = llt.matrixL().solve(Eigen::MatrixXd::Identity(n, n));
  return std::make_unique<LinearPriorFactor>(block_sizes, std::move(x0), std::move(sqrt_info),
                                             Eigen::VectorXd::Zero(n));
}

}  // namespace skerry
