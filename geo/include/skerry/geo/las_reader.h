#pragma once
/// \file
/// A small reader of ASPRS LAS 1.0-1.4 files (uncompressed; Debian ships no LAS library):
/// public header block, variable length records (VLRs and 1.4 extended VLRs), point data
/// formats 0-10, and the CRS from the LASF_Projection records (OGC WKT, or GeoTIFF keys).

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "skerry/geo/point_cloud.h"

namespace skerry::geo {

/// The fields of the public header block that the reader uses (LAS 1.4 specification, R15).
struct LasHeader {
  int version_major = 0;
  int version_minor = 0;
  std::uint16_t global_encoding = 0;
  std::uint16_t header_size = 0;  ///< 227 (1.0-1.2), 235 (1.3), 375 (1.4), or more
  std::uint32_t offset_to_points = 0;
  std::uint32_t vlr_count = 0;
  int point_format = 0;             ///< 0..10 (compression bits removed)
  std::uint16_t record_length = 0;  ///< bytes per point record (>= the format's own size)
  std::uint32_t legacy_point_count = 0;
  std::uint64_t extended_point_count = 0;  ///< 1.4 only, else 0
  std::uint64_t point_count = 0;           ///< the count in force (extended for 1.4 when set)
  Eigen::Vector3d scale = Eigen::Vector3d::Ones();
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  Eigen::Vector3d min = Eigen::Vector3d::Zero();
  Eigen::Vector3d max = Eigen::Vector3d::Zero();
  std::uint64_t waveform_start = 0;  ///< 1.3+
  std::uint64_t evlr_start = 0;      ///< 1.4
  std::uint32_t evlr_count = 0;      ///< 1.4
};

/// One variable length record (or extended VLR).
struct LasVlr {
  std::string user_id;
  std::uint16_t record_id = 0;
  std::string description;
  bool extended = false;
  std::vector<std::uint8_t> data;
};

struct LasFile {
  LasHeader header;
  std::vector<LasVlr> vlrs;
  /// frame kCrs; points in the file's CRS units, intensity, classification, return number.
  PointCloud cloud;
  /// Bounds of the points as read (for comparison with header.min / header.max).
  Eigen::Vector3d read_min = Eigen::Vector3d::Zero();
  Eigen::Vector3d read_max = Eigen::Vector3d::Zero();
};

/// Reads the header and the VLRs only.
LasFile ReadLasHeader(const std::string& path);

/// Reads the whole file. Throws InputError naming `path`:
/// - field "signature": not a LAS file; "point_format": LAZ ("compressed LAS is not supported")
///   or a format outside 0-10 or a record length shorter than the format;
/// - field "version" / "header_size": an unknown version or a header block too short for it;
/// - field "point_count": the header's count disagrees with the file (truncated file or wrong
///   count: both numbers are given), or 1.4's legacy and extended counts disagree;
/// - field "bounds": a point lies outside the header's min/max by more than one scale step.
/// The CRS is taken from an OGC WKT record (LASF_Projection 2112) if there is one, else from the
/// GeoTIFF keys (34735/34736/34737): the EPSG code of ProjectedCSTypeGeoKey (3072) or
/// GeographicTypeGeoKey (2048), with ProjLinearUnitsGeoKey (3076) overriding the linear unit.
/// User-defined GeoKey CRSs are not decoded: cloud.crs_wkt stays empty, cloud.crs_note says why,
/// and the caller passes a CRS to PointCloudToEnu.
LasFile ReadLas(const std::string& path);

}  // namespace skerry::geo
