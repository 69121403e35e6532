#pragma once
/// \file
/// The terrain the simulator's cameras see: a DEM's raster surface, never the estimator's map of
/// it. The estimator resamples the raster onto an ENU grid from the corner of the box it needs
/// (skyline::HorizonForTrack), at half the raster's finest cell by default
/// (skyline.dem_oversampling); a world rendered from that same grid would be the map at every
/// node, and reward the estimator for agreeing with itself (an "inverse crime", Kaipio &
/// Somersalo 2007, "Statistical inverse problems: discretization, model reduction and inverse
/// crimes", J. Comput. Appl. Math. 198(2)). The world is therefore the raster sampled at half its
/// finest cell, on nodes a quarter cell off that corner in both axes: for a map from the same box
/// (the simulator's range and the estimator's `skyline.max_range_m` are both 60 km by default)
/// every world node lies midway between the map's; from any other box they fall where they fall.
/// Either way both follow the raster's own bilinear surface, neither at the other's nodes.

#include <Eigen/Geometry>

#include "skerry/geo/dem.h"
#include "skerry/geo/enu_height_grid.h"

namespace skerry::sim {

/// The world's terrain over `box_w` (ENU, m). Throws as geo::Dem::ResampleToEnu does.
geo::EnuHeightGrid WorldTerrain(const geo::Dem& dem, const Eigen::AlignedBox2d& box_w);

}  // namespace skerry::sim
