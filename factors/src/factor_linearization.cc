#include "skerry/factors/factor_linearization.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace skerry {

Eigen::Matrix<double, 4, 3> QuaternionLeftPlusJacobian(const double* q_xyzw) {
  // Exp(theta) ~ [theta/2, 1]; (p * q).vec = p_w q_v + q_w p_v + p_v x q_v,
  // (p * q).w = p_w q_w - p_v . q_v  =>  d/dtheta = 1/2 [q_w I - [q_v]x ; -q_v^T].
  const Eigen::Vector3d qv(q_xyzw[0], q_xyzw[1], q_xyzw[2]);
  const double qw = q_xyzw[3];
  Eigen::Matrix<double, 4, 3> J;
  J.topRows<3>() =
      0.5 * (qw * Eigen::Matrix3d::Identity() -
             (Eigen::Matrix3d() << 0, -qv.z(), qv.y(), qv.z(), 0, -qv.x(), -qv.y(), qv.x(), 0)
                 .finished());
  J.row(3) = -0.5 * qv.transpose();
  return J;
}

bool LinearizeResidual(const ceres::CostFunction& cost,
                       const ceres::LossFunction* loss,
                       const std::vector<const double*>& residual_values,
                       const std::vector<const double*>& jacobian_values,
                       LinearizedResidual* out) {
  const std::vector<int32_t>& sizes = cost.parameter_block_sizes();
  const int m = cost.num_residuals();
  const size_t n = sizes.size();
  // Scratch kept per thread: a batch linearises every factor of a run per iteration, and the
  // allocations were a third of it. `out` is reused the same way by callers that keep it. The
  // ambient Jacobians share one buffer that only grows: factors of different shapes follow each
  // other (an IMU factor, its bias walk, a fix), and a matrix per block was reallocated at
  // nearly every call.
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  thread_local std::vector<double> ambient_storage;
  thread_local std::vector<double*> jac_ptrs;
  thread_local std::vector<double> r_storage;
  size_t total = 0;
  for (size_t k = 0; k < n; ++k) total += static_cast<size_t>(m) * static_cast<size_t>(sizes[k]);
  if (ambient_storage.size() < total) ambient_storage.resize(total);
  jac_ptrs.resize(n);
  for (size_t k = 0, offset = 0; k < n; ++k) {
    jac_ptrs[k] = ambient_storage.data() + offset;
    offset += static_cast<size_t>(m) * static_cast<size_t>(sizes[k]);
  }
  const auto ambient = [&](size_t k) {
    return Eigen::Map<const RowMajor>(jac_ptrs[k], m, sizes[k]);
  };
  if (r_storage.size() < static_cast<size_t>(m)) r_storage.resize(static_cast<size_t>(m));
  Eigen::Map<Eigen::VectorXd> r(r_storage.data(), m);
  if (!cost.Evaluate(jacobian_values.data(), r.data(), jac_ptrs.data())) return false;
  if (residual_values != jacobian_values) {
    if (!cost.Evaluate(residual_values.data(), r.data(), nullptr)) return false;
  }
  double scale = 1.0;
  if (loss != nullptr) {
    double rho[3];
    loss->Evaluate(r.squaredNorm(), rho);
    scale = std::sqrt(std::max(rho[1], 0.0));
  }
  out->residual = scale * r;
  out->jacobians.resize(n);
  for (size_t k = 0; k < n; ++k) {
    if (sizes[k] == 4) {
      out->jacobians[k].resize(m, 3);
      out->jacobians[k].noalias() =
          scale * ambient(k).lazyProduct(QuaternionLeftPlusJacobian(jacobian_values[k]));
    } else {
      out->jacobians[k] = scale * ambient(k);
    }
  }
  return true;
}

}  // namespace skerry
