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

/// Grid spacing: config.dem_spacing_m, else the DEM's own cell size (the smaller of its two).
/// An empty track means the dataset origin. std::invalid_argument when the grown box misses
/// the DEM altogether.
std::shared_ptr<const HorizonPredictor> HorizonForTrack(const geo::Dem& dem,
                                                        const std::vector<Eigen::Vector3d>& track_w,
                                                        const SkylineConfig& config);

}  // namespace skerry::skyline
