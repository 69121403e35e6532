#pragma once
/// \file
/// The global step of LiDAR-to-aerial alignment: position by normalised cross-correlation over
/// a window around a prior, heading by a deterministic sweep (prior work searched heading with a
/// 10-particle swarm, which found local optima; a sweep at a fixed step cannot miss the peak by
/// more than half a step and costs the same at every call).
///
/// The sweep's headings are the multiples of the step covering prior +- range (a fixed grid: the
/// match does not depend on where between two steps the prior lies). For each heading the scan's
/// structure points (levelled frame) are rotated and drawn into a template at `resolution_m`,
/// blurred by `blur_m`; the map's edges, reduced to the same resolution (edge density) and blurred
/// alike, are correlated with it over the search window by OpenCV's matchTemplate
/// (TM_CCOEFF_NORMED: zero-mean normalised correlation, evaluated through the DFT with zero
/// padding, so no wrap-around). The best score over headings and positions is the match, refined
/// below a cell and a step by parabolas through its neighbours.
///
/// What it says about itself:
/// - `covariance`: the spread of the score volume near the peak (cells and headings within
///   `peak_drop` of the best score, weighted by how far they rise above that level): a peak
///   stretched along a quay gives a covariance stretched along it; floored by a cell and a step.
/// - `ambiguity`: the second-best score at least `ambiguity_radius_m` away from the best (any
///   heading) over the best. Near 1: two places fit as well (prior work's false matches on boats,
///   or a repetitive scene), flagged as `ambiguous` above `ambiguous_ratio`.

#include <Eigen/Core>
#include <vector>

#include "skerry/lidar_aerial/aerial_map.h"
#include "skerry/lidar_aerial/planar_pose.h"

namespace skerry::lidar_aerial {

struct CoarseSearchOptions {
  double resolution_m = 1.0;
  double search_radius_m = 30.0;    ///< half-width of the square of positions searched
  double heading_range_deg = 20.0;  ///< headings prior +- this
  double heading_step_deg = 1.0;
  double blur_m = 1.0;
  double peak_drop = 0.1;  ///< score below the best that still counts as the peak
  double ambiguity_radius_m = 5.0;
  double ambiguous_ratio = 0.9;
};

struct CoarseMatch {
  /// false: no points, the window lies outside the map, or nothing under it correlates (no
  /// edges: a blank image, open water): the best score is not positive.
  bool valid = false;
  PlanarPose pose;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();  ///< x, y (m), yaw (rad)
  double score = 0.0;         ///< normalised correlation at the peak, in [-1, 1]
  double second_score = 0.0;  ///< best beyond ambiguity_radius_m
  double ambiguity = 0.0;     ///< second_score / score (0 when score <= 0)
  bool ambiguous = false;
  int headings = 0;  ///< headings tried
};

/// `points_l`: structure points in the levelled frame (only x, y are used); `prior`: the centre
/// of the search.
CoarseMatch CoarseSearch(const AerialMap& map,
                         const std::vector<Eigen::Vector3d>& points_l,
                         const PlanarPose& prior,
                         const CoarseSearchOptions& options = {});

}  // namespace skerry::lidar_aerial
