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
/// DEM must have valid heights (the orthophoto must cover the track itself).
DatasetMaps LoadDatasetMaps(const Dataset& data, double margin_m = 0.0);

}  // namespace skerry
