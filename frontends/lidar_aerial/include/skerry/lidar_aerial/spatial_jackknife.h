#pragma once
/// \file
/// How far a scan's registration would move had one part of the scene been different: the
/// delete-a-group jackknife over spatial blocks of the scan's points, and the covariance it gives.
///
/// The fine step's curvature, (J^T J)^-1 of the weighted residuals (scan_registration.h), says how
/// sharply the cost rises at its minimum. It knows nothing of errors that a whole stretch of the
/// scene shares: a kerb the photo's tone curve lets through in one part and not another, an area
/// without data, a roof's relief displacement, a mosaic's seam. On the real Autzen pair it states
/// 0.1 m and 0.07 deg where the solution moves 1.3 m and 1.6 deg with the photo's contrast and
/// 1.6 m and 1.9 deg when a quarter of the scene is missing (docs/results.md).
///
/// The jackknife measures that from the data. The points are cut into G = a x a blocks of equal
/// count (a strips along the levelled x axis, each cut into a cells along y: contiguous parts of
/// the scene, as spatial cross-validation does, Roberts et al. 2017, "Cross-validation strategies
/// for data with temporal, spatial, hierarchical, or phylogenetic structure", Ecography 40), the
/// registration is solved G times with one block left out, from the full solution, and the spread
/// of those G solutions theta_(g) about their mean gives the covariance of the full one (the
/// delete-a-group jackknife: Efron and Stein 1981, "The jackknife estimate of variance", Ann.
/// Statist. 9; Shao and Tu 1995, "The Jackknife and Bootstrap", sec. 2.3, eq. 2.19 with equal
/// groups): C = (G - 1) / G * sum_g (theta_(g) - mean)(theta_(g) - mean)^T. Errors shared within a
/// block and independent between blocks are in it; what every block shares (the whole photo off
/// by 2 m) is not, nor can any registration of the two files see that.

#include <Eigen/Core>
#include <memory>
#include <optional>
#include <vector>

#include "skerry/lidar_aerial/map_alignment_residual.h"
#include "skerry/lidar_aerial/planar_pose.h"

namespace skerry::lidar_aerial {

struct SpatialJackknife {
  int groups = 0;  ///< G, the blocks left out one at a time
  /// C above, on (x, y, yaw) in (m, m, rad).
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  /// The largest move of a leave-one-block-out solution from the full one (m, rad).
  double max_shift_m = 0.0;
  double max_turn_rad = 0.0;
};

/// The jackknife of the planar registration `solution` of the levelled points `points_l` (only
/// their x and y are used) on `field`, with `groups_per_axis`^2 blocks, each re-solve of at most
/// `max_iterations` Levenberg-Marquardt steps. nullopt when groups_per_axis < 2, when a block
/// would hold fewer than 3 points, or when a re-solve fails.
std::optional<SpatialJackknife> JackknifeRegistration(
    std::shared_ptr<const EdgeDistanceField> field,
    const std::vector<Eigen::Vector2d>& points_l,
    const PlanarPose& solution,
    const MapAlignmentOptions& options,
    int groups_per_axis,
    int max_iterations = 20);

/// The smallest covariance (in the Loewner order, along the generalised eigenvectors of the
/// pair) that is at least `a` and at least `b`: with b = L L^T, L (max(D, 1)) L^T for
/// L^-1 a L^-T = V D V^T, V kept. Used to state the larger of the jackknife's and the
/// curvature's uncertainty in every direction. Returns `a` when `b` is not positive definite.
Eigen::Matrix3d CovarianceAtLeast(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b);

}  // namespace skerry::lidar_aerial
