#include "pcl_reader.h"

#include <pcl/PCLPointCloud2.h>
#include <pcl/conversions.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <limits>

#include "skerry/core/input_error.h"

namespace skerry::geo::internal {
namespace {

bool HasField(const pcl::PCLPointCloud2& blob, const std::string& name) {
  return std::any_of(blob.fields.begin(), blob.fields.end(),
                     [&](const pcl::PCLPointField& f) { return f.name == name; });
}

PointCloud FromBlob(const pcl::PCLPointCloud2& blob, const std::string& path) {
  for (const char* axis : {"x", "y", "z"}) {
    if (!HasField(blob, axis)) {
      throw InputError(path, 0, axis, std::string("the cloud has no '") + axis + "' field");
    }
  }
  PointCloud cloud;
  cloud.path = path;
  cloud.frame = CloudFrame::kSensor;
  if (HasField(blob, "intensity")) {
    pcl::PointCloud<pcl::PointXYZI> points;
    pcl::fromPCLPointCloud2(blob, points);
    cloud.points.reserve(points.size());
    cloud.intensity.reserve(points.size());
    for (const pcl::PointXYZI& p : points) {
      cloud.points.emplace_back(p.x, p.y, p.z);
      cloud.intensity.push_back(p.intensity);
    }
  } else {
    pcl::PointCloud<pcl::PointXYZ> points;
    pcl::fromPCLPointCloud2(blob, points);
    cloud.points.reserve(points.size());
    for (const pcl::PointXYZ& p : points) cloud.points.emplace_back(p.x, p.y, p.z);
  }
  return cloud;
}

void RequireFile(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw InputError(path, 0, "", "no such file");
  }
}

}  // namespace

PointCloud ReadPcd(const std::string& path) {
  RequireFile(path);
  pcl::PCDReader reader;
  // PCL 1.13's read() crashes on some malformed files (a header without FIELDS): check the
  // header first, and that a binary body holds every point it announces.
  {
    pcl::PCLPointCloud2 header;
    Eigen::Vector4f origin;
    Eigen::Quaternionf orientation;
    int version = 0;
    int data_type = 0;
    unsigned int data_index = 0;
    if (reader.readHeader(path, header, origin, orientation, version, data_type, data_index) < 0 ||
        header.fields.empty() || header.point_step == 0) {
      throw InputError(path, 0, "", "PCL cannot read it as a PCD file (no valid header)");
    }
    for (const char* axis : {"x", "y", "z"}) {
      if (!HasField(header, axis)) {
        throw InputError(path, 0, axis, std::string("the cloud has no '") + axis + "' field");
      }
    }
    const std::uint64_t points = static_cast<std::uint64_t>(header.width) * header.height;
    std::error_code ec;
    const std::uint64_t size = std::filesystem::file_size(path, ec);
    if (ec) throw InputError(path, 0, "", "cannot read its size: " + ec.message());
    // points * point_step can overflow for a malformed header: compare by division.
    const bool fits =
        data_index <= size && (points == 0 || (size - data_index) / points >= header.point_step);
    const std::uint64_t needed =
        fits ? data_index + points * header.point_step : std::numeric_limits<std::uint64_t>::max();
    if (data_type == 1 && !fits) {
      throw InputError(path, 0, "",
                       "the PCD header announces " + std::to_string(points) + " points (" +
                           std::to_string(needed) + " bytes) but the file has " +
                           std::to_string(size) + " bytes: truncated");
    }
  }
  pcl::PCLPointCloud2 blob;
  if (reader.read(path, blob) < 0) {
    throw InputError(path, 0, "", "PCL cannot read it as a PCD file");
  }
  return FromBlob(blob, path);
}

PointCloud ReadPly(const std::string& path) {
  RequireFile(path);
  pcl::PCLPointCloud2 blob;
  pcl::PLYReader reader;
  if (reader.read(path, blob) < 0) {
    throw InputError(path, 0, "", "PCL cannot read it as a PLY file");
  }
  return FromBlob(blob, path);
}

}  // namespace skerry::geo::internal
