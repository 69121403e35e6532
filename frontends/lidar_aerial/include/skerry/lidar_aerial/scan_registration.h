#pragma once
/// \file
/// One levelled scan registered to an aerial map on its own: the coarse search around a prior
/// (coarse_search.h), then Levenberg-Marquardt on the planar pose over the fine residuals
/// (map_alignment_residual.h) from the coarse match. What starts the window (lidar_start.h) and
/// relocates it (lidar_aerial_frontend.h); what the real-data protocol (Autzen) measures.
///
/// Beside the pose it reports what a caller needs to trust it: the covariance of the fine
/// solution, (J^T J)^-1 of the weighted residuals (the cost's curvature at its minimum: it knows
/// nothing of an image that is itself off by metres), and the *degeneracy* of the position: the
/// ratio of the smallest to the largest eigenvalue of its 2x2 information, with the direction of
/// the smallest. Near 0, the scan constrains position along one direction only (prior work's
/// parallel quays: position along them unobservable); the weak direction says which.

#include <Eigen/Core>
#include <vector>

#include "skerry/lidar_aerial/coarse_search.h"
#include "skerry/lidar_aerial/map_alignment_residual.h"

namespace skerry::lidar_aerial {

struct RegistrationOptions {
  bool coarse_first = true;  ///< false: the fine step from the prior alone
  CoarseSearchOptions coarse;
  MapAlignmentOptions fine;
  int max_iterations = 50;
};

struct Registration {
  bool valid = false;  ///< a solution was found (points, map coverage, a usable solve)
  PlanarPose pose;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();  ///< x, y (m), yaw (rad)
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
