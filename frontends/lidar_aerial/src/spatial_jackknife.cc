#include "skerry/lidar_aerial/spatial_jackknife.h"

#include <ceres/ceres.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numeric>

namespace skerry::lidar_aerial {

namespace {

// Indices of `points` cut into a x a blocks of equal count: a strips along x, each cut along y.
std::vector<std::vector<size_t>> EqualCountBlocks(const std::vector<Eigen::Vector2d>& points,
                                                  int a) {
  std::vector<size_t> order(points.size());
  std::iota(order.begin(), order.end(), size_t{0});
  const auto by = [&](int axis) {
    return [&points, axis](size_t i, size_t j) {
      return points[i](axis) < points[j](axis) || (points[i](axis) == points[j](axis) && i < j);
    };
  };
  std::sort(order.begin(), order.end(), by(0));
  std::vector<std::vector<size_t>> blocks;
  const size_t n = order.size();
  for (int s = 0; s < a; ++s) {
    std::vector<size_t> strip(order.begin() + static_cast<std::ptrdiff_t>(n * s / a),
                              order.begin() + static_cast<std::ptrdiff_t>(n * (s + 1) / a));
    std::sort(strip.begin(), strip.end(), by(1));
    const size_t m = strip.size();
    for (int c = 0; c < a; ++c) {
      blocks.emplace_back(strip.begin() + static_cast<std::ptrdiff_t>(m * c / a),
                          strip.begin() + static_cast<std::ptrdiff_t>(m * (c + 1) / a));
    }
  }
  return blocks;
}

// Levenberg-Marquardt on (yaw, x, y) from `from`; nullopt when the solve is not usable.
std::optional<PlanarPose> Solve(std::shared_ptr<const EdgeDistanceField> field,
                                std::vector<Eigen::Vector2d> points,
                                const PlanarPose& from,
                                const MapAlignmentOptions& options,
                                int max_iterations) {
  double x[3] = {from.yaw, from.t.x(), from.t.y()};
  ceres::Problem problem;
  problem.AddResidualBlock(
      PlanarAlignmentCost::Create(std::move(field), std::move(points), options).release(), nullptr,
      x);
  ceres::Solver::Options so;
  so.linear_solver_type = ceres::DENSE_QR;
  so.max_num_iterations = max_iterations;
  so.num_threads = 1;
  so.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  if (!summary.IsSolutionUsable()) return std::nullopt;
  return PlanarPose{{x[1], x[2]}, WrapAngle(x[0])};
}

}  // namespace

std::optional<SpatialJackknife> JackknifeRegistration(
    std::shared_ptr<const EdgeDistanceField> field,
    const std::vector<Eigen::Vector2d>& points_l,
    const PlanarPose& solution,
    const MapAlignmentOptions& options,
    int groups_per_axis,
    int max_iterations) {
  if (groups_per_axis < 2) return std::nullopt;
  const int g = groups_per_axis * groups_per_axis;
  if (points_l.size() < static_cast<size_t>(3 * g)) return std::nullopt;
  const std::vector<std::vector<size_t>> blocks = EqualCountBlocks(points_l, groups_per_axis);
  std::vector<char> left_out(points_l.size());
  // theta_(g) - solution on (x, y, yaw); the yaw difference wrapped.
  std::vector<Eigen::Vector3d> moves;
  SpatialJackknife out;
  for (const std::vector<size_t>& block : blocks) {
    std::fill(left_out.begin(), left_out.end(), 0);
    for (size_t i : block) left_out[i] = 1;
    std::vector<Eigen::Vector2d> kept;
    kept.reserve(points_l.size() - block.size());
    for (size_t i = 0; i < points_l.size(); ++i) {
      if (!left_out[i]) kept.push_back(points_l[i]);
    }
    const std::optional<PlanarPose> p =
        Solve(field, std::move(kept), solution, options, max_iterations);
    if (!p) return std::nullopt;
    const Eigen::Vector3d d(p->t.x() - solution.t.x(), p->t.y() - solution.t.y(),
                            WrapAngle(p->yaw - solution.yaw));
    moves.push_back(d);
    out.max_shift_m = std::max(out.max_shift_m, d.head<2>().norm());
    out.max_turn_rad = std::max(out.max_turn_rad, std::abs(d.z()));
  }
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& d : moves) mean += d;
  mean /= static_cast<double>(g);
  for (const Eigen::Vector3d& d : moves) {
    out.covariance += (d - mean) * (d - mean).transpose();
  }
  out.covariance *= static_cast<double>(g - 1) / static_cast<double>(g);
  out.groups = g;
  return out;
}

Eigen::Matrix3d CovarianceAtLeast(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  const Eigen::LLT<Eigen::Matrix3d> llt(b);
  if (llt.info() != Eigen::Success) return a;
  const Eigen::Matrix3d L = llt.matrixL();
  const Eigen::Matrix3d Li = L.inverse();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(Li * a * Li.transpose());
  const Eigen::Matrix3d V = eig.eigenvectors();
  const Eigen::Vector3d d = eig.eigenvalues().cwiseMax(1.0);
  return L * V * d.asDiagonal() * V.transpose() * L.transpose();
}

}  // namespace skerry::lidar_aerial
