#include "skerry/factors/gnss_drift_step_factor.h"

#include <Eigen/Cholesky>
#include <cmath>
#include <stdexcept>

namespace skerry {

GnssDriftStepFactor::GnssDriftStepFactor(const GnssDriftParams& params,
                                         double dt_s,
                                         const Eigen::Vector3d& step_m,
                                         const Eigen::Matrix3d& step_cov)
    : step_m_(step_m) {
  // The transition's own noise, exactly as GnssDriftFactor has it.
  const GnssDriftFactor plain(params, dt_s);
  phi_ = plain.phi();
  const Eigen::Vector3d sigma_w = plain.sqrt_info().cwiseInverse();
  covariance_ = sigma_w.cwiseAbs2().asDiagonal();
  covariance_ += 0.5 * (step_cov + step_cov.transpose());
  if (!step_m.allFinite() || !covariance_.allFinite()) {
    throw std::invalid_argument("GnssDriftStepFactor: the step or its covariance is not finite");
  }
  // (Q_w + C_s)^-1 = L L^T; the whitening r = L^T e has E[r r^T] = L^T (Q_w + C_s) L = I.
  const Eigen::LLT<Eigen::Matrix3d> llt(covariance_);
  if (llt.info() != Eigen::Success) {
    throw std::invalid_argument("GnssDriftStepFactor: Q_w + C_s is not positive definite");
  }
  const Eigen::Matrix3d info = llt.solve(Eigen::Matrix3d::Identity());
  const Eigen::LLT<Eigen::Matrix3d> info_llt(0.5 * (info + info.transpose()));
  if (info_llt.info() != Eigen::Success) {
    throw std::invalid_argument("GnssDriftStepFactor: the information is not positive definite");
  }
  sqrt_info_ = info_llt.matrixU();
}

bool GnssDriftStepFactor::Evaluate(double const* const* parameters,
                                   double* residuals,
                                   double** jacobians) const {
  const Eigen::Map<const Eigen::Vector3d> b_i(parameters[0]), b_j(parameters[1]);
  Eigen::Map<Eigen::Vector3d> r(residuals);
  r = sqrt_info_ * (b_j - phi_ * b_i - step_m_);
  if (jacobians == nullptr) return true;
  using Jac = Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>;
  if (jacobians[0] != nullptr) {
    Jac J_r_bi(jacobians[0]);
    J_r_bi = -phi_ * sqrt_info_;
  }
  if (jacobians[1] != nullptr) {
    Jac J_r_bj(jacobians[1]);
    J_r_bj = sqrt_info_;
  }
  return true;
}

}  // namespace skerry
