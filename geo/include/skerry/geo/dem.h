#pragma once
/// \file
/// A digital elevation model (GeoTIFF, SRTM .hgt, ESRI ASCII grid, any raster GDAL opens) in any
/// CRS, with its heights turned into WGS84 ellipsoidal heights and its lookups done from the
/// local ENU frame `w`.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "skerry/core/geodesy.h"
#include "skerry/geo/enu_height_grid.h"
#include "skerry/geo/geoid.h"
#include "skerry/geo/vertical_datum.h"

namespace skerry::geo {

/// How to read a DEM. The vertical datum has no default: the caller states it for every load.
struct DemOptions {
  explicit DemOptions(VerticalDatum datum) : vertical_datum(datum) {}

  /// The datum of the raster's heights. SRTM (.hgt) is kEgm96.
  VerticalDatum vertical_datum;
  /// CRS override: "EPSG:32633", WKT text, a PROJ string, or the path of a .prj / .wkt file.
  /// Empty: the raster's own CRS, and a raster without one is an InputError.
  std::string crs;
  /// Where the caller takes `crs` from, named in the error when the raster has no CRS
  /// ("maps.dem.crs in DIR/dataset.yaml").
  std::string crs_given_as = "DemOptions::crs";
  /// The geoid grid used for kEgm96 (ignored for kEllipsoidal).
  std::string geoid_path = kDefaultEgm96GridPath;
  /// Metres per raster height unit. Unset: the band's unit ("m", "ft", "US survey foot"...),
  /// metres when the band states none. The band's own scale and offset are always applied.
  std::optional<double> height_unit_m;
  /// An extra nodata value (raw raster units) for rasters that do not declare theirs. Heights
  /// outside [-11000, 9000] m after conversion, and the raw values -9999, -32767 and -99999
  /// when not declared, are refused (InputError, field "nodata") as undeclared nodata.
  std::optional<double> nodata;
  /// The most cells a DEM may declare: more is an InputError (field "size") before anything is
  /// allocated, where a few hundred bytes of GeoTIFF header declaring 10^10 cells would otherwise
  /// ask for 40 GB. 2^28 cells (1 GiB of float32 heights) hold twenty 1" SRTM tiles or a 1 m DEM
  /// 16 km square; crop a larger raster to the area of the track, or raise this.
  std::int64_t max_cells = std::int64_t{1} << 28;
  /// Read only the cells under this box (ENU x, y in the frame, metres) and two around them, as
  /// if the raster were cropped there: the DEM of a whole country (a VRT over its tiles) costs
  /// the memory of the area used, and max_cells bounds that window. The footprint, the geo box
  /// and every lookup are the window's. A box that misses the raster is an InputError
  /// ("coverage"). Unset: the whole raster.
  std::optional<Eigen::AlignedBox2d> window_enu;
};

/// Geodetic bounding box (deg).
struct GeoBox {
  double lat_min_deg = 0.0;
  double lat_max_deg = 0.0;
  double lon_min_deg = 0.0;
  double lon_max_deg = 0.0;
};

/// A DEM held in memory, read once at construction.
///
/// Interpolation is bilinear in the raster's own pixel grid between the *centres* of the four
/// surrounding cells, where GDAL's geotransform puts them (it always describes cell corners:
/// GDAL has already shifted pixel-is-point rasters by half a cell, so SRTM .hgt centres fall on
/// whole arc-seconds and an ESRI grid's `xllcenter` is a centre). The valid area is therefore the
/// rectangle of cell centres, half a cell inside the raster's outer edge.
///
/// Voids (GDAL's nodata value, NaN, and -32768 in 16-bit integer rasters, SRTM's void) are
/// missing: a lookup touching one returns nullopt, never -32 km. Heights are held as float32
/// metres (resolution ~0.1 mm at 1000 m).
///
/// Thread safety: lookups are const but go through one PROJ transformation guarded by a mutex.
class Dem {
 public:
  /// Reads the raster. Throws InputError naming `path` (and the field: "crs", "geoid_path",
  /// "geotransform", "height_unit"...) when the file cannot be opened or is corrupt, has no
  /// georeferencing, has no CRS and none is given, or (kEgm96) the geoid grid is missing.
  Dem(const std::string& path, const LocalFrame& frame, const DemOptions& options);
  ~Dem();
  Dem(Dem&&) noexcept;
  Dem& operator=(Dem&&) noexcept;

  /// The raster value (m) at a WGS84 position, in the raster's own vertical datum (orthometric
  /// for kEgm96), bilinear; nullopt outside the valid area or if any of the four cells is void.
  std::optional<double> RasterHeight(double lat_deg, double lon_deg) const;
  /// The terrain's ellipsoidal height (m): RasterHeight plus, for kEgm96, the geoid undulation.
  std::optional<double> EllipsoidalHeight(double lat_deg, double lon_deg) const;
  /// The geoid undulation N (m) used at a position (0 for kEllipsoidal).
  std::optional<double> GeoidUndulation(double lat_deg, double lon_deg) const;

  /// Ellipsoidal height (m) of the terrain on the ellipsoid normal through the ENU point p_w.
  std::optional<double> HeightAt(const Eigen::Vector3d& p_w) const;
  /// The point's ellipsoidal height minus the terrain's under it (m): > 0 above ground.
  std::optional<double> Clearance(const Eigen::Vector3d& p_w) const;

  /// The terrain surface's ENU up coordinate on a regular grid covering box_w (nodes from
  /// box_w.min() every spacing_m up to box_w.max()). For each node (x, y) the terrain point
  /// (x, y, z) is found by iterating z <- z + (h_terrain(lat, lon) - h) with (lat, lon, h) the
  /// geodetic coordinates of (x, y, z), starting at z = 0: each step moves along the ENU up axis,
  /// which leans away from the local vertical by d/R, so the terrain's slope makes the first
  /// step land at a slightly wrong (lat, lon); the loop stops once |dz| < 1 mm (two or three
  /// steps; at most 5). Throws std::invalid_argument for a spacing <= 0 or an empty box.
  EnuHeightGrid ResampleToEnu(const Eigen::AlignedBox2d& box_w, double spacing_m) const;

  /// Throws InputError (field "coverage") naming the DEM file when any point of the track, or
  /// any point within margin_m of it horizontally, falls outside the valid area or on a void
  /// cell. The message gives how many points fail, the first (index and ENU point) and the one
  /// missing by most, with the distance (m) by which it misses the raster (to about a cell).
  void RequireCovers(const std::vector<Eigen::Vector3d>& track_w, double margin_m) const;

  const std::string& path() const;
  VerticalDatum vertical_datum() const;
  /// The CRS the raster was read in (WKT2) and where it came from ("file" or "override").
  const std::string& crs_wkt() const;
  const std::string& crs_source() const;
  int cols() const;
  int rows() const;
  /// Cell size in the CRS's own units (x, y), e.g. degrees or metres.
  Eigen::Vector2d cell_size_crs() const;
  /// Distance (m) on the ellipsoid between neighbouring cell centres along the raster's rows (x)
  /// and columns (y), at the raster's centre.
  Eigen::Vector2d cell_size_m() const;
  /// The valid area (the rectangle of cell centres): geodetic bounding box, and the ENU (x, y)
  /// bounding box of its outline at the frame origin's height.
  const GeoBox& footprint_geodetic() const;
  const Eigen::AlignedBox2d& footprint_enu() const;
  /// Number of void cells.
  int void_count() const;
  /// Centres (lat, lon) of the void cells, in raster order.
  std::vector<Eigen::Vector2d> VoidCellCentres() const;
  const LocalFrame& frame() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace skerry::geo
