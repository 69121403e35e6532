#include "skerry/lidar_aerial/aerial_map_tiles.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <stdexcept>

#include "skerry/core/input_error.h"

namespace skerry::lidar_aerial {

AerialMapTiles::AerialMapTiles(std::shared_ptr<const AerialMap> whole, double make_s)
    : map_options_(whole ? whole->options() : AerialMapOptions{}), made_count_(1), make_s_(make_s) {
  if (!whole) throw std::invalid_argument("AerialMapTiles: no map");
  whole_ = std::make_shared<const AerialMapTile>(std::move(whole));
}

AerialMapTiles::AerialMapTiles(std::shared_ptr<const geo::Orthophoto> ortho,
                               const Eigen::AlignedBox2d& bounds_w,
                               const AerialMapOptions& map_options,
                               const AerialMapTilesOptions& options)
    : ortho_(std::move(ortho)), bounds_w_(bounds_w), map_options_(map_options), options_(options) {
  if (!ortho_) throw std::invalid_argument("AerialMapTiles: no orthophoto");
  if (!(options.tile_m > 0.0 && std::isfinite(options.tile_m))) {
    throw std::invalid_argument("AerialMapTiles: tile_m must be positive");
  }
  if (!(options.margin_m > 0.0 && std::isfinite(options.margin_m))) {
    throw std::invalid_argument("AerialMapTiles: margin_m must be positive");
  }
  if (options.cache_tiles < 1) {
    throw std::invalid_argument("AerialMapTiles: cache_tiles must be at least 1");
  }
}

AerialMapTiles::Key AerialMapTiles::KeyOf(const Eigen::Vector2d& xy_w) const {
  return {static_cast<long long>(std::floor(xy_w.x() / options_.tile_m)),
          static_cast<long long>(std::floor(xy_w.y() / options_.tile_m))};
}

Eigen::AlignedBox2d AerialMapTiles::TileBox(const Eigen::Vector2d& xy_w) const {
  const Key k = KeyOf(xy_w);
  const Eigen::Vector2d lo(static_cast<double>(k.first) * options_.tile_m,
                           static_cast<double>(k.second) * options_.tile_m);
  const Eigen::Vector2d grow = Eigen::Vector2d::Constant(options_.margin_m);
  return {lo - grow, lo + Eigen::Vector2d::Constant(options_.tile_m) + grow};
}

std::shared_ptr<const AerialMapTile> AerialMapTiles::At(const Eigen::Vector2d& xy_w) const {
  if (whole_) return whole_;
  if (!xy_w.allFinite() || (xy_w.array().abs() > 1e12).any()) return nullptr;
  const Key key = KeyOf(xy_w);
  std::lock_guard<std::mutex> lock(mutex_);
  if (off_photo_.count(key)) return nullptr;
  std::shared_ptr<const AerialMapTile> tile;
  if (const auto it = made_.find(key); it != made_.end()) tile = it->second.lock();
  if (!tile) {
    const Eigen::AlignedBox2d box = TileBox(xy_w).intersection(bounds_w_);
    if (box.isEmpty()) {
      off_photo_.insert(key);  // outside the bounds: the scan is off the map
      return nullptr;
    }
    const auto t0 = std::chrono::steady_clock::now();
    try {
      tile = std::make_shared<const AerialMapTile>(
          std::make_shared<const AerialMap>(*ortho_, box, map_options_));
    } catch (const InputError& e) {
      if (e.field() != "coverage") throw;
      off_photo_.insert(key);  // nothing of the photo there: the scan is off the map
      return nullptr;
    }
    make_s_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    ++made_count_;
    made_[key] = tile;
  }
  // Most recently used first; the cache keeps cache_tiles of them.
  recent_.remove(tile);
  recent_.push_front(tile);
  while (static_cast<int>(recent_.size()) > options_.cache_tiles) recent_.pop_back();
  // Forget squares whose tile nobody holds any more.
  for (auto it = made_.begin(); it != made_.end();) {
    it = it->second.expired() ? made_.erase(it) : std::next(it);
  }
  return tile;
}

int AerialMapTiles::made() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return made_count_;
}

double AerialMapTiles::make_s() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return make_s_;
}

}  // namespace skerry::lidar_aerial
