#include "skerry/geo/point_cloud.h"

#include <cctype>
#include <cmath>
#include <filesystem>

#include "gdal_support.h"
#include "kitti_bin.h"
#include "pcl_reader.h"
#include "skerry/core/input_error.h"
#include "skerry/geo/las_reader.h"

namespace skerry::geo {

PointCloud LoadPointCloud(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".las") return ReadLas(path).cloud;
  if (ext == ".laz") {
    throw InputError(path, 0, "point_format",
                     "compressed LAS (LAZ) is not supported: decompress it to .las first");
  }
  if (ext == ".pcd") return internal::ReadPcd(path);
  if (ext == ".ply") return internal::ReadPly(path);
  if (ext == ".bin") return internal::ReadKittiBin(path);
  throw InputError(path, 0, "",
                   "unknown point cloud format '" + ext + "' (.las, .pcd, .ply, KITTI .bin)");
}

PointCloud PointCloudToEnu(const PointCloud& cloud,
                           const LocalFrame& frame,
                           const CloudToEnuOptions& options) {
  if (cloud.frame == CloudFrame::kSensor) {
    throw InputError(cloud.path, 0, "crs",
                     "a sensor-frame cloud (KITTI, PCD, PLY) is not georeferenced: place it "
                     "with the sensor's pose instead");
  }
  if (cloud.frame == CloudFrame::kLocalEnu) return cloud;
  OGRSpatialReference crs;
  if (!options.crs.empty()) {
    crs = internal::ParseCrs(options.crs, cloud.path, "crs");
  } else if (!cloud.crs_wkt.empty()) {
    crs = internal::ParseCrs(cloud.crs_wkt, cloud.path, "crs");
  } else {
    throw InputError(
        cloud.path, 0, "crs",
        "the cloud's CRS is unknown (" + cloud.crs_note + "); give one in CloudToEnuOptions::crs");
  }
  double z_unit_m = 1.0;
  if (options.z_unit_m) {
    z_unit_m = *options.z_unit_m;
  } else if (crs.IsProjected()) {
    z_unit_m = crs.GetLinearUnits();
  }
  if (!(z_unit_m > 0.0)) throw InputError(cloud.path, 0, "z_unit", "z unit must be > 0 m");
  std::optional<Geoid> geoid;
  if (options.vertical_datum == VerticalDatum::kEgm96) geoid.emplace(options.geoid_path);

  const internal::CrsToWgs84 transform(crs, cloud.path);
  const size_t n = cloud.points.size();
  std::vector<double> x(n);
  std::vector<double> y(n);
  for (size_t i = 0; i < n; ++i) {
    x[i] = cloud.points[i].x();
    y[i] = cloud.points[i].y();
  }
  transform.ToLonLat(x.data(), y.data(), static_cast<int>(n));

  PointCloud out = cloud;
  out.frame = CloudFrame::kLocalEnu;
  out.crs_note = "local ENU from " + (options.crs.empty() ? cloud.crs_note : "the given CRS");
  for (size_t i = 0; i < n; ++i) {
    if (std::isnan(x[i])) {
      throw InputError(cloud.path, 0, "crs",
                       "point " + std::to_string(i) + " cannot be transformed to WGS84");
    }
    double h = cloud.points[i].z() * z_unit_m;
    if (geoid) {
      const std::optional<double> undulation = geoid->Undulation(y[i], x[i]);
      if (!undulation) {
        throw InputError(cloud.path, 0, "geoid_path",
                         "no geoid undulation at point " + std::to_string(i));
      }
      h += *undulation;
    }
    out.points[i] = frame.ToEnu(y[i], x[i], h);
  }
  return out;
}

}  // namespace skerry::geo
