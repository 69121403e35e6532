#include "skerry/geo/dem.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "gdal_support.h"
#include "skerry/core/input_error.h"

namespace skerry::geo {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// Lowest and highest terrain (m): the Challenger Deep (-10935 m), Everest (8849 m). Anything
// beyond is an undeclared nodata value that must not become a height.
constexpr double kMinPlausibleHeightM = -11000.0;
constexpr double kMaxPlausibleHeightM = 9000.0;

// Void markers writers use without declaring them (-9999 would otherwise pass as bathymetry).
bool IsCommonVoidMarker(float raw) {
  return raw == -9999.0f || raw == -32767.0f || raw == -99999.0f;
}
// Cell-index slack: a point exactly on the outer row of centres must not fall out by rounding.
constexpr double kEdgeSlack = 1e-9;

std::string Format(const char* fmt, double a, double b, double c) {
  char buf[128];
  std::snprintf(buf, sizeof(buf), fmt, a, b, c);
  return buf;
}

}  // namespace

struct Dem::Impl {
  Impl(const std::string& p, const LocalFrame& f, VerticalDatum d) : path(p), frame(f), datum(d) {}

  std::string path;
  LocalFrame frame;
  VerticalDatum datum;
  std::optional<Geoid> geoid;
  std::string crs_wkt;
  std::string crs_source;
  std::unique_ptr<internal::CrsToWgs84> transform;
  double gt[6] = {0, 1, 0, 0, 0, 1};
  double inv_gt[6] = {0, 1, 0, 0, 0, 1};
  int cols = 0;
  int rows = 0;
  std::vector<float> height_m;   // raster datum, metres, row-major, NaN for voids
  std::vector<int> void_prefix;  // (rows + 1) x (cols + 1) integral image of voids
  int voids = 0;
  Eigen::Vector2d cell_size_m = Eigen::Vector2d::Zero();
  GeoBox geo_box;
  Eigen::AlignedBox2d enu_box;

  float Cell(int c, int r) const { return height_m[static_cast<size_t>(r) * cols + c]; }

  // Void cells in the inclusive cell range [c0, c1] x [r0, r1] (clipped to the raster).
  int VoidsIn(int c0, int r0, int c1, int r1) const {
    c0 = std::max(c0, 0);
    r0 = std::max(r0, 0);
    c1 = std::min(c1, cols - 1);
    r1 = std::min(r1, rows - 1);
    if (c0 > c1 || r0 > r1) return 0;
    const auto at = [&](int r, int c) {
      return void_prefix[static_cast<size_t>(r) * (cols + 1) + c];
    };
    return at(r1 + 1, c1 + 1) - at(r0, c1 + 1) - at(r1 + 1, c0) + at(r0, c0);
  }

  // In place: lon/lat (deg) -> continuous cell-centre indices (c, r): cell (i, j)'s centre is at
  // (i, j). NaN where the CRS transform fails.
  void LonLatToCell(double* x, double* y, int n) const {
    transform->FromLonLat(x, y, n);
    for (int i = 0; i < n; ++i) {
      if (std::isnan(x[i])) continue;
      double px = 0.0;
      double py = 0.0;
      GDALApplyGeoTransform(const_cast<double*>(inv_gt), x[i], y[i], &px, &py);
      x[i] = px - 0.5;
      y[i] = py - 0.5;
    }
  }

  // In place: cell-centre indices -> lon/lat (deg).
  void CellToLonLat(double* c, double* r, int n) const {
    for (int i = 0; i < n; ++i) {
      double x = 0.0;
      double y = 0.0;
      GDALApplyGeoTransform(const_cast<double*>(gt), c[i] + 0.5, r[i] + 0.5, &x, &y);
      c[i] = x;
      r[i] = y;
    }
    transform->ToLonLat(c, r, n);
  }

  // Bilinear between the centres of the four cells around (c, r); nullopt outside the centres'
  // rectangle or when any of the four is void.
  std::optional<double> Bilinear(double c, double r) const {
    if (!(c >= -kEdgeSlack && c <= cols - 1 + kEdgeSlack && r >= -kEdgeSlack &&
          r <= rows - 1 + kEdgeSlack)) {
      return std::nullopt;
    }
    c = std::clamp(c, 0.0, cols - 1.0);
    r = std::clamp(r, 0.0, rows - 1.0);
    const int c0 = std::min(static_cast<int>(c), cols - 2);
    const int r0 = std::min(static_cast<int>(r), rows - 2);
    const double tc = c - c0;
    const double tr = r - r0;
    const double v00 = Cell(c0, r0);
    const double v10 = Cell(c0 + 1, r0);
    const double v01 = Cell(c0, r0 + 1);
    const double v11 = Cell(c0 + 1, r0 + 1);
    if (std::isnan(v00) || std::isnan(v10) || std::isnan(v01) || std::isnan(v11)) {
      return std::nullopt;
    }
    return (1 - tr) * ((1 - tc) * v00 + tc * v10) + tr * ((1 - tc) * v01 + tc * v11);
  }

  double Undulation(double lat, double lon, bool* ok) const {
    *ok = true;
    if (datum != VerticalDatum::kEgm96) return 0.0;
    const std::optional<double> n = geoid->Undulation(lat, lon);
    *ok = n.has_value();
    return n.value_or(0.0);
  }

  // Terrain ellipsoidal height at many positions (in place: lat[i] becomes the height, NaN when
  // missing). lon is overwritten.
  void EllipsoidalHeights(std::vector<double>& lat, std::vector<double>& lon) const {
    const int n = static_cast<int>(lat.size());
    std::vector<double> c = lon;
    std::vector<double> r = lat;
    LonLatToCell(c.data(), r.data(), n);
    for (int i = 0; i < n; ++i) {
      const std::optional<double> h = std::isnan(c[i]) ? std::nullopt : Bilinear(c[i], r[i]);
      bool ok = false;
      const double undulation = h ? Undulation(lat[i], lon[i], &ok) : 0.0;
      lat[i] = (h && ok) ? *h + undulation : kNaN;
    }
  }
};

Dem::Dem(const std::string& path, const LocalFrame& frame, const DemOptions& options)
    : impl_(std::make_unique<Impl>(path, frame, options.vertical_datum)) {
  Impl& d = *impl_;
  internal::GdalDatasetPtr dataset = internal::OpenRaster(path);
  d.cols = dataset->GetRasterXSize();
  d.rows = dataset->GetRasterYSize();
  if (d.cols < 2 || d.rows < 2) {
    throw InputError(path, 0, "", "a DEM needs at least 2 x 2 cells to interpolate");
  }
  if (!options.window_enu) {
    internal::RequireRasterFits(*dataset, options.max_cells, sizeof(float), "DemOptions::max_cells",
                                path);
  } else if (options.max_cells < 1) {
    throw std::invalid_argument("DemOptions::max_cells must be at least 1");
  }
  if (dataset->GetGeoTransform(d.gt) != CE_None) {
    throw InputError(path, 0, "geotransform", "the raster has no georeferencing (geotransform)");
  }
  if (!GDALInvGeoTransform(d.gt, d.inv_gt)) {
    throw InputError(path, 0, "geotransform", "the raster's geotransform is degenerate");
  }

  // CRS: the caller's override, else the raster's own.
  OGRSpatialReference crs;
  if (!options.crs.empty()) {
    crs = internal::ParseCrs(options.crs, path, "crs");
    d.crs_source = "override";
  } else {
    const OGRSpatialReference* own = dataset->GetSpatialRef();
    if (own == nullptr || own->IsEmpty()) {
      throw InputError(path, 0, "crs",
                       "the raster has no CRS and none was given; give one (\"EPSG:32633\", "
                       "WKT, a PROJ string or a .prj / .wkt file) as " +
                           options.crs_given_as);
    }
    crs = internal::NormaliseCrs(*own, path);
    d.crs_source = "file";
  }
  d.crs_wkt = internal::CrsWkt(crs);
  d.transform = std::make_unique<internal::CrsToWgs84>(crs, path);

  // The window: the cells under the box's outline (64 points a side, at the origin's height) and
  // two more around them, clipped to the raster; from here on the raster is that window.
  int c0 = 0, r0 = 0;
  if (options.window_enu) {
    const Eigen::AlignedBox2d& box = *options.window_enu;
    if (box.isEmpty() || !box.min().allFinite() || !box.max().allFinite()) {
      throw std::invalid_argument("DemOptions::window_enu must be a finite, non-empty box");
    }
    constexpr int kSteps = 64;
    // Corners counter-clockwise: bottom left, bottom right, top right, top left.
    constexpr Eigen::AlignedBox2d::CornerType kCorners[5] = {
        Eigen::AlignedBox2d::BottomLeft, Eigen::AlignedBox2d::BottomRight,
        Eigen::AlignedBox2d::TopRight, Eigen::AlignedBox2d::TopLeft,
        Eigen::AlignedBox2d::BottomLeft};
    std::vector<double> lon, lat;
    for (int side = 0; side < 4; ++side) {
      const Eigen::Vector2d a = box.corner(kCorners[side]);
      const Eigen::Vector2d b = box.corner(kCorners[side + 1]);
      for (int k = 0; k < kSteps; ++k) {
        const double t = static_cast<double>(k) / kSteps;
        const Eigen::Vector2d p = a + t * (b - a);
        const Eigen::Vector3d llh =
            d.frame.ToGeodetic(Eigen::Vector3d(p.x(), p.y(), d.frame.origin().height_m));
        lat.push_back(llh.x());
        lon.push_back(llh.y());
      }
    }
    std::vector<double> c = lon, r = lat;
    d.LonLatToCell(c.data(), r.data(), static_cast<int>(c.size()));
    double c_lo = std::numeric_limits<double>::infinity(), r_lo = c_lo, c_hi = -c_lo, r_hi = -c_lo;
    for (size_t i = 0; i < c.size(); ++i) {
      if (!std::isfinite(c[i]) || !std::isfinite(r[i])) continue;
      c_lo = std::min(c_lo, c[i]);
      c_hi = std::max(c_hi, c[i]);
      r_lo = std::min(r_lo, r[i]);
      r_hi = std::max(r_hi, r[i]);
    }
    const auto cell = [](double x, double add, int n) {
      return static_cast<int>(std::clamp(x + add, 0.0, static_cast<double>(n - 1)));
    };
    const bool placed = c_lo <= c_hi && r_lo <= r_hi;
    c0 = placed ? cell(std::floor(c_lo), -2.0, d.cols) : 0;
    r0 = placed ? cell(std::floor(r_lo), -2.0, d.rows) : 0;
    const int c1 = placed ? cell(std::ceil(c_hi), 2.0, d.cols) : -1;
    const int r1 = placed ? cell(std::ceil(r_hi), 2.0, d.rows) : -1;
    const bool misses = !placed || c_hi < -0.5 || r_hi < -0.5 || c_lo > d.cols - 0.5 ||
                        r_lo > d.rows - 0.5 || c1 - c0 < 1 || r1 - r0 < 1;
    if (misses) {
      char area[160];
      std::snprintf(area, sizeof(area), "ENU x %.0f to %.0f m, y %.0f to %.0f m", box.min().x(),
                    box.max().x(), box.min().y(), box.max().y());
      throw InputError(path, 0, "coverage",
                       std::string("the raster does not reach the area used (") + area + ")");
    }
    const int w = c1 - c0 + 1, h = r1 - r0 + 1;
    if (std::int64_t{w} * h > options.max_cells) {
      throw InputError(path, 0, "size",
                       "the window of the raster under the area used (" + std::to_string(w) +
                           " x " + std::to_string(h) + " cells from column " + std::to_string(c0) +
                           ", row " + std::to_string(r0) +
                           ") is more than DemOptions::max_cells (" +
                           std::to_string(options.max_cells) + ")");
    }
    // The window's geotransform: its first cell is the raster's (c0, r0).
    d.gt[0] += c0 * d.gt[1] + r0 * d.gt[2];
    d.gt[3] += c0 * d.gt[4] + r0 * d.gt[5];
    GDALInvGeoTransform(d.gt, d.inv_gt);
    d.cols = w;
    d.rows = h;
  }

  // Heights: raw * scale + offset, in the band's unit, converted to metres; voids to NaN.
  GDALRasterBand* band = dataset->GetRasterBand(1);
  double unit_m = 1.0;
  if (options.height_unit_m) {
    unit_m = *options.height_unit_m;
    if (!(unit_m > 0.0)) throw InputError(path, 0, "height_unit", "height_unit_m must be > 0");
  } else {
    const std::string unit = band->GetUnitType() != nullptr ? band->GetUnitType() : "";
    unit_m = internal::HeightUnitToMetres(unit);
    if (unit_m == 0.0) {
      throw InputError(path, 0, "height_unit",
                       "unknown height unit '" + unit + "'; give DemOptions::height_unit_m");
    }
  }
  int has = 0;
  double scale = band->GetScale(&has);
  if (!has) scale = 1.0;
  double offset = band->GetOffset(&has);
  if (!has) offset = 0.0;
  int has_nodata = 0;
  const double nodata = band->GetNoDataValue(&has_nodata);
  const bool int16 = band->GetRasterDataType() == GDT_Int16;

  d.height_m.resize(static_cast<size_t>(d.cols) * d.rows);
  {
    internal::QuietGdalErrors quiet;
    if (band->RasterIO(GF_Read, c0, r0, d.cols, d.rows, d.height_m.data(), d.cols, d.rows,
                       GDT_Float32, 0, 0, nullptr) != CE_None) {
      throw InputError(path, 0, "",
                       "cannot read the raster's cells (truncated or corrupt?)" +
                           internal::QuietGdalErrors::LastMessage());
    }
  }
  const auto is_nodata = [&](float raw) {
    return std::isnan(raw) || (has_nodata && raw == static_cast<float>(nodata)) ||
           (options.nodata && raw == static_cast<float>(*options.nodata)) ||
           (int16 && raw == -32768.0f);
  };
  for (int r = 0; r < d.rows; ++r) {
    for (int c = 0; c < d.cols; ++c) {
      float& v = d.height_m[static_cast<size_t>(r) * d.cols + c];
      if (is_nodata(v)) {
        v = std::numeric_limits<float>::quiet_NaN();
        ++d.voids;
        continue;
      }
      const double h = (v * scale + offset) * unit_m;
      if (!(h >= kMinPlausibleHeightM && h <= kMaxPlausibleHeightM) || IsCommonVoidMarker(v)) {
        throw InputError(path, 0, "nodata",
                         Format("cell (col %.0f, row %.0f) holds %.6g, not a terrain height: an "
                                "undeclared nodata value? give DemOptions::nodata",
                                c + c0, r + r0, static_cast<double>(v)));
      }
      v = static_cast<float>(h);
    }
  }
  d.void_prefix.assign(static_cast<size_t>(d.rows + 1) * (d.cols + 1), 0);
  for (int r = 0; r < d.rows; ++r) {
    int row_sum = 0;
    for (int c = 0; c < d.cols; ++c) {
      row_sum += std::isnan(d.Cell(c, r)) ? 1 : 0;
      d.void_prefix[static_cast<size_t>(r + 1) * (d.cols + 1) + c + 1] =
          d.void_prefix[static_cast<size_t>(r) * (d.cols + 1) + c + 1] + row_sum;
    }
  }

  if (d.datum == VerticalDatum::kEgm96) {
    try {
      d.geoid.emplace(options.geoid_path);
    } catch (const InputError& e) {
      throw InputError(path, 0, "geoid_path",
                       std::string("EGM96 heights need the geoid grid: ") + e.what());
    }
  }

  // Footprint: the outline of the rectangle of cell centres, 64 steps per side.
  constexpr int kSteps = 64;
  std::vector<double> oc;
  std::vector<double> orow;
  for (int side = 0; side < 4; ++side) {
    for (int k = 0; k < kSteps; ++k) {
      const double t = static_cast<double>(k) / kSteps;
      const double w = d.cols - 1.0;
      const double h = d.rows - 1.0;
      const double c[4] = {t * w, w, (1 - t) * w, 0.0};
      const double r[4] = {0.0, t * h, h, (1 - t) * h};
      oc.push_back(c[side]);
      orow.push_back(r[side]);
    }
  }
  d.CellToLonLat(oc.data(), orow.data(), static_cast<int>(oc.size()));
  d.geo_box = {std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
               std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity()};
  for (size_t i = 0; i < oc.size(); ++i) {
    if (std::isnan(oc[i])) {
      throw InputError(path, 0, "crs", "the raster's corners cannot be placed on WGS84");
    }
    d.geo_box.lon_min_deg = std::min(d.geo_box.lon_min_deg, oc[i]);
    d.geo_box.lon_max_deg = std::max(d.geo_box.lon_max_deg, oc[i]);
    d.geo_box.lat_min_deg = std::min(d.geo_box.lat_min_deg, orow[i]);
    d.geo_box.lat_max_deg = std::max(d.geo_box.lat_max_deg, orow[i]);
    d.enu_box.extend(d.frame.ToEnu(orow[i], oc[i], d.frame.origin().height_m).head<2>().eval());
  }

  // Cell size on the ellipsoid (h = 0) at the raster's centre.
  const double cc = 0.5 * (d.cols - 1);
  const double rc = 0.5 * (d.rows - 1);
  double c3[3] = {cc, cc + 1, cc};
  double r3[3] = {rc, rc, rc + 1};
  d.CellToLonLat(c3, r3, 3);
  const Eigen::Vector3d p0 = d.frame.ToEnu(r3[0], c3[0], 0.0);
  d.cell_size_m = {(d.frame.ToEnu(r3[1], c3[1], 0.0) - p0).norm(),
                   (d.frame.ToEnu(r3[2], c3[2], 0.0) - p0).norm()};
}

Dem::~Dem() = default;
Dem::Dem(Dem&&) noexcept = default;
Dem& Dem::operator=(Dem&&) noexcept = default;

std::optional<double> Dem::RasterHeight(double lat_deg, double lon_deg) const {
  double c = lon_deg;
  double r = lat_deg;
  impl_->LonLatToCell(&c, &r, 1);
  if (std::isnan(c)) return std::nullopt;
  return impl_->Bilinear(c, r);
}

std::optional<double> Dem::GeoidUndulation(double lat_deg, double lon_deg) const {
  bool ok = false;
  const double n = impl_->Undulation(lat_deg, lon_deg, &ok);
  if (!ok) return std::nullopt;
  return n;
}

std::optional<double> Dem::EllipsoidalHeight(double lat_deg, double lon_deg) const {
  const std::optional<double> h = RasterHeight(lat_deg, lon_deg);
  if (!h) return std::nullopt;
  const std::optional<double> n = GeoidUndulation(lat_deg, lon_deg);
  if (!n) return std::nullopt;
  return *h + *n;
}

std::optional<double> Dem::HeightAt(const Eigen::Vector3d& p_w) const {
  const Eigen::Vector3d llh = impl_->frame.ToGeodetic(p_w);
  return EllipsoidalHeight(llh.x(), llh.y());
}

std::optional<double> Dem::Clearance(const Eigen::Vector3d& p_w) const {
  const Eigen::Vector3d llh = impl_->frame.ToGeodetic(p_w);
  const std::optional<double> terrain = EllipsoidalHeight(llh.x(), llh.y());
  if (!terrain) return std::nullopt;
  return llh.z() - *terrain;
}

EnuHeightGrid Dem::ResampleToEnu(const Eigen::AlignedBox2d& box_w, double spacing_m) const {
  if (!(spacing_m > 0.0)) throw std::invalid_argument("ResampleToEnu: spacing_m must be > 0");
  if (box_w.isEmpty()) throw std::invalid_argument("ResampleToEnu: empty box");
  const Eigen::Vector2d size = box_w.sizes();
  const double cols_d = std::floor(size.x() / spacing_m + 1e-9) + 1;
  const double rows_d = std::floor(size.y() / spacing_m + 1e-9) + 1;
  if (cols_d * rows_d > 2e8) {
    throw std::invalid_argument("ResampleToEnu: more than 2e8 nodes; use a coarser spacing");
  }
  EnuHeightGrid grid;
  grid.origin_w = box_w.min();
  grid.spacing_m = spacing_m;
  grid.cols = static_cast<int>(cols_d);
  grid.rows = static_cast<int>(rows_d);
  grid.up_m.assign(static_cast<size_t>(grid.cols) * grid.rows, kNaN);

  constexpr int kMaxSteps = 5;
  constexpr double kToleranceM = 1e-3;
  const int n = grid.cols;
  std::vector<double> z(n);
  std::vector<int> active;
  std::vector<double> lat;
  std::vector<double> lon;
  std::vector<double> h;
  for (int row = 0; row < grid.rows; ++row) {
    std::fill(z.begin(), z.end(), 0.0);
    active.resize(n);
    for (int col = 0; col < n; ++col) active[col] = col;
    for (int step = 0; step < kMaxSteps && !active.empty(); ++step) {
      const size_t m = active.size();
      lat.resize(m);
      lon.resize(m);
      h.resize(m);
      for (size_t k = 0; k < m; ++k) {
        const Eigen::Vector2d xy = grid.NodePosition(active[k], row);
        const Eigen::Vector3d llh = impl_->frame.ToGeodetic({xy.x(), xy.y(), z[active[k]]});
        lat[k] = llh.x();
        lon[k] = llh.y();
        h[k] = llh.z();
      }
      impl_->EllipsoidalHeights(lat, lon);  // lat[k] <- terrain height
      std::vector<int> still;
      for (size_t k = 0; k < m; ++k) {
        const int col = active[k];
        double& out = grid.up_m[static_cast<size_t>(row) * n + col];
        if (std::isnan(lat[k])) {
          out = kNaN;
          continue;
        }
        const double dz = lat[k] - h[k];
        z[col] += dz;
        out = z[col];
        if (std::abs(dz) >= kToleranceM) still.push_back(col);
      }
      active.swap(still);
    }
  }
  return grid;
}

void Dem::RequireCovers(const std::vector<Eigen::Vector3d>& track_w, double margin_m) const {
  const Impl& d = *impl_;
  if (track_w.empty()) return;
  margin_m = std::max(0.0, margin_m);
  // The point and, with a margin, 8 points around it on a circle of that radius.
  const int per_point = margin_m > 0.0 ? 9 : 1;
  std::vector<double> lon;
  std::vector<double> lat;
  lon.reserve(track_w.size() * per_point);
  lat.reserve(track_w.size() * per_point);
  for (const Eigen::Vector3d& p : track_w) {
    for (int k = 0; k < per_point; ++k) {
      Eigen::Vector3d q = p;
      if (k > 0) {
        const double a = (k - 1) * M_PI / 4.0;
        q += margin_m * Eigen::Vector3d(std::cos(a), std::sin(a), 0.0);
      }
      const Eigen::Vector3d llh = d.frame.ToGeodetic(q);
      lat.push_back(llh.x());
      lon.push_back(llh.y());
    }
  }
  d.LonLatToCell(lon.data(), lat.data(), static_cast<int>(lon.size()));

  struct Gap {
    size_t index = 0;
    double miss_m = 0.0;  // infinity when the point cannot be placed in the raster's CRS
    int voids = 0;
  };
  std::vector<Gap> gaps;
  for (size_t i = 0; i < track_w.size(); ++i) {
    double c_min = std::numeric_limits<double>::infinity();
    double c_max = -c_min;
    double r_min = c_min;
    double r_max = -c_min;
    bool placed = true;
    for (int k = 0; k < per_point; ++k) {
      const double c = lon[i * per_point + k];
      const double r = lat[i * per_point + k];
      if (std::isnan(c)) placed = false;
      c_min = std::min(c_min, c);
      c_max = std::max(c_max, c);
      r_min = std::min(r_min, r);
      r_max = std::max(r_max, r);
    }
    if (!placed) {
      gaps.push_back({i, std::numeric_limits<double>::infinity(), 0});
      continue;
    }
    const double over_c = std::max({0.0, -c_min, c_max - (d.cols - 1)});
    const double over_r = std::max({0.0, -r_min, r_max - (d.rows - 1)});
    if (over_c > kEdgeSlack || over_r > kEdgeSlack) {
      gaps.push_back({i, std::hypot(over_c * d.cell_size_m.x(), over_r * d.cell_size_m.y()), 0});
      continue;
    }
    const int voids =
        d.VoidsIn(static_cast<int>(std::floor(c_min)), static_cast<int>(std::floor(r_min)),
                  static_cast<int>(std::ceil(c_max)), static_cast<int>(std::ceil(r_max)));
    if (voids > 0) gaps.push_back({i, 0.0, voids});
  }
  if (gaps.empty()) return;

  const auto describe = [&](const Gap& g) {
    const Eigen::Vector3d& p = track_w[g.index];
    std::string s = "index " + std::to_string(g.index) + " at ENU " +
                    Format("(%.1f, %.1f, %.1f) m", p.x(), p.y(), p.z());
    if (std::isinf(g.miss_m)) return s + " cannot be placed in the DEM's CRS";
    if (g.voids > 0) {
      return s + " has " + std::to_string(g.voids) + " void cell(s) within " +
             Format("%.1f m", margin_m, 0, 0);
    }
    return s + " misses the DEM by " + Format("%.1f m", g.miss_m, 0, 0);
  };
  const Gap* largest = &gaps.front();
  for (const Gap& g : gaps) {
    if (g.miss_m > largest->miss_m) largest = &g;
  }
  std::string message = "the DEM does not cover the track (margin " +
                        Format("%.1f m", margin_m, 0, 0) + "): " + std::to_string(gaps.size()) +
                        " of " + std::to_string(track_w.size()) +
                        " points fail; first: " + describe(gaps.front());
  if (largest != &gaps.front()) message += "; largest: " + describe(*largest);
  message += Format("; DEM valid area lat %.5f..%.5f, lon %.5f..", d.geo_box.lat_min_deg,
                    d.geo_box.lat_max_deg, d.geo_box.lon_min_deg) +
             Format("%.5f deg", d.geo_box.lon_max_deg, 0, 0);
  throw InputError(d.path, 0, "coverage", message);
}

const std::string& Dem::path() const { return impl_->path; }
VerticalDatum Dem::vertical_datum() const { return impl_->datum; }
const std::string& Dem::crs_wkt() const { return impl_->crs_wkt; }
const std::string& Dem::crs_source() const { return impl_->crs_source; }
int Dem::cols() const { return impl_->cols; }
int Dem::rows() const { return impl_->rows; }
Eigen::Vector2d Dem::cell_size_crs() const {
  return {std::hypot(impl_->gt[1], impl_->gt[4]), std::hypot(impl_->gt[2], impl_->gt[5])};
}
Eigen::Vector2d Dem::cell_size_m() const { return impl_->cell_size_m; }
const GeoBox& Dem::footprint_geodetic() const { return impl_->geo_box; }
const Eigen::AlignedBox2d& Dem::footprint_enu() const { return impl_->enu_box; }
int Dem::void_count() const { return impl_->voids; }
const LocalFrame& Dem::frame() const { return impl_->frame; }

std::vector<Eigen::Vector2d> Dem::VoidCellCentres() const {
  const Impl& d = *impl_;
  std::vector<double> c;
  std::vector<double> r;
  for (int row = 0; row < d.rows; ++row) {
    for (int col = 0; col < d.cols; ++col) {
      if (std::isnan(d.Cell(col, row))) {
        c.push_back(col);
        r.push_back(row);
      }
    }
  }
  d.CellToLonLat(c.data(), r.data(), static_cast<int>(c.size()));
  std::vector<Eigen::Vector2d> out;
  for (size_t i = 0; i < c.size(); ++i) out.emplace_back(r[i], c[i]);
  return out;
}

}  // namespace skerry::geo
