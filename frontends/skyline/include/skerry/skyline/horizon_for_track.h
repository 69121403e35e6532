#pragma once
/// \file
/// The horizon predictor a dataset's cameras share: the DEM resampled to the ENU frame over the
/// track's bounding box grown by the horizon's range, clipped to the DEM's footprint.

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "skerry/geo/dem.h"
#include "skerry/skyline/horizon_predictor.h"
#include "skerry/solvers/estimator_config.h"

namespace skerry::skyline {

/// Grid spacing: config.dem_spacing_m, else the DEM's own cell size (the smaller of its two).
/// An empty track means the dataset origin. std::invalid_argument when the grown box misses
/// the DEM altogether.
std::shared_ptr<const HorizonPredictor> HorizonForTrack(const geo::Dem& dem,
                                                        const std::vector<Eigen::Vector3d>& track_w,
                                                        const SkylineConfig& config);

}  // namespace skerry::skyline
