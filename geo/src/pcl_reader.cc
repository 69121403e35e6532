#include "pcl_reader.h"

#include <pcl/PCLPointCloud2.h>
#include <pcl/conversions.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <limits>
#include <vector>

#include "skerry/core/input_error.h"

namespace skerry::geo::internal {
namespace {

bool HasField(const pcl::PCLPointCloud2& blob, const std::string& name) {
  return std::any_of(blob.fields.begin(), blob.fields.end(),
                     [&](const pcl::PCLPointField& f) { return f.name == name; });
}

// The per-point time field `t` as seconds: FLOAT32 / FLOAT64 are seconds after the scan's stamp
// (skerry's simulator, most drivers' deskew fields); an integer field is nanoseconds (the
// Ouster driver's uint32 `t`). Empty when the cloud has no `t`.
std::vector<float> ReadTimes(const pcl::PCLPointCloud2& blob, const std::string& path) {
  const auto field = std::find_if(blob.fields.begin(), blob.fields.end(),
                                  [](const pcl::PCLPointField& f) { return f.name == "t"; });
  if (field == blob.fields.end()) return {};
  using F = pcl::PCLPointField;
  std::uint32_t size = 0;
  switch (field->datatype) {
    case F::FLOAT32:
    case F::UINT32:
    case F::INT32:
      size = 4;
      break;
    case F::FLOAT64:
    case F::UINT64:
    case F::INT64:
      size = 8;
      break;
    default:
      throw InputError(path, 0, "t",
                       "the time field must be a float (seconds) or a 32/64-bit integer "
                       "(nanoseconds)");
  }
  if (field->count != 1 || field->offset + size > blob.point_step) {
    throw InputError(path, 0, "t", "the time field must be one number per point");
  }
  if (blob.height > 0 && blob.width > 0 &&
      blob.data.size() < static_cast<size_t>(blob.height - 1) * blob.row_step +
                             static_cast<size_t>(blob.width) * blob.point_step) {
    throw InputError(path, 0, "t", "the cloud's data is shorter than its header says");
  }
  const bool seconds = field->datatype == F::FLOAT32 || field->datatype == F::FLOAT64;
  std::vector<float> times;
  times.reserve(static_cast<size_t>(blob.width) * blob.height);
  for (std::uint32_t row = 0; row < blob.height; ++row) {
    for (std::uint32_t col = 0; col < blob.width; ++col) {
      const std::uint8_t* p = blob.data.data() + static_cast<size_t>(row) * blob.row_step +
                              col * blob.point_step + field->offset;
      double v = 0.0;
      switch (field->datatype) {
        case F::FLOAT32: {
          float f;
          std::memcpy(&f, p, sizeof(f));
          v = f;
          break;
        }
        case F::FLOAT64:
          std::memcpy(&v, p, sizeof(v));
          break;
        case F::UINT32: {
          std::uint32_t u;
          std::memcpy(&u, p, sizeof(u));
          v = u;
          break;
        }
        case F::INT32: {
          std::int32_t u;
          std::memcpy(&u, p, sizeof(u));
          v = u;
          break;
        }
        case F::UINT64: {
          std::uint64_t u;
          std::memcpy(&u, p, sizeof(u));
          v = static_cast<double>(u);
          break;
        }
        case F::INT64: {
          std::int64_t u;
          std::memcpy(&u, p, sizeof(u));
          v = static_cast<double>(u);
          break;
        }
        default:
          break;
      }
      times.push_back(static_cast<float>(seconds ? v : v * 1e-9));
    }
  }
  return times;
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
  // An empty cloud (a scan that saw nothing) is valid; PCL's conversion indexes its first point.
  if (static_cast<size_t>(blob.width) * blob.height == 0) return cloud;
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
  cloud.time_s = ReadTimes(blob, path);
  return cloud;
}

void RequireFile(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    throw InputError(path, 0, "", "no such file");
  }
}

PointCloud ReadPcdFile(const std::string& path) {
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

PointCloud ReadPlyFile(const std::string& path) {
  RequireFile(path);
  pcl::PCLPointCloud2 blob;
  pcl::PLYReader reader;
  if (reader.read(path, blob) < 0) {
    throw InputError(path, 0, "", "PCL cannot read it as a PLY file");
  }
  return FromBlob(blob, path);
}

}  // namespace
}  // namespace skerry::geo::internal

// The module's entry point (pcl_reader.h): no exception crosses the module boundary.
extern "C" __attribute__((visibility("default"))) bool skerry_pcl_read(
    const std::string& path,
    skerry::geo::internal::PclFormat format,
    skerry::geo::PointCloud* cloud,
    skerry::geo::internal::PclReadError* error) noexcept {
  using skerry::geo::internal::PclFormat;
  try {
    *cloud = format == PclFormat::kPcd ? skerry::geo::internal::ReadPcdFile(path)
                                       : skerry::geo::internal::ReadPlyFile(path);
    return true;
  } catch (const skerry::InputError& e) {
    // what() is "FILE:LINE: FIELD: message": the same error with an empty message is its prefix.
    const std::string prefix = skerry::InputError(e.file(), e.line(), e.field(), "").what();
    const std::string what = e.what();
    *error = {e.file(), e.line(), e.field(),
              what.compare(0, prefix.size(), prefix) == 0 ? what.substr(prefix.size()) : what};
  } catch (const std::exception& e) {
    *error = {path, 0, "", std::string("PCL cannot read it: ") + e.what()};
  } catch (...) {
    *error = {path, 0, "", "PCL cannot read it"};
  }
  return false;
}
