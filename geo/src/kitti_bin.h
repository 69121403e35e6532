#pragma once
// KITTI Velodyne scans (private to skerry_geo): float32 x, y, z, reflectance per point,
// little-endian, no header.

#include <string>

#include "skerry/geo/point_cloud.h"

namespace skerry::geo::internal {

/// Throws InputError naming `path` when it cannot be read or its size is not a multiple of 16.
PointCloud ReadKittiBin(const std::string& path);

}  // namespace skerry::geo::internal
