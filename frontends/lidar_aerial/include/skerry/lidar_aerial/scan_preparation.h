#pragma once
/// \file
/// A LiDAR scan reduced to what an aerial image can confirm: the edges of its vertical structure.
///
/// From above, a camera sees where height changes: a quay wall, a pier's edge, a building's
/// outline, a tree crown's rim against the grass, a pole. The scan is levelled with the
/// *estimated* roll and pitch (heading stays the estimator's to find), cut to range, freed of
/// the water, the own hull and returns below a height, and binned into vertical columns of
/// `cell_m` x `cell_m`. Two kinds of column are structure edges:
/// - a *wall*: its returns span at least `min_vertical_extent_m` with no vertical gap wider than
///   `max_wall_gap_m` (a wall or pole seen side-on stacks returns at every height: prior work's
///   "stacked points"; a tree seen from above puts canopy and ground returns in one column with
///   the trunk zone empty between them, and is not a wall);
/// - a *rim*: its highest return is at least `min_vertical_extent_m` above the highest return of
///   a neighbouring column (the upper side of a step: a roof's edge, a crown's rim, a quay's
///   edge seen from above). A column with no returns takes, for this comparison, the highest of
///   its neighbours when at least `fill_neighbours` of its eight have returns (sparse airborne
///   data leaves holes inside a crown that are not steps); otherwise it is unobserved and makes
///   no step.
/// - a *front* (`front_edges`): the column of the nearest return in an azimuth sector of
///   `front_sector_deg` about the sensor: what a vessel's LiDAR sees first across the water,
///   which returns nothing (a quay's or a pier's edge, a moored hull). A quay 1.8 m high seen
///   from 30 m by a 32-beam scanner is two returns on its face: neither wall nor rim, but the
///   nearest thing in its direction, and in the image the border of concrete and water.
/// The inside of a roof or a crown is none of these, as it shows no edge in the image.
///
/// When the returns carry intensity, the top surface's intensity (the highest return of each
/// column: what a camera looking down sees) makes a third kind: its Canny edges, found as the
/// aerial map finds the image's (blur, thresholds at quantiles of the gradient magnitude), away
/// from unobserved columns: a path's border, a kerb, paint, the rim of a dark crown on bright
/// grass.
///
/// What stands high is not where an orthophoto shows it. Unless the image is a true orthophoto,
/// a point h above the ground seen at an angle theta off nadir is displaced by h tan(theta)
/// (relief displacement: a 15 m tree 18 degrees off nadir moves 5 m), and a sun casts its
/// shadow beside it. Rims and intensity edges higher than `max_edge_height_m` above the local
/// floor (the lowest return within `floor_radius_m`) are therefore not used; walls are, as a
/// wall's position is its foot's. Ground-level edges (a path, a kerb, a quay's edge, paint) are
/// where the image has them. Each edge
/// column gives one point, its returns' mean (a 2-D voxel filter: thousands of returns on one
/// wall do not count thousands of times), weighted by its number of returns; at most
/// `max_points` columns are kept, the most populated first, as prior work kept its 3000 fullest
/// cells.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <limits>
#include <vector>

namespace skerry::lidar_aerial {

struct ScanPreparationOptions {
  double min_range_m = 0.0;  ///< horizontal distance from the sensor; nearer returns dropped
  double max_range_m = 0.0;  ///< 0: no limit
  /// Returns lower than this in the levelled frame (sensor origin, z up) are dropped: the
  /// water and returns just above it (prior work: 0.3 m above the water).
  double min_height_m = -std::numeric_limits<double>::infinity();
  /// The own hull (or vehicle), in the sensor frame: returns inside are dropped. Empty: none.
  Eigen::AlignedBox3d hull_s;
  double cell_m = 0.5;
  double min_vertical_extent_m = 1.5;
  double max_wall_gap_m = 1.0;
  /// The wall's gap may grow with the column's horizontal range by this much per metre (a
  /// scanner's beams fan out: 1.3 degrees apart leave 0.023 m per metre between returns).
  double max_wall_gap_per_m = 0.0;
  bool front_edges = false;
  double front_sector_deg = 0.5;
  int fill_neighbours = 3;
  double max_edge_height_m = 3.0;  ///< <= 0: no limit
  double floor_radius_m = 5.0;
  bool intensity_edges = true;  ///< when intensities are given
  double intensity_blur_m = 1.0;
  double canny_high_quantile = 0.90;
  double canny_low_quantile = 0.75;
  /// At most this many points (<= 0: no limit); with intensity edges, half for the structure
  /// columns and half for the intensity edges (the fullest columns first in each), either share
  /// passing what it does not use to the other.
  int max_points = 3000;
};

struct PreparedScan {
  /// One point per edge column, in the sensor frame (so that any attitude can be applied to
  /// it), with its number of returns.
  std::vector<Eigen::Vector3d> points_s;
  std::vector<int> returns;
  /// The mean time of each edge column's returns (as the `time_s` given), or empty.
  std::vector<double> time_s;
  /// Per point, its column's highest return and its local floor (the lowest return within
  /// `floor_radius_m`), as heights above the point in the levelled frame (top >= 0 >= floor):
  /// how high the structure stands, which says how far an aerial photo displaces its outline
  /// (aerial_map.h, ReliefDisplacement).
  std::vector<float> top_m, floor_m;
  // What happened to the input.
  int input = 0;
  int dropped_range = 0;
  int dropped_low = 0;
  int dropped_hull = 0;
  int dropped_invalid = 0;  ///< NaN or infinite coordinates
  int columns = 0;          ///< columns with returns
  int wall_columns = 0;
  int rim_columns = 0;        ///< rims that are not walls
  int front_columns = 0;      ///< fronts that are neither
  int intensity_columns = 0;  ///< intensity edges that are neither
  int dropped_high = 0;       ///< columns too high above the floor to be edges (not walls)
};

/// `q_level_s`: the rotation that levels the sensor frame (roll and pitch of the sensor in a
/// gravity-aligned frame with its own heading: R_level_s = R_w_s with the yaw removed).
/// `intensity`: one per point, or empty. `time_s`: one per point (when each was measured, in any
/// time origin: a deskewing frontend needs each edge point's), or empty.
PreparedScan PrepareScan(const std::vector<Eigen::Vector3d>& points_s,
                         const std::vector<float>& intensity,
                         const Eigen::Quaterniond& q_level_s,
                         const ScanPreparationOptions& options = {},
                         const std::vector<double>& time_s = {});

}  // namespace skerry::lidar_aerial
