#pragma once
// PCD and PLY clouds through PCL, which is loaded only when a PCD or PLY file is read: PCL's
// reader pulls in VTK and GDCM (≈ 19 MiB of memory and 0.06 s of CPU at start-up for every
// process that links it). The reader is a module (libskerry_pcl_reader.so, pcl_reader.cc) with
// one entry point; pcl_module.cc finds and loads it. Private to skerry_geo: PCL never reaches a
// public header.

#include <string>

#include "skerry/geo/point_cloud.h"

namespace skerry::geo::internal {

enum class PclFormat : int { kPcd = 0, kPly = 1 };

/// An InputError's parts, carried across the module boundary as data.
struct PclReadError {
  std::string file;
  int line = 0;
  std::string field;
  std::string message;
};

/// The module's entry point, exported as kPclReadSymbol: reads `path` into `*cloud` (x, y, z
/// and, when the file has the fields, intensity and the per-point time `t`: a float in seconds,
/// or an integer in nanoseconds as the Ouster driver writes it). False with `*error` set when it
/// cannot. Never throws.
using PclReadFunction = bool (*)(const std::string& path,
                                 PclFormat format,
                                 PointCloud* cloud,
                                 PclReadError* error) noexcept;
inline constexpr const char* kPclReadSymbol = "skerry_pcl_read";

/// Through the module (loaded on the first call). Throw InputError naming `path`, also when the
/// module cannot be found or loaded.
PointCloud ReadPcd(const std::string& path);
PointCloud ReadPly(const std::string& path);

}  // namespace skerry::geo::internal
