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
                     double residual_scale) {
  if (slots.size() + fixed.size() != cost.parameter_block_sizes().size()) {
    throw std::logic_error("BlockInnovation: one slot or fixed value per parameter block");
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
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(m, kGraphStateDim);
  for (size_t k = 0; k < slots.size(); ++k) {
    J.middleCols(SlotTangentOffset(slots[k]), lin.jacobians[k].cols()) += lin.jacobians[k];
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
  Eigen::MatrixXd S = J * P * J.transpose() + Eigen::MatrixXd::Identity(n, n);
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
