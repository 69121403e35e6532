#pragma once
/// \file
/// The simulated harbour: solid upright boxes in the local ENU frame w (quays and the land behind
/// them, piers, breakwaters, buildings, boats, bollards, poles, a crane, paint) above a flat water
/// surface, and a ray caster over them for the LiDAR (lidar_scans.h) and the aerial camera
/// (aerial_render.h).
///
/// Each box says whether it was there when the aerial photograph was taken (`in_image`) and
/// whether it is there now, for the LiDAR (`in_lidar`): a boat moored in the photograph and gone
/// since is only in the image, one that arrived since only in the LiDAR.
///
/// The ray caster walks a uniform 2-D grid of cells over the boxes' footprints with the 2-D DDA
/// of Amanatides and Woo ("A fast voxel traversal algorithm for ray tracing", Eurographics 1987),
/// clipped to the height band [water, tallest top], and tests the boxes listed in each cell it
/// crosses with the slab method (Kay and Kajiya 1986) in the box's own frame. It stops at the
/// first cell whose exit lies beyond the nearest hit found. The water is a plane that returns
/// nothing: a ray reaching it is lost.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <vector>

#include "skerry/sim/scenario.h"

namespace skerry::sim {

enum class HarbourObjectKind {
  kQuay,        ///< land bordered by a quay wall; its top is the ground behind the quay
  kPier,        ///< a pier standing in the water
  kBreakwater,  ///< a mole or breakwater
  kBuilding,
  kBoat,
  kBollard,
  kPole,
  kCraneLeg,
  kCraneBeam,
  kMarking,  ///< paint on the ground: a thin box
};

/// "quay", "pier", ...
const char* HarbourObjectKindName(HarbourObjectKind kind);

/// The ground an orthophoto is rectified to (its terrain model): quays, piers, breakwaters,
/// paint. Everything else stands on it and leans in the photograph.
bool IsTerrain(HarbourObjectKind kind);

/// A solid upright box: its length along the direction yaw_rad (from east, counter-clockwise),
/// its width across, from bottom_m to top_m in w's up.
struct HarbourBox {
  HarbourObjectKind kind = HarbourObjectKind::kQuay;
  Eigen::Vector2d centre_w = Eigen::Vector2d::Zero();  ///< east, north, m
  double yaw_rad = 0.0;
  double length_m = 1.0;
  double width_m = 1.0;
  double bottom_m = 0.0;
  double top_m = 1.0;
  double albedo = 0.5;        ///< 0..1: its brightness in the aerial image, before texture
  double reflectivity = 0.5;  ///< 0..1: scales the LiDAR intensity
  bool in_image = true;       ///< there when the aerial photograph was taken
  bool in_lidar = true;       ///< there now, for the LiDAR
};

/// An arbitrary oriented box (the vessel's hull in w): centre, axes (columns of R_w_box), half
/// sizes along them.
struct OrientedBox {
  Eigen::Vector3d centre_w = Eigen::Vector3d::Zero();
  Eigen::Matrix3d R_w_box = Eigen::Matrix3d::Identity();
  Eigen::Vector3d half_size_m = Eigen::Vector3d::Constant(0.5);
};

/// Which boxes a query sees: the world now (the LiDAR's), at the photograph, or every box.
enum class WorldView { kLidar, kImage, kAll };

struct RayHit {
  double range_m = 0.0;  ///< along the (normalised) direction
  Eigen::Vector3d point_w = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal_w = Eigen::Vector3d::UnitZ();  ///< outward normal of the face hit
  double reflectivity = 0.0;
  int box = -1;  ///< index into boxes(); -1 for a box given to RaycastBox
};

/// The first hit of the ray origin + t direction, t in (0, max_range_m], on the box's outside.
/// Surfaces face outward only: a ray starting inside the box leaves it without a hit, and a ray
/// that only touches the box (along a face, through an edge) misses it. `direction` need not be
/// normalised; the range is in its unit.
std::optional<RayHit> RaycastBox(const OrientedBox& box,
                                 const Eigen::Vector3d& origin,
                                 const Eigen::Vector3d& direction,
                                 double max_range_m);

/// The box as an OrientedBox.
OrientedBox ToOrientedBox(const HarbourBox& box);

/// Whether two oriented boxes overlap (touching counts), by the separating-axis test over the
/// 15 candidate axes (Gottschalk, Lin, Manocha, "OBBTree", SIGGRAPH 1996; Ericson, Real-Time
/// Collision Detection, 2005, sec. 4.4.1).
bool BoxesOverlap(const OrientedBox& a, const OrientedBox& b);

class HarbourWorld {
 public:
  /// The boxes over water at water_level_m (w's up). `cell_m`: the grid's cell size. Throws
  /// std::invalid_argument on a box with a non-positive size or a top not above its bottom.
  HarbourWorld(std::vector<HarbourBox> boxes, double water_level_m, double cell_m = 4.0);

  /// The first box surface the ray meets within max_range_m, as RaycastBox, among the boxes in
  /// `view`; nothing when it reaches the water (or an origin below it) first.
  std::optional<RayHit> Raycast(const Eigen::Vector3d& origin_w,
                                const Eigen::Vector3d& direction_w,
                                double max_range_m,
                                WorldView view = WorldView::kLidar) const;

  /// Whether the box overlaps any box of `view` (touching counts).
  bool Intersects(const OrientedBox& box, WorldView view = WorldView::kAll) const;

  /// The height of the terrain (IsTerrain boxes of `view`) at a point: the highest top of those
  /// covering it, else the water level.
  double TerrainHeight(const Eigen::Vector2d& p_w, WorldView view) const;

  const std::vector<HarbourBox>& boxes() const { return boxes_; }
  double water_level_m() const { return water_level_m_; }
  double max_top_m() const { return max_top_m_; }
  /// The boxes' footprints, east/north.
  const Eigen::AlignedBox2d& bounds() const { return bounds_; }

 private:
  struct Cell {
    std::vector<int> boxes;
    double max_top_m = -1e300;
  };
  bool Sees(const HarbourBox& b, WorldView view) const;
  /// Cell index range covering an east/north box (clamped to the grid).
  void CellRange(const Eigen::AlignedBox2d& region, int* i0, int* j0, int* i1, int* j1) const;

  std::vector<HarbourBox> boxes_;
  std::vector<OrientedBox> oriented_;
  double water_level_m_;
  double max_top_m_;
  Eigen::AlignedBox2d bounds_;
  double cell_m_;
  Eigen::Vector2d grid_origin_;
  int nx_ = 0, ny_ = 0;
  std::vector<Cell> cells_;  ///< row-major, nx_ per row
};

/// Where the built-in layout puts its main features, in w: to place trajectories, and to score a
/// frontend where only the channel's two parallel quays are in view.
struct HarbourLayout {
  Eigen::Vector2d basin_centre_w = Eigen::Vector2d::Zero();
  double basin_size_m = 0.0;
  /// The channel: its centre line from the mouth (on the basin's north quay line) to its open
  /// end, between two parallel quay walls channel_width_m apart.
  Eigen::Vector2d channel_mouth_w = Eigen::Vector2d::Zero();
  Eigen::Vector2d channel_end_w = Eigen::Vector2d::Zero();
  double channel_width_m = 0.0;
  /// The middle of the entrance between the breakwater and the east mole (south side).
  Eigen::Vector2d entrance_w = Eigen::Vector2d::Zero();
  double entrance_width_m = 0.0;
};

HarbourLayout HarbourLayoutOf(const HarbourSpec& spec);

/// The built-in harbour of `spec` (docs/simulator.md, "The harbour"), its boats drawn from the
/// seed. Throws std::invalid_argument when the boats asked for do not fit along the quays.
HarbourWorld BuildHarbour(const HarbourSpec& spec, std::uint64_t seed);

}  // namespace skerry::sim
