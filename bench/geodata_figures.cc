/// \file
/// The geodata layer's figures on the real files of ../shared/data, printed as one Markdown
/// table: DEM heights against surveyed ground control points (Engabreen) and published summit
/// and lake heights (SRTM, orthometric and ellipsoidal with the EGM96 undulation, checked
/// against PROJ's), GeoTIFF vs .hgt agreement, SRTM voids, the Autzen orthophoto's pixel <-> ENU
/// round trip and ground sample distance, and the Autzen LAS cloud (count, bounds, extent
/// against the orthophoto, read time).
///
/// Usage: skerry_geodata_figures [DATA_DIR]   (default ../shared/data)

#include <gdal_utils.h>
#include <ogr_spatialref.h>
#include <unistd.h>

#include <GeographicLib/UTMUPS.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "skerry/core/geodesy.h"
#include "skerry/core/input_error.h"
#include "skerry/geo/dem.h"
#include "skerry/geo/las_reader.h"
#include "skerry/geo/orthophoto.h"
#include "skerry/geo/point_cloud.h"

namespace skerry::bench {
namespace {

namespace fs = std::filesystem;
using geo::Dem;
using geo::DemOptions;
using geo::VerticalDatum;

struct Row {
  std::string figure;
  std::string measured;
  std::string reference;
};

std::string Fmt(const char* fmt, double v) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), fmt, v);
  return buf;
}

double Median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// EGM96 undulation as PROJ computes it (WGS84 3-D -> WGS84 + EGM96 height, through PROJ's own
// reading of egm96_15.gtx): an independent check of skerry's bilinear lookup.
std::optional<double> ProjUndulation(double lat_deg, double lon_deg) {
  OGRSpatialReference from;
  OGRSpatialReference to;
  if (from.importFromEPSG(4979) != OGRERR_NONE) return std::nullopt;
  if (to.SetFromUserInput("EPSG:4326+5773") != OGRERR_NONE) return std::nullopt;
  from.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  to.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  std::unique_ptr<OGRCoordinateTransformation> t(OGRCreateCoordinateTransformation(&from, &to));
  if (!t) return std::nullopt;
  double x = lon_deg;
  double y = lat_deg;
  double z = 0.0;
  if (!t->Transform(1, &x, &y, &z)) return std::nullopt;
  return -z;  // H = h - N with h = 0
}

void Engabreen(const std::string& data, std::vector<Row>& rows) {
  const std::string dir = data + "/engabreen";
  // Camera centre (data README): E 446722.0, N 7396671.0 (UTM 33N), h 770 m.
  double lat0 = 0.0;
  double lon0 = 0.0;
  GeographicLib::UTMUPS::Reverse(33, true, 446722.0, 7396671.0, lat0, lon0);
  DemOptions options(VerticalDatum::kEgm96);
  options.crs = "EPSG:32633";
  const Dem dem(dir + "/engabreen_dem_3m_utm33n.asc", LocalFrame({lat0, lon0, 770.0}), options);
  std::ifstream in(dir + "/gcp8902.txt");
  std::vector<double> diff;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '%') continue;
    std::istringstream fields(line);
    double x = 0.0;
    double y = 0.0;
    double z = 0.0;
    if (!(fields >> x >> y >> z)) continue;  // u, v (pixel sums like 1951+9) are not needed
    double lat = 0.0;
    double lon = 0.0;
    GeographicLib::UTMUPS::Reverse(33, true, x, y, lat, lon);
    const std::optional<double> h = dem.RasterHeight(lat, lon);
    if (h) diff.push_back(std::abs(*h - z));
  }
  if (diff.empty()) throw std::runtime_error(dir + "/gcp8902.txt: no ground control points read");
  rows.push_back({"Engabreen: GCPs inside the 3 m DEM", std::to_string(diff.size()) + " of 28",
                  "gcp8902.txt"});
  rows.push_back({"Engabreen: median \\|DEM − GCP Z\\| (m)", Fmt("%.2f", Median(diff)), "-"});
  rows.push_back({"Engabreen: max \\|DEM − GCP Z\\| (m)",
                  Fmt("%.2f", *std::max_element(diff.begin(), diff.end())), "-"});
  rows.push_back({"Engabreen: EGM96 N at the camera (m)",
                  Fmt("%.2f", dem.GeoidUndulation(lat0, lon0).value_or(NAN)),
                  "PROJ " + Fmt("%.2f", ProjUndulation(lat0, lon0).value_or(NAN))});
}

void Santis(const std::string& data, std::vector<Row>& rows) {
  const Dem dem(data + "/dem/N47E009.hgt", LocalFrame({47.6, 9.4, 440.0}),
                DemOptions(VerticalDatum::kEgm96));
  const double lat = 47.2493;
  const double lon = 9.3434;
  // Highest cell centre within 300 m of the summit: centres lie on whole 3" steps.
  const LocalFrame at_summit({lat, lon, 0.0});
  double best = -1e9;
  double best_lat = 0.0;
  double best_lon = 0.0;
  const double step = 1.0 / 1200.0;
  for (int i = -10; i <= 10; ++i) {
    for (int j = -10; j <= 10; ++j) {
      const double la = std::round(lat / step) * step + i * step;
      const double lo = std::round(lon / step) * step + j * step;
      if (at_summit.ToEnu(la, lo, 0.0).head<2>().norm() > 300.0) continue;
      const std::optional<double> h = dem.RasterHeight(la, lo);
      if (h && *h > best) {
        best = *h;
        best_lat = la;
        best_lon = lo;
      }
    }
  }
  const double summit = dem.RasterHeight(lat, lon).value_or(NAN);
  const double n = dem.GeoidUndulation(lat, lon).value_or(NAN);
  rows.push_back({"Säntis 47.2493 N 9.3434 E: SRTM orthometric, bilinear (m)", Fmt("%.1f", summit),
                  "published 2502"});
  rows.push_back({"Säntis: highest SRTM cell within 300 m (m)",
                  Fmt("%.0f", best) + Fmt(" at %.5f N", best_lat) + Fmt(" %.5f E", best_lon),
                  "published 2502 (3\" cells smooth the peak)"});
  rows.push_back({"Säntis: EGM96 undulation N (m)", Fmt("%.3f", n),
                  "PROJ " + Fmt("%.3f", ProjUndulation(lat, lon).value_or(NAN))});
  rows.push_back({"Säntis: ellipsoidal height, bilinear (m)",
                  Fmt("%.1f", dem.EllipsoidalHeight(lat, lon).value_or(NAN)), "orthometric + N"});

  const double lake_lat = 47.60;
  const double lake_lon = 9.40;
  rows.push_back({"Lake Constance 47.60 N 9.40 E: SRTM orthometric (m)",
                  Fmt("%.1f", dem.RasterHeight(lake_lat, lake_lon).value_or(NAN)),
                  "mean level ≈ 395"});
  rows.push_back({"Lake Constance: EGM96 N (m)",
                  Fmt("%.3f", dem.GeoidUndulation(lake_lat, lake_lon).value_or(NAN)),
                  "PROJ " + Fmt("%.3f", ProjUndulation(lake_lat, lake_lon).value_or(NAN))});
  rows.push_back({"Lake Constance: ellipsoidal (m)",
                  Fmt("%.1f", dem.EllipsoidalHeight(lake_lat, lake_lon).value_or(NAN)),
                  "orthometric + N"});

  // Earth curvature in the ENU grid: the lake 30 km from an origin on its surface.
  const double h_a = dem.EllipsoidalHeight(lake_lat, lake_lon).value_or(NAN);
  const LocalFrame on_lake({lake_lat, lake_lon, h_a});
  const Dem lake(data + "/dem/N47E009.hgt", on_lake, DemOptions(VerticalDatum::kEgm96));
  const double lat_b = 47.78;
  const double lon_b = 9.10;
  const double h_b = lake.EllipsoidalHeight(lat_b, lon_b).value_or(NAN);
  const Eigen::Vector2d b = on_lake.ToEnu(lat_b, lon_b, h_b).head<2>();
  const geo::EnuHeightGrid grid = lake.ResampleToEnu(Eigen::AlignedBox2d(b, b), 10.0);
  // Euler's radius of curvature along B's azimuth at the mid-latitude.
  const double phi = 0.5 * (lake_lat + lat_b) * M_PI / 180;
  const double w = 1 - 6.69437999014e-3 * std::pow(std::sin(phi), 2);
  const double m = 6378137.0 * (1 - 6.69437999014e-3) / std::pow(w, 1.5);
  const double nu = 6378137.0 / std::sqrt(w);
  const double azimuth = std::atan2(b.x(), b.y());
  const double r = 1 / (std::pow(std::cos(azimuth), 2) / m + std::pow(std::sin(azimuth), 2) / nu);
  const double expected = (h_b - h_a) - b.squaredNorm() / (2 * r);
  rows.push_back({"ResampleToEnu: lake surface " + Fmt("%.1f km", b.norm() / 1000) +
                      " from an origin on the lake, ENU z (m)",
                  Fmt("%.2f", grid.at(0, 0)), Fmt("(h_b − h_a) − d²/2R = %.2f", expected)});
}

void GeoTiffVsHgt(const std::string& data, std::vector<Row>& rows) {
  const std::string hgt = data + "/dem/N43E007.hgt";
  const fs::path tmp =
      fs::temp_directory_path() / ("skerry_geodata_figures_" + std::to_string(::getpid()));
  fs::create_directories(tmp);
  const std::string tif = (tmp / "N43E007.tif").string();
  GDALAllRegister();
  GDALDatasetH src = GDALOpen(hgt.c_str(), GA_ReadOnly);
  char* argv[] = {const_cast<char*>("-of"), const_cast<char*>("GTiff"), nullptr};
  GDALTranslateOptions* opts = GDALTranslateOptionsNew(argv, nullptr);
  int usage_error = 0;
  GDALDatasetH out = GDALTranslate(tif.c_str(), src, opts, &usage_error);
  GDALTranslateOptionsFree(opts);
  if (out != nullptr) GDALClose(out);
  if (src != nullptr) GDALClose(src);

  const LocalFrame frame({43.7, 7.3, 50.0});
  const Dem from_hgt(hgt, frame, DemOptions(VerticalDatum::kEgm96));
  const Dem from_tif(tif, frame, DemOptions(VerticalDatum::kEgm96));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  double max_diff = 0.0;
  int compared = 0;
  int both_missing = 0;
  int one_missing = 0;
  for (int k = 0; k < 20000; ++k) {
    const double lat = 43.0 + u01(rng);
    const double lon = 7.0 + u01(rng);
    const std::optional<double> a = from_hgt.EllipsoidalHeight(lat, lon);
    const std::optional<double> b = from_tif.EllipsoidalHeight(lat, lon);
    if (a && b) {
      max_diff = std::max(max_diff, std::abs(*a - *b));
      ++compared;
    } else if (!a && !b) {
      ++both_missing;
    } else {
      ++one_missing;
    }
  }
  rows.push_back(
      {"N43E007: .hgt vs gdal_translate GeoTIFF, max \\|Δh\\| over " + std::to_string(compared) +
           " random points (m)",
       Fmt("%.3g", max_diff) + " (" + std::to_string(one_missing) + " missing in one only)", "0"});

  // The shared meridian 7 E: the last column of N43E006.tiff and the first of N43E007.hgt.
  const Dem west(data + "/dem/N43E006.tiff", frame, DemOptions(VerticalDatum::kEgm96));
  double edge_max = 0.0;
  int edge_n = 0;
  int edge_same = 0;
  for (int k = 0; k <= 1200; ++k) {
    const double lat = 43.0 + k / 1200.0;
    const std::optional<double> a = west.RasterHeight(lat, 7.0);
    const std::optional<double> b = from_hgt.RasterHeight(lat, 7.0);
    if (a && b) {
      edge_max = std::max(edge_max, std::abs(*a - *b));
      edge_same += std::abs(*a - *b) < 1e-3;
      ++edge_n;
    }
  }
  rows.push_back({"N43E006.tiff vs N43E007.hgt on their shared 7° E column",
                  std::to_string(edge_same) + " of " + std::to_string(edge_n) +
                      " cells equal, max \\|Δh\\| " + Fmt("%.0f m", edge_max),
                  "not equal: the two tiles come from different SRTM releases"});

  std::string voids;
  for (const Eigen::Vector2d& c : from_hgt.VoidCellCentres()) {
    voids += (voids.empty() ? "" : ", ") + Fmt("%.5f N", c.x()) + Fmt(" %.5f E", c.y());
    voids += from_hgt.RasterHeight(c.x(), c.y()) ? " (read!)" : " (missing)";
  }
  rows.push_back({"N43E007.hgt void cells (−32768)",
                  std::to_string(from_hgt.void_count()) + ": " + voids, "4 (data README)"});
  fs::remove_all(tmp);
}

void Autzen(const std::string& data, std::vector<Row>& rows) {
  const std::string dir = data + "/autzen";
  // A first load fixes the image centre, the second uses it as the ENU origin.
  const geo::Orthophoto rough(dir + "/autzen.jpg", LocalFrame({44.05, -123.07, 100.0}));
  const Eigen::Vector3d centre_llh = rough.frame().ToGeodetic(
      rough.PixelToEnu(0.5 * (rough.width() - 1), 0.5 * (rough.height() - 1), 100.0));
  const LocalFrame frame({centre_llh.x(), centre_llh.y(), 100.0});
  const geo::Orthophoto ortho(dir + "/autzen.jpg", frame);

  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.5, ortho.width() - 0.5);
  std::uniform_real_distribution<double> v(-0.5, ortho.height() - 0.5);
  double max_err = 0.0;
  for (int k = 0; k < 10000; ++k) {
    const double uu = u(rng);
    const double vv = v(rng);
    const Eigen::Vector2d back = ortho.EnuToPixel(ortho.PixelToEnu(uu, vv, 120.0));
    max_err = std::max(max_err, (back - Eigen::Vector2d(uu, vv)).norm());
  }
  rows.push_back({"Autzen orthophoto: pixel → ENU → pixel, max error over 10,000 pixels (px)",
                  Fmt("%.2e", max_err), "< 1e-3"});
  rows.push_back({"Autzen orthophoto: ground sample distance on the ellipsoid (m)",
                  Fmt("%.6f", ortho.ground_sample_distance_m()) + " (x " +
                      Fmt("%.6f", ortho.gsd_m().x()) + ", y " + Fmt("%.6f", ortho.gsd_m().y()) +
                      ")",
                  "1 ft = 0.3048 / k, Lambert scale k < 1 between 43 and 45.5 N"});
  const Eigen::Vector3d up = ortho.PixelToEnu(1623.5, 2092.0) - ortho.PixelToEnu(1623.5, 2292.0);
  rows.push_back({"Autzen orthophoto: image up vs true north (deg)",
                  Fmt("%.3f", std::atan2(up.x(), up.y()) * 180 / M_PI),
                  "Lambert convergence n (λ − λ0), λ0 = −120.5"});

  const std::string las_path = dir + "/autzen_trim.las";
  std::vector<double> times;
  geo::LasFile las;
  for (int run = 0; run < 5; ++run) {
    const auto t0 = std::chrono::steady_clock::now();
    las = geo::ReadLas(las_path);
    times.push_back(Seconds(t0));
  }
  const geo::LasHeader& h = las.header;
  rows.push_back({"Autzen LAS: header count / points read",
                  std::to_string(h.point_count) + " / " + std::to_string(las.cloud.points.size()),
                  "110,000"});
  const double bound_diff = std::max((las.read_min - h.min).cwiseAbs().maxCoeff(),
                                     (las.read_max - h.max).cwiseAbs().maxCoeff());
  rows.push_back({"Autzen LAS: max \\|read bounds − header bounds\\| (ft)", Fmt("%.3g", bound_diff),
                  "≤ scale " + Fmt("%.2f", h.scale.x())});
  rows.push_back({"Autzen LAS: CRS", las.cloud.crs_note.substr(0, 80), "-"});
  rows.push_back({"Autzen LAS: ReadLas time, median of 5 (ms)", Fmt("%.1f", 1e3 * Median(times)),
                  std::to_string(las.cloud.points.size()) + " points, 3.7 MB, file in page cache"});

  const auto t0 = std::chrono::steady_clock::now();
  const geo::PointCloud enu =
      geo::PointCloudToEnu(las.cloud, frame, geo::CloudToEnuOptions(VerticalDatum::kEgm96));
  const double to_enu_s = Seconds(t0);
  Eigen::AlignedBox2d box;
  int outside = 0;
  double overshoot_px = 0.0;
  for (const Eigen::Vector3d& p : enu.points) {
    box.extend(p.head<2>().eval());
    if (!ortho.Covers(p)) {
      ++outside;
      overshoot_px = std::max(overshoot_px, ortho.EnuToPixel(p).y() - (ortho.height() - 0.5));
    }
  }
  const Eigen::AlignedBox2d& fp = ortho.footprint_box_enu();
  const double margin = std::min({box.min().x() - fp.min().x(), box.min().y() - fp.min().y(),
                                  fp.max().x() - box.max().x(), fp.max().y() - box.max().y()});
  rows.push_back({"Autzen LAS: ENU extent (m)",
                  Fmt("x %.1f", box.min().x()) + Fmt("..%.1f", box.max().x()) +
                      Fmt(", y %.1f", box.min().y()) + Fmt("..%.1f", box.max().y()),
                  "orthophoto footprint x " + Fmt("%.1f", fp.min().x()) +
                      Fmt("..%.1f", fp.max().x()) + Fmt(", y %.1f", fp.min().y()) +
                      Fmt("..%.1f", fp.max().y())});
  rows.push_back(
      {"Autzen LAS: ENU box inside the orthophoto footprint's ENU box, smallest margin (m)",
       Fmt("%.1f", margin), "> 0"});
  rows.push_back({"Autzen LAS: points off the orthophoto, and how far past its south edge (ft)",
                  std::to_string(outside) + " of " + std::to_string(enu.points.size()) +
                      Fmt(", %.3f", overshoot_px),
                  Fmt("header min y is %.3f ft south of the image edge",
                      853362.1430851521 + 0.5 - ortho.height() - h.min.y())});
  rows.push_back({"Autzen LAS: PointCloudToEnu time (ms)", Fmt("%.1f", 1e3 * to_enu_s), "-"});
}

int Main(int argc, char** argv) {
  const std::string data = argc > 1 ? argv[1] : "../shared/data";
  if (argc > 2 || (argc == 2 && (std::string(argv[1]) == "--help" || argv[1][0] == '-'))) {
    std::printf("usage: skerry_geodata_figures [DATA_DIR]   (default ../shared/data)\n");
    return argc == 2 && std::string(argv[1]) == "--help" ? 0 : 2;
  }
  std::vector<Row> rows;
  Engabreen(data, rows);
  Santis(data, rows);
  GeoTiffVsHgt(data, rows);
  Autzen(data, rows);
  std::printf("| figure | measured | reference |\n|---|---|---|\n");
  for (const Row& r : rows) {
    std::printf("| %s | %s | %s |\n", r.figure.c_str(), r.measured.c_str(), r.reference.c_str());
  }
  return 0;
}

}  // namespace
}  // namespace skerry::bench

int main(int argc, char** argv) {
  try {
    return skerry::bench::Main(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "skerry_geodata_figures: %s\n", e.what());
    return 1;
  }
}
