#pragma once
/// \file
/// Prior work's LiDAR-to-aerial matcher, reimplemented as a baseline to run beside skerry's
/// registration on the same scans (bench/aerial_alignment.cc). Prior work localised a motor boat
/// from five LiDARs against a 150 x 150 m aerial tile at 0.16 m/px:
///
/// 1. The scan projected top-down with the heading being tried, around the prior position.
/// 2. "Stacked" points kept: the `stacked_cells` most populated cells of `cell_m` (walls and
///    poles); (the cut 0.3 m above the water and the hull is the caller's, as in PrepareScan).
/// 3. RANSAC lines per grid cell of `ransac_cell_m`: in each cell the line with the most points
///    within `ransac_inlier_m`; its inliers (at least `ransac_min_inliers`) are drawn, the rest
///    dropped.
/// 4. Canny edges of the aerial image (here the AerialMap's, at the same resolution).
/// 5. Position: the unpadded FFT cross-correlation of the two tile-sized images (circular: a
///    shift wraps around the tile), its peak the offset from the prior.
/// 6. Heading: a particle swarm over prior +- `heading_range_deg` (10 particles, 6 iterations;
///    inertia 0.7, cognitive and social weights 1.5), each particle's fitness the correlation
///    peak at its heading.
/// 7. A gate: a match moving the position more than `gate_m` from the prior is rejected (the EKF
///    does not take it).
/// Its known failures, which the baseline keeps: the swarm's local optima, the wrap-around of
/// the unpadded correlation, the heading range of +-5 degrees.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "skerry/lidar_aerial/aerial_map.h"
#include "skerry/lidar_aerial/planar_pose.h"

namespace skerry::lidar_aerial::baseline {

struct BaselineOptions {
  double tile_m = 150.0;
  double cell_m = 0.16;  ///< the tile's pixel (the map must have this resolution)
  int stacked_cells = 3000;
  double ransac_cell_m = 5.0;
  int ransac_iterations = 50;
  double ransac_inlier_m = 0.2;
  int ransac_min_inliers = 5;
  int particles = 10;
  int iterations = 6;
  double heading_range_deg = 5.0;
  double gate_m = 2.0;
  std::uint32_t seed = 1;
};

struct BaselineMatch {
  bool valid = false;   ///< a correlation peak was found (points and map under the tile)
  bool gated = false;   ///< rejected by the gate: the estimate stays at the prior
  PlanarPose pose;      ///< the match (the prior when gated or invalid)
  PlanarPose matched;   ///< the match even when gated
  double score = 0.0;   ///< normalised correlation peak of the best particle
  int evaluations = 0;  ///< correlations computed
};

/// `map` must have `cell_m` resolution; `points_l`: the scan in its levelled frame.
BaselineMatch MatchBaseline(const AerialMap& map,
                            const std::vector<Eigen::Vector3d>& points_l,
                            const PlanarPose& prior,
                            const BaselineOptions& options = {});

}  // namespace skerry::lidar_aerial::baseline
