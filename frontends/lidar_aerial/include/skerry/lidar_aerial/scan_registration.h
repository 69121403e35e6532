#pragma once
/// \file
/// One levelled scan registered to an aerial map on its own: the coarse search around a prior
/// (coarse_search.h), then Levenberg-Marquardt on the planar pose over the fine residuals
/// (map_alignment_residual.h) from the coarse match. What starts the window (lidar_start.h) and
/// relocates it (lidar_aerial_frontend.h); what the real-data protocol (Autzen) measures.
///
/// Beside the pose it reports what a caller needs to trust it: the covariance of the fine
/// solution, (J^T J)^-1 of the weighted residuals (the cost's curvature at its minimum: it knows
/// nothing of an image that is itself off by metres), raised on request to the spread of a
/// spatial jackknife (spatial_jackknife.h: how far the solution moves when one part of the scene
/// is left out), and the *degeneracy* of the position: the
/// ratio of the smallest to the largest eigenvalue of its 2x2 information, with the direction of
/// the smallest. Near 0, the scan constrains position along one direction only (prior work's
/// parallel quays: position along them unobservable); the weak direction says which.

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "skerry/lidar_aerial/coarse_search.h"
#include "skerry/lidar_aerial/map_alignment_residual.h"
#include "skerry/lidar_aerial/spatial_jackknife.h"

namespace skerry::lidar_aerial {

struct RegistrationOptions {
  bool coarse_first = true;  ///< false: the fine step from the prior alone
  CoarseSearchOptions coarse;
  MapAlignmentOptions fine;
  int max_iterations = 50;
  /// a >= 2: the covariance is at least the spatial jackknife's over a x a blocks of the points
  /// (a x a extra fine solves); 0: the curvature alone.
  int jackknife_groups_per_axis = 0;
};

struct Registration {
  bool valid = false;  ///< a solution was found (points, map coverage, a usable solve)
  PlanarPose pose;
  /// x, y (m), yaw (rad): the curvature's, or CovarianceAtLeast(jackknife's, curvature's).
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d curvature_covariance = Eigen::Matrix3d::Zero();  ///< (J^T J)^-1 alone
  std::optional<SpatialJackknife> jackknife;  ///< when asked for and it could be made
  /// lambda_min / lambda_max of the position information, in [0, 1]; and the direction (unit,
  /// ENU) of lambda_min.
  double constraint_ratio = 0.0;
  Eigen::Vector2d weak_direction = Eigen::Vector2d::Zero();
  CoarseMatch coarse;  ///< the coarse step's result (invalid when skipped)
  int iterations = 0;
  double rms_distance_m = 0.0;  ///< over the points, at the solution (clipped distances)
  double inlier_share = 0.0;    ///< points within the loss scale of an edge
};

Registration RegisterScan(const AerialMap& map,
                          std::shared_ptr<const EdgeDistanceField> field,
                          const std::vector<Eigen::Vector3d>& points_l,
                          const PlanarPose& prior,
                          const RegistrationOptions& options = {});

}  // namespace skerry::lidar_aerial
