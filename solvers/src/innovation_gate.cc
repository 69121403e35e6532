#include "skerry/solvers/innovation_gate.h"

#include <Eigen/Cholesky>
#include <cmath>
#include <stdexcept>

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
                     bool* evaluated) {
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
  const Eigen::MatrixXd S = J * P * J.transpose() + Eigen::MatrixXd::Identity(m, m);
  const Eigen::LLT<Eigen::MatrixXd> llt(S);
  if (llt.info() != Eigen::Success) return false;
  out->dim = m;
  out->d2 = lin.residual.dot(llt.solve(lin.residual));
  out->log_det_s = 2.0 * Eigen::MatrixXd(llt.matrixL()).diagonal().array().log().sum();
  return std::isfinite(out->d2);
}

}  // namespace skerry
