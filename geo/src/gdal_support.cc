#include "gdal_support.h"

#include <cpl_error.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "skerry/core/input_error.h"

namespace skerry::geo::internal {

void EnsureGdalRegistered() {
  static std::once_flag once;
  std::call_once(once, [] { GDALAllRegister(); });
}

QuietGdalErrors::QuietGdalErrors() {
  CPLPushErrorHandler(CPLQuietErrorHandler);
  CPLErrorReset();
}

QuietGdalErrors::~QuietGdalErrors() { CPLPopErrorHandler(); }

std::string QuietGdalErrors::LastMessage() {
  const char* message = CPLGetLastErrorMsg();
  if (message == nullptr || *message == '\0') return "";
  return std::string(": ") + message;
}

GdalDatasetPtr OpenRaster(const std::string& path) {
  EnsureGdalRegistered();
  if (!std::filesystem::exists(path)) throw InputError(path, 0, "", "no such file");
  QuietGdalErrors quiet;
  GdalDatasetPtr dataset(GDALDataset::FromHandle(
      GDALOpenEx(path.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr)));
  if (!dataset) {
    throw InputError(path, 0, "",
                     "GDAL cannot open it as a raster" + QuietGdalErrors::LastMessage());
  }
  if (dataset->GetRasterCount() < 1 || dataset->GetRasterXSize() < 1 ||
      dataset->GetRasterYSize() < 1) {
    throw InputError(path, 0, "", "the raster has no bands or no pixels");
  }
  return dataset;
}

void RequireRasterFits(GDALDataset& dataset,
                       std::int64_t max_pixels,
                       int bytes_per_pixel,
                       const std::string& limit_name,
                       const std::string& path,
                       const std::string& field) {
  if (max_pixels < 1) throw std::invalid_argument(limit_name + " must be at least 1");
  const int cols = dataset.GetRasterXSize();
  const int rows = dataset.GetRasterYSize();
  const std::int64_t pixels = std::int64_t{cols} * rows;
  if (pixels <= max_pixels) return;
  char size[160];
  std::snprintf(size, sizeof(size), "%d x %d = %lld cells (%.1f GiB in memory)", cols, rows,
                static_cast<long long>(pixels),
                static_cast<double>(pixels) * bytes_per_pixel / (1024.0 * 1024.0 * 1024.0));
  throw InputError(path, 0, field,
                   std::string("the raster declares ") + size + ", more than " + limit_name + " (" +
                       std::to_string(max_pixels) +
                       "); crop it to the area of the track (gdal_translate -projwin) or raise "
                       "the limit");
}

OGRSpatialReference ParseCrs(const std::string& text,
                             const std::string& file,
                             const std::string& field) {
  EnsureGdalRegistered();
  std::string definition = text;
  std::string origin = "'" + text + "'";
  std::error_code ec;
  // A path (an EPSG code or WKT text is never an existing file name).
  if (text.find('[') == std::string::npos && std::filesystem::is_regular_file(text, ec)) {
    std::ifstream in(text);
    std::ostringstream content;
    content << in.rdbuf();
    if (!in) throw InputError(file, 0, field, "cannot read the CRS file " + text);
    definition = content.str();
    origin = "the CRS file " + text;
  }
  // Leading/trailing blanks and line breaks are harmless in WKT but not in "EPSG:..." strings.
  const auto not_space = [](unsigned char c) { return !std::isspace(c); };
  definition.erase(definition.begin(),
                   std::find_if(definition.begin(), definition.end(), not_space));
  definition.erase(std::find_if(definition.rbegin(), definition.rend(), not_space).base(),
                   definition.end());
  if (definition.empty()) throw InputError(file, 0, field, "empty CRS " + origin);
  OGRSpatialReference crs;
  QuietGdalErrors quiet;
  if (crs.SetFromUserInput(definition.c_str()) != OGRERR_NONE || crs.IsEmpty()) {
    throw InputError(file, 0, field,
                     "cannot parse the CRS " + origin + QuietGdalErrors::LastMessage());
  }
  crs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  return crs;
}

OGRSpatialReference NormaliseCrs(const OGRSpatialReference& crs, const std::string& file) {
  if (crs.IsEmpty()) throw InputError(file, 0, "crs", "empty CRS");
  OGRSpatialReference out(crs);
  out.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  return out;
}

std::string CrsName(const OGRSpatialReference& crs) {
  std::string name = crs.GetName() != nullptr ? crs.GetName() : "unnamed CRS";
  const char* authority = crs.GetAuthorityName(nullptr);
  const char* code = crs.GetAuthorityCode(nullptr);
  if (authority != nullptr && code != nullptr) {
    name += std::string(" (") + authority + ":" + code + ")";
  }
  return name;
}

std::string CrsWkt(const OGRSpatialReference& crs) {
  char* wkt = nullptr;
  const char* const options[] = {"FORMAT=WKT2_2019", nullptr};
  crs.exportToWkt(&wkt, options);
  std::string out = wkt != nullptr ? wkt : "";
  CPLFree(wkt);
  return out;
}

double HeightUnitToMetres(const std::string& unit) {
  std::string u;
  for (char c : unit) u += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (u.empty() || u == "m" || u == "metre" || u == "meter" || u == "metres" || u == "meters") {
    return 1.0;
  }
  if (u == "ft" || u == "foot" || u == "feet" || u == "international foot") return 0.3048;
  if (u == "us survey foot" || u == "ftus" || u == "us-ft" || u == "us_survey_foot") {
    return 1200.0 / 3937.0;
  }
  if (u == "km" || u == "kilometre" || u == "kilometer") return 1000.0;
  if (u == "cm" || u == "centimetre" || u == "centimeter") return 0.01;
  if (u == "mm" || u == "millimetre" || u == "millimeter") return 0.001;
  return 0.0;
}

namespace {

int TransformInPlace(OGRCoordinateTransformation& t, double* x, double* y, int n) {
  if (n <= 0) return 0;
  std::vector<int> ok(static_cast<size_t>(n), 0);
  t.Transform(static_cast<size_t>(n), x, y, nullptr, nullptr, ok.data());
  int failed = 0;
  for (int i = 0; i < n; ++i) {
    if (!ok[i] || !std::isfinite(x[i]) || !std::isfinite(y[i])) {
      x[i] = y[i] = std::numeric_limits<double>::quiet_NaN();
      ++failed;
    }
  }
  return failed;
}

}  // namespace

CrsToWgs84::CrsToWgs84(const OGRSpatialReference& crs, const std::string& file) {
  EnsureGdalRegistered();
  OGRSpatialReference source = NormaliseCrs(crs, file);
  OGRSpatialReference wgs84;
  wgs84.importFromEPSG(4326);
  wgs84.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  is_geographic_ = source.IsGeographic() != 0;
  QuietGdalErrors quiet;
  to_wgs84_.reset(OGRCreateCoordinateTransformation(&source, &wgs84));
  if (to_wgs84_) from_wgs84_.reset(to_wgs84_->GetInverse());
  if (!to_wgs84_ || !from_wgs84_) {
    throw InputError(file, 0, "crs",
                     "PROJ finds no transformation from " + CrsName(source) + " to WGS84" +
                         QuietGdalErrors::LastMessage());
  }
}

int CrsToWgs84::ToLonLat(double* x, double* y, int n) const {
  std::lock_guard<std::mutex> lock(mutex_);
  QuietGdalErrors quiet;
  return TransformInPlace(*to_wgs84_, x, y, n);
}

int CrsToWgs84::FromLonLat(double* lon, double* lat, int n) const {
  std::lock_guard<std::mutex> lock(mutex_);
  QuietGdalErrors quiet;
  return TransformInPlace(*from_wgs84_, lon, lat, n);
}

}  // namespace skerry::geo::internal
