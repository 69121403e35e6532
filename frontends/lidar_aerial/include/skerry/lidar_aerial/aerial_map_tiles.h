#pragma once
/// \file
/// The aerial map around a track, as one map or as tiles made when the scans reach them.
///
/// One map of the track's box (AerialMap) holds about 7 bytes a cell for the whole run and about
/// 40 while it is made: 110 MB per square kilometre at 0.25 m. That is cheap for a track inside a
/// harbour and too much for one along 20 km of coast, whose box is hundreds of square kilometres.
/// Tiles bound it by the track's length instead of its box:
/// - The plane is cut into squares of `tile_m` on a lattice anchored at the ENU origin.
/// - A scan whose body lies in a square uses that square's tile: the map of the square grown by
///   `margin_m` on every side, so that it holds all the scan can reach (the LiDAR's range, the
///   coarse search's radius, the distance clip).
/// - A tile is made the first time a scan needs it (AerialMap over its box: the orthophoto is read
///   by that window) and shared by every block made on it.
/// - The cache keeps the last `cache_tiles` tiles used. A tile that a block still holds (its cost
///   holds the tile's distance field) is found again rather than made twice.
///
/// Neighbouring tiles overlap by 2 margin_m. A cell's grey is the same in both (AerialMap), but
/// Canny's thresholds are quantiles of each tile's own gradients, so an edge near one tile's
/// border can differ from its neighbour's (docs/lidar_aerial.md).
///
/// Thread safety: At() is serialised (the batch prepares blocks on several threads).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <list>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <utility>

#include "skerry/geo/orthophoto.h"
#include "skerry/lidar_aerial/aerial_map.h"
#include "skerry/lidar_aerial/map_alignment_residual.h"

namespace skerry::lidar_aerial {

/// One map and its distance field, made together and kept together.
struct AerialMapTile {
  explicit AerialMapTile(std::shared_ptr<const AerialMap> m) : map(std::move(m)), field(*map) {}
  AerialMapTile(const AerialMapTile&) = delete;  // the field's interpolator points into itself
  AerialMapTile& operator=(const AerialMapTile&) = delete;

  std::shared_ptr<const AerialMap> map;
  EdgeDistanceField field;
};

/// The tile's distance field, sharing the tile's ownership (a cost that holds it holds the tile).
inline std::shared_ptr<const EdgeDistanceField> FieldOf(
    const std::shared_ptr<const AerialMapTile>& tile) {
  return {tile, &tile->field};
}

struct AerialMapTilesOptions {
  double tile_m = 250.0;    ///< side of a tile's square
  double margin_m = 160.0;  ///< what a scan can reach beyond its square
  int cache_tiles = 4;      ///< tiles kept beyond those the blocks hold
};

class AerialMapTiles {
 public:
  /// One map for every position (the track's box); At() returns it everywhere.
  explicit AerialMapTiles(std::shared_ptr<const AerialMap> whole, double make_s = 0.0);
  /// Tiles of `ortho` inside `bounds_w` (ENU x/y), made on demand with `map_options`.
  /// std::invalid_argument for a tile_m or margin_m that is not positive and finite, or a cache
  /// of fewer than 1 tile.
  AerialMapTiles(std::shared_ptr<const geo::Orthophoto> ortho,
                 const Eigen::AlignedBox2d& bounds_w,
                 const AerialMapOptions& map_options,
                 const AerialMapTilesOptions& options);

  /// The map for a scan with its body at xy_w: the whole map, or the tile of xy_w's square (made
  /// now when it is not at hand); null when that tile does not overlap the orthophoto, or xy_w is
  /// not finite.
  std::shared_ptr<const AerialMapTile> At(const Eigen::Vector2d& xy_w) const;

  bool tiled() const { return ortho_ != nullptr; }
  const AerialMapOptions& map_options() const { return map_options_; }
  const AerialMapTilesOptions& options() const { return options_; }
  /// The ENU box of the tile whose square holds xy_w, before it is clipped to the bounds.
  Eigen::AlignedBox2d TileBox(const Eigen::Vector2d& xy_w) const;

  /// Maps made so far (1 for a whole map) and the seconds spent making them.
  int made() const;
  double make_s() const;

 private:
  using Key = std::pair<long long, long long>;
  Key KeyOf(const Eigen::Vector2d& xy_w) const;

  std::shared_ptr<const AerialMapTile> whole_;
  std::shared_ptr<const geo::Orthophoto> ortho_;
  Eigen::AlignedBox2d bounds_w_;
  AerialMapOptions map_options_;
  AerialMapTilesOptions options_;

  mutable std::mutex mutex_;
  mutable std::map<Key, std::weak_ptr<const AerialMapTile>> made_;
  mutable std::set<Key> off_photo_;  ///< squares whose tile does not overlap the photo
  mutable std::list<std::shared_ptr<const AerialMapTile>> recent_;  ///< most recent first
  mutable int made_count_ = 0;
  mutable double make_s_ = 0.0;
};

}  // namespace skerry::lidar_aerial
