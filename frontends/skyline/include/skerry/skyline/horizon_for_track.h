#pragma once
/// \file
/// The horizon predictor a dataset's cameras share: the DEM resampled to the ENU frame over the
/// track's bounding box grown by the horizon's range, clipped to the DEM's footprint.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <vector>

#include "skerry/geo/dem.h"
#include "skerry/skyline/horizon_predictor.h"
#include "skerry/solvers/estimator_config.h"

namespace skerry::skyline {

/// The ENU box (x, y) the horizon of a track needs: the track's bounding box (the dataset origin
/// when the track is empty) grown by `range_m` on every side. What HorizonForTrack resamples,
/// before it is clipped to the DEM, and the window a DEM too large to hold is read by
/// (LoadDatasetMaps).
Eigen::AlignedBox2d HorizonBox(const std::vector<Eigen::Vector3d>& track_w, double range_m);

/// The most nodes an oversampled map may have (about 0.4 GB with its pyramid): beyond it the
/// oversampling is cut to what fits, never below the DEM's own cell.
constexpr double kMaxOversampledMapNodes = 30e6;

/// The map's grid spacing over `box_w`: config.dem_spacing_m when > 0; else the DEM's own cell
/// (the smaller of its two) over config.dem_oversampling, made coarser where that grid would
/// exceed kMaxOversampledMapNodes, never coarser than the cell.
///
/// Why oversample: the raster's surface is bilinear between its nodes, and so is the map's
/// between its own. A map at the raster's cell whose nodes fall between the raster's cuts every
/// crest (its nodes lie on the raster's surface, and a bilinear surface through them never rises
/// above their highest), so the map's skyline is low. The loss grows about linearly with the
/// spacing (a crest is a kink of the raster's surface): on the Côte d'Azur DEM (3", a 67 m cell),
/// against the raster sampled at a quarter of its cell, a camera off Nice sees the Alps' skyline
/// 0.13 px low at the raster's cell and 0.05 px low at half of it
/// (tests/skyline/horizon_for_track_test.cc); at 30 km 0.1 px is 40 m of range.
double MapSpacing(const geo::Dem& dem,
                  const Eigen::AlignedBox2d& box_w,
                  const SkylineConfig& config);

/// The DEM resampled at MapSpacing over the track's box grown by config.max_range_m, clipped to
/// the DEM, and sharpened when config.dem_sharpening > 0 (geo/terrain_sharpening.h). An empty track
/// means the dataset origin. std::invalid_argument when the grown box misses the DEM altogether.
std::shared_ptr<const HorizonPredictor> HorizonForTrack(const geo::Dem& dem,
                                                        const std::vector<Eigen::Vector3d>& track_w,
                                                        const SkylineConfig& config);

}  // namespace skerry::skyline
