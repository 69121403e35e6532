#include "skerry/factors/pose_fix_factor.h"

#include <cmath>
#include <stdexcept>

namespace skerry {

PoseFixFactor::PoseFixFactor(const PoseFix& fix, const Eigen::Matrix3d& R_n_w)
    : components_(fix.MeasuredComponents()), R_n_w_(R_n_w) {
  z_ << fix.p_w, fix.heading_deg * M_PI / 180.0;
  const int n = static_cast<int>(components_.size());
  Eigen::MatrixXd C(n, n);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) C(i, j) = fix.covariance(components_[i], components_[j]);
  }
  if (!C.allFinite() || !z_.allFinite()) {
    throw std::invalid_argument("pose fix: a value or its covariance is not finite");
  }
  const Eigen::LLT<Eigen::MatrixXd> llt(0.5 * (C + C.transpose()));
  if (llt.info() != Eigen::Success ||
      (C - C.transpose()).cwiseAbs().maxCoeff() > 1e-9 * std::max(1.0, C.cwiseAbs().maxCoeff())) {
    throw std::invalid_argument(
        "pose fix: the covariance of the measured components is not symmetric positive "
        "definite");
  }
  // r = L^-1 e with L L^T = C: E[r r^T] = I.
  const Eigen::MatrixXd L_inv = Eigen::MatrixXd(llt.matrixL())
                                    .triangularView<Eigen::Lower>()
                                    .solve(Eigen::MatrixXd::Identity(n, n));
  sqrt_info_.setZero();
  sqrt_info_.topLeftCorner(n, n) = L_inv;
}

std::unique_ptr<ceres::CostFunction> PoseFixFactor::Create(const PoseFix& fix,
                                                           const Eigen::Matrix3d& R_n_w) {
  auto* functor = new PoseFixFactor(fix, R_n_w);
  const int m = functor->num_residuals();
  return std::make_unique<ceres::AutoDiffCostFunction<PoseFixFactor, ceres::DYNAMIC, 4, 3, 4, 3>>(
      functor, m);
}

}  // namespace skerry
