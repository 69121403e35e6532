#pragma once
/// \file
/// Point clouds as plain arrays, loaded by file extension (.las, .pcd, .ply, KITTI .bin), and
/// the conversion of a georeferenced cloud into the local ENU frame `w`.

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "skerry/core/geodesy.h"
#include "skerry/geo/geoid.h"
#include "skerry/geo/vertical_datum.h"

namespace skerry::geo {

/// What a cloud's coordinates are in.
enum class CloudFrame {
  kSensor,    ///< the scanner's own frame (KITTI .bin, PCD, PLY): never georeferenced here
  kCrs,       ///< a map CRS (LAS): crs_wkt, or empty when the file's CRS could not be decoded
  kLocalEnu,  ///< the dataset's local ENU frame `w` (after PointCloudToEnu)
};

/// A point cloud. Per-point attributes are either empty (the format has none) or one per point.
struct PointCloud {
  std::string path;  ///< the file it was read from
  CloudFrame frame = CloudFrame::kSensor;
  /// Coordinates in `frame` (doubles: projected coordinates need them). For kCrs, x/y in the
  /// CRS's units (e.g. feet) and z as stored in the file (scaled, LAS z unit).
  std::vector<Eigen::Vector3d> points;
  std::vector<float> intensity;  ///< LAS/PCD intensity as stored; KITTI reflectance (0..1)
  std::vector<std::uint8_t> classification;  ///< LAS class (ASPRS codes: 2 ground, 9 water...)
  std::vector<std::uint8_t> return_number;   ///< LAS return number (1 = first)
  /// PCD/PLY field `t`: when each return was measured, seconds after the scan's stamp (a sweep's
  /// returns span its rotation; the LiDAR frontend deskews with them). A float field is seconds,
  /// an integer one nanoseconds (as Ouster's driver writes it). Empty when absent.
  std::vector<float> time_s;
  std::string crs_wkt;   ///< kCrs: the source CRS as WKT2; empty if unknown
  std::string crs_note;  ///< where the CRS came from, or why it could not be decoded
};

/// Reads a cloud by extension (case-insensitive): .las (LasReader, LAS 1.0-1.4, formats 0-10),
/// .pcd and .ply (through PCL; fields x, y, z and, if present, intensity and t), .bin (KITTI
/// Velodyne: float32 x, y, z, reflectance per point). .laz and anything else: InputError naming the
/// file.
PointCloud LoadPointCloud(const std::string& path);

/// How to turn a georeferenced cloud's coordinates into ENU.
struct CloudToEnuOptions {
  explicit CloudToEnuOptions(VerticalDatum datum) : vertical_datum(datum) {}

  /// The datum of the cloud's z (LAS heights are often orthometric: pass kEgm96 to add the
  /// EGM96 undulation, the best skerry can do for NAVD88 and other national datums, ~1 m).
  VerticalDatum vertical_datum;
  /// CRS override ("EPSG:2992", WKT, PROJ string, .prj/.wkt path); empty: the cloud's crs_wkt.
  std::string crs;
  std::string geoid_path = kDefaultEgm96GridPath;
  /// Metres per z unit. Unset: the CRS's linear unit for a projected CRS (feet for a feet CRS,
  /// as LAS writers do), metres for a geographic one.
  std::optional<double> z_unit_m;
};

/// The cloud in the local ENU frame: x/y through the CRS -> WGS84 transform (PROJ), z scaled
/// to metres and made ellipsoidal, then LocalFrame::ToEnu. Attributes are copied. The
/// horizontal datum shift's effect on heights (NAD83 vs WGS84: ~1 m) is not applied. Throws
/// InputError naming the cloud's file when the cloud is in a sensor frame, has no CRS and none
/// is given, or a point cannot be transformed.
PointCloud PointCloudToEnu(const PointCloud& cloud,
                           const LocalFrame& frame,
                           const CloudToEnuOptions& options);

}  // namespace skerry::geo
