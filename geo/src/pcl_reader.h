#pragma once
// PCD and PLY clouds through PCL (private to skerry_geo: PCL never reaches a public header).

#include <string>

#include "skerry/geo/point_cloud.h"

namespace skerry::geo::internal {

/// x, y, z and, when the file has the fields, intensity and the per-point time `t` (a float in
/// seconds, or an integer in nanoseconds as the Ouster driver writes it). Throws InputError
/// naming `path`.
PointCloud ReadPcd(const std::string& path);
PointCloud ReadPly(const std::string& path);

}  // namespace skerry::geo::internal
