#pragma once
// GDAL / OGR plumbing shared by the geo readers (private to skerry_geo): registration, quiet
// error capture, datasets that close themselves, CRS parsing and CRS <-> WGS84 transforms.

#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>

namespace skerry::geo::internal {

/// GDALAllRegister(), once per process.
void EnsureGdalRegistered();

/// While alive, GDAL errors on this thread go nowhere (not to stderr); LastMessage() returns the
/// last one, so that it can be put into an InputError.
class QuietGdalErrors {
 public:
  QuietGdalErrors();
  ~QuietGdalErrors();
  QuietGdalErrors(const QuietGdalErrors&) = delete;
  QuietGdalErrors& operator=(const QuietGdalErrors&) = delete;
  /// ": <GDAL's message>" or "" when GDAL said nothing.
  static std::string LastMessage();
};

struct GdalDatasetCloser {
  void operator()(GDALDataset* dataset) const { GDALClose(dataset); }
};
using GdalDatasetPtr = std::unique_ptr<GDALDataset, GdalDatasetCloser>;

/// Opens a raster read-only; throws InputError naming `path` (missing file, unknown format,
/// corrupt header) with GDAL's own reason.
GdalDatasetPtr OpenRaster(const std::string& path);

/// Throws InputError(path, 0, field) when the raster's declared pixels exceed `max_pixels`, before
/// anything of that size is allocated: a GeoTIFF header of a few hundred bytes (a sparse or a
/// truncated file) can declare 10^10 pixels. The message gives the size, its memory at
/// `bytes_per_pixel`, the limit's name `limit_name` and how to crop the raster.
/// std::invalid_argument for a limit below 1.
void RequireRasterFits(GDALDataset& dataset,
                       std::int64_t max_pixels,
                       int bytes_per_pixel,
                       const std::string& limit_name,
                       const std::string& path,
                       const std::string& field = "size");

/// A CRS given by the user: "EPSG:32633", WKT (1 or 2, ESRI flavour too), a PROJ string, or the
/// path of a file holding one of those (.prj, .wkt). Axis order is set to the traditional GIS
/// order (x = easting / longitude). Throws InputError(file, 0, field, ...) when it cannot be read.
OGRSpatialReference ParseCrs(const std::string& text,
                             const std::string& file,
                             const std::string& field);

/// `crs` with the traditional GIS axis order, throws InputError(file, 0, "crs") if it is empty.
OGRSpatialReference NormaliseCrs(const OGRSpatialReference& crs, const std::string& file);

/// "NAME (EPSG:CODE)" or "NAME".
std::string CrsName(const OGRSpatialReference& crs);

/// WKT2 text of a CRS.
std::string CrsWkt(const OGRSpatialReference& crs);

/// Metres per unit of a height unit name as GDAL bands state them ("m", "metre", "ft", "foot",
/// "US survey foot", "ftUS"...); 0 when the name is not known. "" is metres.
double HeightUnitToMetres(const std::string& unit);

/// Both directions between a CRS and WGS84 geographic in (lon, lat) order, through one PROJ
/// operation (the inverse is the forward's own inverse, so a round trip closes exactly).
/// OGRCoordinateTransformation is not thread-safe: calls are serialised by a mutex.
class CrsToWgs84 {
 public:
  /// Throws InputError(file, 0, "crs") when PROJ finds no operation.
  CrsToWgs84(const OGRSpatialReference& crs, const std::string& file);

  /// In place: x[i], y[i] in the CRS -> lon[i], lat[i] (deg). Points that fail become NaN;
  /// returns the number that failed.
  int ToLonLat(double* x, double* y, int n) const;
  /// In place: lon[i], lat[i] (deg) -> x[i], y[i] in the CRS. Failures become NaN.
  int FromLonLat(double* lon, double* lat, int n) const;

  bool is_geographic() const { return is_geographic_; }

 private:
  std::unique_ptr<OGRCoordinateTransformation> to_wgs84_;
  std::unique_ptr<OGRCoordinateTransformation> from_wgs84_;
  bool is_geographic_ = false;
  mutable std::mutex mutex_;
};

}  // namespace skerry::geo::internal
