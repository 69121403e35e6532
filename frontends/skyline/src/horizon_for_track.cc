#include "skerry/skyline/horizon_for_track.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include "skerry/geo/terrain_sharpening.h"

namespace skerry::skyline {

Eigen::AlignedBox2d HorizonBox(const std::vector<Eigen::Vector3d>& track_w, double range_m) {
  Eigen::AlignedBox2d box;
  if (track_w.empty()) box.extend(Eigen::Vector2d::Zero());
  for (const Eigen::Vector3d& p : track_w) box.extend(p.head<2>());
  const Eigen::Vector2d grow = Eigen::Vector2d::Constant(range_m);
  return {box.min() - grow, box.max() + grow};
}

double MapSpacing(const geo::Dem& dem,
                  const Eigen::AlignedBox2d& box_w,
                  const SkylineConfig& config) {
  if (config.dem_spacing_m > 0) return config.dem_spacing_m;
  const double cell = dem.cell_size_m().minCoeff();
  const double oversampled = cell / std::max(1, config.dem_oversampling);
  const Eigen::Vector2d size =
      box_w.isEmpty() ? Eigen::Vector2d(Eigen::Vector2d::Zero()) : Eigen::Vector2d(box_w.sizes());
  const double fits = std::sqrt(size.x() * size.y() / kMaxOversampledMapNodes);
  return std::min(cell, std::max(oversampled, fits));
}

std::shared_ptr<const HorizonPredictor> HorizonForTrack(const geo::Dem& dem,
                                                        const std::vector<Eigen::Vector3d>& track_w,
                                                        const SkylineConfig& config) {
  Eigen::AlignedBox2d box = HorizonBox(track_w, config.max_range_m);
  // The DEM's footprint in ENU is that of its outline at the origin's height; half a cell in
  // from it keeps the grid's outer nodes on valid data where the outline curves.
  box = box.intersection(dem.footprint_enu());
  if (box.isEmpty()) {
    throw std::invalid_argument("DEM " + dem.path() + " does not reach within " +
                                std::to_string(config.max_range_m) + " m of the track");
  }
  const double spacing = MapSpacing(dem, box, config);
  HorizonOptions options;
  options.refraction_k = config.refraction_k;
  options.max_range_m = config.max_range_m;
  geo::EnuHeightGrid grid = dem.ResampleToEnu(box, spacing);
  const double footprint_m = config.dem_footprint_cells * dem.cell_size_m().minCoeff();
  if (config.dem_sharpening_sigma > 0) {
    // The gain estimated with the states: the map stays as it is and carries what a gain of 1
    // would add to it (SkylineResidualModel).
    geo::EnuHeightGrid detail = grid;
    geo::SharpenTerrain({1.0, footprint_m}, options.earth_radius_m, &detail);
    for (size_t i = 0; i < detail.up_m.size(); ++i) detail.up_m[i] -= grid.up_m[i];
    auto horizon = std::make_shared<HorizonPredictor>(std::move(grid), options);
    horizon->AttachDetail(std::move(detail));
    return horizon;
  }
  if (config.dem_sharpening > 0) {
    geo::SharpenTerrain({config.dem_sharpening, footprint_m}, options.earth_radius_m, &grid);
  }
  return std::make_shared<HorizonPredictor>(std::move(grid), options);
}

}  // namespace skerry::skyline
