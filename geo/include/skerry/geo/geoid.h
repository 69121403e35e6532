#pragma once
/// \file
/// A geoid undulation grid (EGM96 by default, PROJ's `egm96_15.gtx`) read through GDAL and
/// interpolated bilinearly: N such that ellipsoidal h = orthometric H + N.

#include <optional>
#include <string>
#include <vector>

namespace skerry::geo {

/// Where Debian's proj-data puts the EGM96 15' grid.
inline constexpr const char* kDefaultEgm96GridPath = "/usr/share/proj/egm96_15.gtx";

/// A geoid grid held in memory (the 15' EGM96 grid is 4 MB). Immutable after construction, so a
/// const Geoid may be shared between threads.
class Geoid {
 public:
  /// Reads the grid (any geographic raster GDAL opens: .gtx, GeoTIFF). Throws InputError
  /// naming `path` if it is missing (install proj-data or give another path), unreadable, or not
  /// on a geographic (lat/lon) grid.
  explicit Geoid(const std::string& path = kDefaultEgm96GridPath);

  /// The undulation N (m) at a WGS84 position, bilinear between the four surrounding grid nodes;
  /// longitude wraps around for a global grid. nullopt outside a regional grid or on a void node.
  std::optional<double> Undulation(double lat_deg, double lon_deg) const;

  const std::string& path() const { return path_; }

 private:
  std::string path_;
  int cols_ = 0;
  int rows_ = 0;
  double lon0_deg_ = 0.0;   ///< longitude of the centre of column 0
  double lat0_deg_ = 0.0;   ///< latitude of the centre of row 0
  double dlon_deg_ = 0.0;   ///< column step (> 0)
  double dlat_deg_ = 0.0;   ///< row step (< 0 for a north-up grid)
  bool wraps_ = false;      ///< the columns span 360 degrees
  std::vector<float> n_m_;  ///< row-major, NaN for voids
};

}  // namespace skerry::geo
