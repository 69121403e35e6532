#include "skerry/solvers/innovation_gate.h"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "skerry/factors/factor_linearization.h"

namespace skerry {

bool BlockInnovation(const ceres::CostFunction& cost,
                     const std::vector<Slot>& slots,
                     const Keyframe& kf,
                     const GraphCovariance& P,
                     Innovation* out) {
  return BlockInnovation(cost, slots, {}, kf, P, out);
}

bool BlockInnovation(const ceres::CostFunction& cost,
                     const std::vector<Slot>& slots,
                     const std::vector<const double*>& fixed,
                     const Keyframe& kf,
                     const GraphCovariance& P,
                     Innovation* out,
                     bool* evaluated,
                     GateSpace space,
                     double residual_scale,
                     const std::vector<double>& fixed_variances) {
  if (slots.size() + fixed.size() != cost.parameter_block_sizes().size()) {
    throw std::logic_error("BlockInnovation: one slot or fixed value per parameter block");
  }
  if (!fixed_variances.empty() && fixed_variances.size() != fixed.size()) {
    throw std::logic_error("BlockInnovation: one variance per fixed block, or none");
  }
  // The uncertain fixed blocks: their index among the cost's blocks, and their variance.
  std::vector<std::pair<size_t, double>> uncertain;
  for (size_t k = 0; k < fixed_variances.size(); ++k) {
    if (!(fixed_variances[k] > 0) || !std::isfinite(fixed_variances[k])) continue;
    if (cost.parameter_block_sizes()[slots.size() + k] != 1) {
      throw std::logic_error("BlockInnovation: a variance only for a fixed block of size 1");
    }
    uncertain.emplace_back(slots.size() + k, fixed_variances[k]);
  }
  if (evaluated != nullptr) *evaluated = false;
  std::vector<const double*> values;
  for (Slot s : slots) values.push_back(kf.block(s));
  for (const double* v : fixed) values.push_back(v);
  LinearizedResidual lin;
  if (!LinearizeResidual(cost, nullptr, values, values, &lin) || !lin.residual.allFinite()) {
    return false;
  }
  if (evaluated != nullptr) *evaluated = true;
  const int m = static_cast<int>(lin.residual.size());
  const int extra = static_cast<int>(uncertain.size());
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(m, kGraphStateDim + extra);
  for (size_t k = 0; k < slots.size(); ++k) {
    J.middleCols(SlotTangentOffset(slots[k]), lin.jacobians[k].cols()) += lin.jacobians[k];
  }
  // P extended by the uncertain fixed blocks' variances (uncorrelated with the keyframe).
  Eigen::MatrixXd P_used = Eigen::MatrixXd::Zero(kGraphStateDim + extra, kGraphStateDim + extra);
  P_used.topLeftCorner(kGraphStateDim, kGraphStateDim) = P;
  for (int e = 0; e < extra; ++e) {
    J.col(kGraphStateDim + e) = lin.jacobians[uncertain[e].first].col(0);
    P_used(kGraphStateDim + e, kGraphStateDim + e) = uncertain[e].second;
  }
  Eigen::VectorXd r = lin.residual;
  if (residual_scale != 1.0) {
    r /= residual_scale;
    J /= residual_scale;
  }
  if (space == GateSpace::kState) {
    StateSpaceProjection proj = ProjectOnState(r, J);
    if (proj.y.size() == 0) return false;  // the block says nothing about the state
    J = proj.B.transpose();                // Cov y = I + B^T P B: y = "J" x + unit noise
    r = std::move(proj.y);
  }
  const int n = static_cast<int>(r.size());
  Eigen::MatrixXd S = J * P_used * J.transpose() + Eigen::MatrixXd::Identity(n, n);
  const Eigen::LLT<Eigen::MatrixXd> llt(S);
  if (llt.info() != Eigen::Success) return false;
  out->dim = n;
  out->d2 = r.dot(llt.solve(r));
  out->log_det_s = 2.0 * Eigen::MatrixXd(llt.matrixL()).diagonal().array().log().sum();
  out->r = std::move(r);
  out->S = std::move(S);  // the LLT keeps its own factor
  return std::isfinite(out->d2);
}

StateSpaceProjection ProjectOnState(const Eigen::VectorXd& r, const Eigen::MatrixXd& J) {
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(J.transpose() * J);
  const Eigen::VectorXd& l = eig.eigenvalues();  // ascending
  const Eigen::VectorXd g = eig.eigenvectors().transpose() * (J.transpose() * r);
  StateSpaceProjection out;
  const double floor = 1e-9 * std::max(0.0, l.size() > 0 ? l(l.size() - 1) : 0.0);
  int k = 0;
  for (int i = 0; i < l.size(); ++i) k += l(i) > floor && l(i) > 0.0;
  out.y.resize(k);
  out.B.resize(J.cols(), k);
  for (int i = static_cast<int>(l.size()) - k, j = 0; i < l.size(); ++i, ++j) {
    const double s = std::sqrt(l(i));
    out.y(j) = g(i) / s;
    out.B.col(j) = eig.eigenvectors().col(i) * s;
  }
  return out;
}

}  // namespace skerry
