#pragma once
// PCD and PLY clouds through PCL (private to skerry_geo: PCL never reaches a public header).

#include <string>

#include "skerry/geo/point_cloud.h"

namespace skerry::geo::internal {

/// x, y, z and, when the file has the field, intensity. Throws InputError naming `path`.
PointCloud ReadPcd(const std::string& path);
PointCloud ReadPly(const std::string& path);

}  // namespace skerry::geo::internal
