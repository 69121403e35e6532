#include "skerry/lidar_aerial/map_alignment_residual.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace skerry::lidar_aerial {

namespace {

double Scale(size_t n, const MapAlignmentOptions& o) {
  if (n == 0) return 0.0;
  return std::sqrt(std::min(1.0, o.effective_points / static_cast<double>(n)) *
                   o.information_share);
}

}  // namespace

DistanceLoss ParseDistanceLoss(const std::string& name) {
  if (name == "geman_mcclure") return DistanceLoss::kGemanMcClure;
  if (name == "huber") return DistanceLoss::kHuber;
  throw std::invalid_argument("unknown loss '" + name + "' (expected geman_mcclure, huber)");
}

const char* ToString(DistanceLoss loss) {
  return loss == DistanceLoss::kGemanMcClure ? "geman_mcclure" : "huber";
}

EdgeDistanceField::EdgeDistanceField(const AerialMap& map)
    : distance_(map.distance().isContinuous() ? map.distance() : map.distance().clone()),
      x0_(map.ToEnu({0.0, 0.0}).x()),
      y1_(map.ToEnu({0.0, 0.0}).y()),
      resolution_m_(map.resolution_m()),
      grid_(distance_.ptr<float>(), 0, distance_.rows, 0, distance_.cols),
      interpolator_(grid_) {}

std::unique_ptr<ceres::CostFunction> MapAlignmentCost::Create(
    std::shared_ptr<const EdgeDistanceField> field,
    std::vector<Eigen::Vector3d> points_s,
    const Eigen::Quaterniond& q_b_s,
    const Eigen::Vector3d& p_b_s,
    const MapAlignmentOptions& options) {
  if (points_s.empty()) throw std::invalid_argument("MapAlignmentCost: no points");
  for (Eigen::Vector3d& p : points_s) p = q_b_s * p + p_b_s;
  const int n = static_cast<int>(points_s.size());
  return std::make_unique<ceres::AutoDiffCostFunction<MapAlignmentCost, ceres::DYNAMIC, 4, 3>>(
      new MapAlignmentCost(std::move(field), std::move(points_s), options), n);
}

MapAlignmentCost::MapAlignmentCost(std::shared_ptr<const EdgeDistanceField> field,
                                   std::vector<Eigen::Vector3d> points_b,
                                   const MapAlignmentOptions& options)
    : field_(std::move(field)),
      points_b_(std::move(points_b)),
      options_(options),
      scale_(Scale(points_b_.size(), options)) {}

PointReading::PointReading(std::shared_ptr<const EdgeDistanceField> field,
                           size_t points,
                           const MapAlignmentOptions& options,
                           std::vector<double> relief,
                           const Eigen::Vector2d& nadir_w,
                           const std::string& who)
    : field_(std::move(field)),
      options_(options),
      scale_(Scale(points, options)),
      relief_(std::move(relief)),
      nadir_w_(nadir_w) {
  if (!relief_.empty() && relief_.size() != points) {
    throw std::invalid_argument(who + ": one relief factor per point, or none");
  }
}

std::unique_ptr<ceres::CostFunction> DeskewedMapAlignmentCost::Create(
    std::shared_ptr<const EdgeDistanceField> field,
    std::vector<Eigen::Vector3d> points_b,
    std::vector<double> tau_s,
    const MapAlignmentOptions& options,
    std::vector<double> relief,
    const Eigen::Vector2d& nadir_w) {
  if (points_b.empty()) throw std::invalid_argument("DeskewedMapAlignmentCost: no points");
  if (tau_s.size() != points_b.size()) {
    throw std::invalid_argument("DeskewedMapAlignmentCost: one time per point");
  }
  const int n = static_cast<int>(points_b.size());
  return std::make_unique<
      ceres::AutoDiffCostFunction<DeskewedMapAlignmentCost, ceres::DYNAMIC, 4, 3, 3>>(
      new DeskewedMapAlignmentCost(std::move(field), std::move(points_b), std::move(tau_s), options,
                                   std::move(relief), nadir_w),
      n);
}

DeskewedMapAlignmentCost::DeskewedMapAlignmentCost(std::shared_ptr<const EdgeDistanceField> field,
                                                   std::vector<Eigen::Vector3d> points_b,
                                                   std::vector<double> tau_s,
                                                   const MapAlignmentOptions& options,
                                                   std::vector<double> relief,
                                                   const Eigen::Vector2d& nadir_w)
    : points_b_(std::move(points_b)),
      tau_s_(std::move(tau_s)),
      reading_(std::move(field),
               points_b_.size(),
               options,
               std::move(relief),
               nadir_w,
               "DeskewedMapAlignmentCost") {}

std::unique_ptr<ceres::CostFunction> MountedMapAlignmentCost::Create(
    std::shared_ptr<const EdgeDistanceField> field,
    const std::vector<Eigen::Vector3d>& points_b,
    std::vector<double> tau_s,
    std::vector<Eigen::Matrix3d> deskew,
    const Eigen::Quaterniond& q_b_s0,
    const Eigen::Vector3d& p_b_s0,
    const MapAlignmentOptions& options,
    std::vector<double> relief,
    const Eigen::Vector2d& nadir_w) {
  if (points_b.empty()) throw std::invalid_argument("MountedMapAlignmentCost: no points");
  if (tau_s.size() != points_b.size() || deskew.size() != points_b.size()) {
    throw std::invalid_argument("MountedMapAlignmentCost: one time and one deskew per point");
  }
  // R_b_s0 p_s,i = D_i^T p_b,i - p_b_s0: each point in the sensor frame, on the body's axes.
  std::vector<Eigen::Vector3d> points_s0_b(points_b.size());
  for (size_t i = 0; i < points_b.size(); ++i) {
    points_s0_b[i] = deskew[i].transpose() * points_b[i] - p_b_s0;
  }
  const int n = static_cast<int>(points_b.size());
  return std::make_unique<
      ceres::AutoDiffCostFunction<MountedMapAlignmentCost, ceres::DYNAMIC, 4, 3, 3, 4, 3>>(
      new MountedMapAlignmentCost(std::move(field), std::move(points_s0_b), std::move(tau_s),
                                  std::move(deskew), q_b_s0.normalized(), p_b_s0.z(), options,
                                  std::move(relief), nadir_w),
      n);
}

MountedMapAlignmentCost::MountedMapAlignmentCost(std::shared_ptr<const EdgeDistanceField> field,
                                                 std::vector<Eigen::Vector3d> points_s0_b,
                                                 std::vector<double> tau_s,
                                                 std::vector<Eigen::Matrix3d> deskew,
                                                 const Eigen::Quaterniond& q_b_s0,
                                                 double height_m,
                                                 const MapAlignmentOptions& options,
                                                 std::vector<double> relief,
                                                 const Eigen::Vector2d& nadir_w)
    : points_s0_b_(std::move(points_s0_b)),
      q_b_s0_(q_b_s0),
      height_m_(height_m),
      tau_s_(std::move(tau_s)),
      deskew_(std::move(deskew)),
      reading_(std::move(field),
               points_s0_b_.size(),
               options,
               std::move(relief),
               nadir_w,
               "MountedMapAlignmentCost") {}

std::unique_ptr<ceres::CostFunction> PlanarAlignmentCost::Create(
    std::shared_ptr<const EdgeDistanceField> field,
    std::vector<Eigen::Vector2d> points_l,
    const MapAlignmentOptions& options) {
  if (points_l.empty()) throw std::invalid_argument("PlanarAlignmentCost: no points");
  const int n = static_cast<int>(points_l.size());
  return std::make_unique<ceres::AutoDiffCostFunction<PlanarAlignmentCost, ceres::DYNAMIC, 3>>(
      new PlanarAlignmentCost(std::move(field), std::move(points_l), options), n);
}

PlanarAlignmentCost::PlanarAlignmentCost(std::shared_ptr<const EdgeDistanceField> field,
                                         std::vector<Eigen::Vector2d> points_l,
                                         const MapAlignmentOptions& options)
    : field_(std::move(field)),
      points_l_(std::move(points_l)),
      options_(options),
      scale_(Scale(points_l_.size(), options)) {}

}  // namespace skerry::lidar_aerial
