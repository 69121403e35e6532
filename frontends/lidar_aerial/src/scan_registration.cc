#include "skerry/lidar_aerial/scan_registration.h"

#include <Eigen/Eigenvalues>
#include <cmath>

namespace skerry::lidar_aerial {

Registration RegisterScan(const AerialMap& map,
                          std::shared_ptr<const EdgeDistanceField> field,
                          const std::vector<Eigen::Vector3d>& points_l,
                          const PlanarPose& prior,
                          const RegistrationOptions& o) {
  Registration out;
  if (points_l.empty()) return out;
  PlanarPose start = prior;
  if (o.coarse_first) {
    out.coarse = CoarseSearch(map, points_l, prior, o.coarse);
    if (!out.coarse.valid) return out;
    start = out.coarse.pose;
  }
  std::vector<Eigen::Vector2d> xy(points_l.size());
  for (size_t i = 0; i < points_l.size(); ++i) xy[i] = points_l[i].head<2>();

  // Parameters (yaw, x, y).
  double x[3] = {start.yaw, start.t.x(), start.t.y()};
  ceres::Problem::Options po;
  po.cost_function_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(po);
  ceres::CostFunction* cost = PlanarAlignmentCost::Create(field, xy, o.fine).release();
  problem.AddResidualBlock(cost, nullptr, x);
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = o.max_iterations;
  so.num_threads = 1;
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  out.iterations = static_cast<int>(summary.iterations.size()) - 1;
  if (!summary.IsSolutionUsable()) return out;
  out.pose.yaw = WrapAngle(x[0]);
  out.pose.t = Eigen::Vector2d(x[1], x[2]);

  // Information J^T J at the solution, reordered to (x, y, yaw).
  const int n = cost->num_residuals();
  Eigen::VectorXd r(n);
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> J(n, 3);
  const double* params[] = {x};
  double* jac[] = {J.data()};
  if (!cost->Evaluate(params, r.data(), jac)) return out;
  Eigen::Matrix<double, Eigen::Dynamic, 3> Jr(n, 3);
  Jr << J.col(1), J.col(2), J.col(0);
  const Eigen::Matrix3d info = Jr.transpose() * Jr;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> pos(info.topLeftCorner<2, 2>());
  const double lmax = pos.eigenvalues()(1);
  out.constraint_ratio = lmax > 0.0 ? std::max(0.0, pos.eigenvalues()(0)) / lmax : 0.0;
  out.weak_direction = pos.eigenvectors().col(0);
  const Eigen::FullPivLU<Eigen::Matrix3d> lu(info);
  out.curvature_covariance =
      lu.isInvertible() ? Eigen::Matrix3d(lu.inverse()) : Eigen::Matrix3d::Constant(HUGE_VAL);
  out.covariance = out.curvature_covariance;
  if (o.jackknife_groups_per_axis > 0 && lu.isInvertible()) {
    out.jackknife = JackknifeRegistration(field, xy, out.pose, o.fine, o.jackknife_groups_per_axis,
                                          o.max_iterations);
    if (out.jackknife) {
      out.covariance = CovarianceAtLeast(out.jackknife->covariance, out.curvature_covariance);
    }
  }

  // Plain distances at the solution.
  double sum2 = 0.0;
  int inliers = 0;
  const double threshold = o.fine.loss_sigmas * o.fine.sigma_m;
  for (const Eigen::Vector2d& p : xy) {
    const Eigen::Vector2d w = out.pose.Apply(p);
    const double d = (*field)(w.x(), w.y());
    sum2 += d * d;
    inliers += d <= threshold;
  }
  out.rms_distance_m = std::sqrt(sum2 / static_cast<double>(xy.size()));
  out.inlier_share = static_cast<double>(inliers) / static_cast<double>(xy.size());
  out.valid = true;
  return out;
}

}  // namespace skerry::lidar_aerial
