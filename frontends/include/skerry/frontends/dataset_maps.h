#pragma once
/// \file
/// The maps a dataset names (`maps:` in dataset.yaml), loaded through the geodata layer into the
/// dataset's local ENU frame, and checked against the track at load time: a DEM that does not
/// cover where the vessel goes is an InputError naming the file and the gap, never a silent zero
/// height later.

#include <optional>
#include <vector>

#include "skerry/geo/dem.h"
#include "skerry/geo/orthophoto.h"
#include "skerry/io/dataset.h"

namespace skerry {

struct DatasetMaps {
  std::optional<geo::Dem> dem;
  std::optional<geo::Orthophoto> orthophoto;
};

/// The track a dataset says the vessel covers, in ENU: its ground truth, else its GNSS fixes,
/// else its pose fixes.
std::vector<Eigen::Vector3d> DatasetTrack(const Dataset& data);

/// Loads data.dem and data.orthophoto (those present). `margin_m`: how far around the track the
/// DEM must have valid heights (the orthophoto must cover the track itself). A DEM of more than
/// geo::DemOptions::max_cells (a country's, as a VRT over its tiles) is read only within
/// `dem_reach_m` of the track's box (the skyline's max_range_m: the terrain a camera can see);
/// one that fits is read whole. The orthophoto stays in its file (OrthophotoOptions::on_disk).
DatasetMaps LoadDatasetMaps(const Dataset& data, double margin_m = 0.0, double dem_reach_m = 6e4);

}  // namespace skerry
