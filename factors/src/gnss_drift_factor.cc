#include "skerry/factors/gnss_drift_factor.h"

#include <algorithm>
#include <cmath>

namespace skerry {

namespace {
constexpr double kMinSigmaM = 1e-3;
}  // namespace

Eigen::Vector3d GnssDriftParams::StationarySigma() const {
  const double h = std::max(sigma_horizontal_m, kMinSigmaM);
  const double v = std::max(sigma_vertical_m, kMinSigmaM);
  return {h, h, v};
}

GnssDriftFactor::GnssDriftFactor(const GnssDriftParams& params, double dt_s) {
  const double dt = std::max(dt_s, 1e-6);
  phi_ = std::exp(-dt / params.tau_s);
  // 1 - phi^2 = -expm1(-2 dt / tau), accurate for dt << tau.
  const double one_minus_phi2 = -std::expm1(-2.0 * dt / params.tau_s);
  sqrt_info_ = (params.StationarySigma() * std::sqrt(one_minus_phi2)).cwiseInverse();
}

bool GnssDriftFactor::Evaluate(double const* const* parameters,
                               double* residuals,
                               double** jacobians) const {
  const Eigen::Map<const Eigen::Vector3d> b_i(parameters[0]), b_j(parameters[1]);
  Eigen::Map<Eigen::Vector3d> r(residuals);
  r = sqrt_info_.asDiagonal() * (b_j - phi_ * b_i);
  if (jacobians == nullptr) return true;
  using Jac = Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>;
  if (jacobians[0] != nullptr) {
    Jac J_r_bi(jacobians[0]);
    J_r_bi.setZero();
    J_r_bi.diagonal() = -phi_ * sqrt_info_;
  }
  if (jacobians[1] != nullptr) {
    Jac J_r_bj(jacobians[1]);
    J_r_bj.setZero();
    J_r_bj.diagonal() = sqrt_info_;
  }
  return true;
}

GnssDriftPriorFactor::GnssDriftPriorFactor(const GnssDriftParams& params)
    : sqrt_info_(params.StationarySigma().cwiseInverse()) {}

bool GnssDriftPriorFactor::Evaluate(double const* const* parameters,
                                    double* residuals,
                                    double** jacobians) const {
  const Eigen::Map<const Eigen::Vector3d> b(parameters[0]);
  Eigen::Map<Eigen::Vector3d> r(residuals);
  r = sqrt_info_.asDiagonal() * b;
  if (jacobians != nullptr && jacobians[0] != nullptr) {
    Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> J_r_b(jacobians[0]);
    J_r_b.setZero();
    J_r_b.diagonal() = sqrt_info_;
  }
  return true;
}

}  // namespace skerry
