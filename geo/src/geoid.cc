#include "skerry/geo/geoid.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>

#include "gdal_support.h"
#include "skerry/core/input_error.h"

namespace skerry::geo {
namespace {
// 2^28 nodes (1 GiB of float32): a 1' global grid (21600 x 10801) fits, a header declaring
// 10^10 nodes is refused before anything is allocated.
constexpr std::int64_t kMaxGeoidNodes = std::int64_t{1} << 28;
}  // namespace

Geoid::Geoid(const std::string& path) : path_(path) {
  if (!std::filesystem::exists(path)) {
    throw InputError(path, 0, "geoid_path",
                     "geoid grid not found (Debian: install proj-data, or give the path of an "
                     "EGM96 grid)");
  }
  internal::GdalDatasetPtr dataset = internal::OpenRaster(path);
  const OGRSpatialReference* crs = dataset->GetSpatialRef();
  if (crs != nullptr && !crs->IsEmpty() && !crs->IsGeographic()) {
    throw InputError(path, 0, "geoid_path", "a geoid grid must be on a latitude/longitude grid");
  }
  double gt[6];
  if (dataset->GetGeoTransform(gt) != CE_None || gt[2] != 0.0 || gt[4] != 0.0 || gt[1] <= 0.0 ||
      gt[5] == 0.0) {
    throw InputError(path, 0, "geoid_path", "no north-up geotransform");
  }
  internal::RequireRasterFits(*dataset, kMaxGeoidNodes, sizeof(float), "the geoid grid's limit",
                              path, "geoid_path");
  cols_ = dataset->GetRasterXSize();
  rows_ = dataset->GetRasterYSize();
  dlon_deg_ = gt[1];
  dlat_deg_ = gt[5];
  lon0_deg_ = gt[0] + 0.5 * gt[1];
  lat0_deg_ = gt[3] + 0.5 * gt[5];
  wraps_ = std::abs(cols_ * dlon_deg_ - 360.0) < 1e-6;

  GDALRasterBand* band = dataset->GetRasterBand(1);
  n_m_.resize(static_cast<size_t>(cols_) * rows_);
  internal::QuietGdalErrors quiet;
  if (band->RasterIO(GF_Read, 0, 0, cols_, rows_, n_m_.data(), cols_, rows_, GDT_Float32, 0, 0,
                     nullptr) != CE_None) {
    throw InputError(path, 0, "geoid_path",
                     "cannot read the grid" + internal::QuietGdalErrors::LastMessage());
  }
  int has_nodata = 0;
  const double nodata = band->GetNoDataValue(&has_nodata);
  for (float& v : n_m_) {
    if (!std::isfinite(v) || (has_nodata && v == static_cast<float>(nodata))) {
      v = std::numeric_limits<float>::quiet_NaN();
    }
  }
}

std::optional<double> Geoid::Undulation(double lat_deg, double lon_deg) const {
  if (!std::isfinite(lat_deg) || !std::isfinite(lon_deg)) return std::nullopt;
  double c = (lon_deg - lon0_deg_) / dlon_deg_;
  const double r = (lat_deg - lat0_deg_) / dlat_deg_;
  if (wraps_) c -= cols_ * std::floor(c / cols_);  // into [0, cols)
  if (r < 0.0 || r > rows_ - 1) return std::nullopt;
  if (!wraps_ && (c < 0.0 || c > cols_ - 1)) return std::nullopt;
  const int c0 = std::min(static_cast<int>(c), wraps_ ? cols_ - 1 : cols_ - 2);
  const int r0 = std::min(static_cast<int>(r), rows_ - 2);
  const int c1 = wraps_ ? (c0 + 1) % cols_ : c0 + 1;
  const double tc = c - c0;
  const double tr = r - r0;
  const auto at = [&](int row, int col) {
    return static_cast<double>(n_m_[static_cast<size_t>(row) * cols_ + col]);
  };
  const double v = (1 - tr) * ((1 - tc) * at(r0, c0) + tc * at(r0, c1)) +
                   tr * ((1 - tc) * at(r0 + 1, c0) + tc * at(r0 + 1, c1));
  if (std::isnan(v)) return std::nullopt;
  return v;
}

}  // namespace skerry::geo
