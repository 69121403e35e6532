#include "skerry/lidar_aerial/planar_minimum.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <vector>

namespace skerry::lidar_aerial {

NavState PlanarMinimum(const ceres::CostFunction& cost, const NavState& at, int max_iterations) {
  const int n = cost.num_residuals();
  std::vector<double> r(static_cast<size_t>(n)), jq(static_cast<size_t>(n) * 4),
      jp(static_cast<size_t>(n) * 3);
  // The cost's squared norm at s (with its Jacobians in jq, jp when asked); -1: not evaluable.
  const auto evaluate = [&](const NavState& s, bool jacobians) {
    const double* values[] = {s.q_w_b.coeffs().data(), s.p_w_b.data(), s.v_w.data()};
    double* js[] = {jq.data(), jp.data(), nullptr};
    if (!cost.Evaluate(values, r.data(), jacobians ? js : nullptr)) return -1.0;
    const double f = Eigen::Map<const Eigen::VectorXd>(r.data(), n).squaredNorm();
    return std::isfinite(f) ? f : -1.0;
  };
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  NavState x = at;
  double f = evaluate(x, true);
  double lambda = 1e-3;
  for (int it = 0; it < max_iterations && f > 0.0; ++it) {
    const Eigen::Map<const RowMajor> Jq(jq.data(), n, 4), Jp(jp.data(), n, 3);
    Eigen::Matrix<double, Eigen::Dynamic, 3> J(n, 3);
    J.col(0) = Jq * (Eigen::Quaterniond(0.0, 0.0, 0.0, 0.5) * x.q_w_b).coeffs();
    J.rightCols<2>() = Jp.leftCols<2>();
    const Eigen::Matrix3d H = J.transpose() * J;
    const Eigen::Vector3d g = J.transpose() * Eigen::Map<const Eigen::VectorXd>(r.data(), n);
    bool stepped = false;
    for (int tries = 0; tries < 8 && !stepped; ++tries) {
      Eigen::Matrix3d A = H;
      A.diagonal() += lambda * H.diagonal().cwiseMax(1e-12);
      const Eigen::Vector3d d = -A.ldlt().solve(g);
      NavState y = x;
      y.q_w_b = Eigen::Quaterniond(Eigen::AngleAxisd(d(0), Eigen::Vector3d::UnitZ())) * x.q_w_b;
      y.p_w_b.head<2>() += d.tail<2>();
      const double fy = d.allFinite() ? evaluate(y, false) : -1.0;
      if (fy >= 0.0 && fy < f) {
        const bool converged = f - fy < 1e-8 * f;
        x = y;
        f = evaluate(x, true);
        lambda = std::max(1e-9, lambda / 10.0);
        stepped = !converged;
        if (converged) return x;
      } else {
        lambda *= 10.0;
      }
    }
    if (!stepped) break;
  }
  return x;
}

}  // namespace skerry::lidar_aerial
