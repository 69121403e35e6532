#pragma once
// Helpers shared by the geo tests: scratch folders, file copies and patches, InputError checks,
// and PROJ's EGM96 undulation as a reference.

#include <gdal_priv.h>
#include <gdal_utils.h>
#include <gtest/gtest.h>
#include <ogr_spatialref.h>
#include <unistd.h>

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "skerry/core/input_error.h"

/// Skips the running test when a file of ../shared/data is missing.
#define SKERRY_SKIP_WITHOUT(path) \
  if (!std::filesystem::exists(path)) GTEST_SKIP() << (path) << " missing"

namespace skerry::geo::testing {

namespace fs = std::filesystem;

inline const std::string kData = SKERRY_SHARED_DATA_DIR;

/// A fresh, empty scratch folder unique to the running test (ctest runs tests in parallel).
inline std::string FreshDir(const std::string& name) {
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::string test = info == nullptr
                               ? "process-" + std::to_string(getpid()) + "/"
                               : std::string(info->test_suite_name()) + "." + info->name() + "/";
  const fs::path dir = fs::path(SKERRY_TEST_TMP_DIR) / (test + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

inline std::vector<std::uint8_t> ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(in), {});
}

inline void WriteBytes(const std::string& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

inline void WriteText(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
}

/// Copies `from` into `dir` under `name` (writable: the shared data is read-only).
inline std::string CopyTo(const std::string& from,
                          const std::string& dir,
                          const std::string& name) {
  const std::string to = (fs::path(dir) / name).string();
  WriteBytes(to, ReadBytes(from));
  return to;
}

template <typename T>
void Poke(std::vector<std::uint8_t>& bytes, size_t offset, T value) {
  std::memcpy(bytes.data() + offset, &value, sizeof(T));
}

/// Runs `f`, expects an InputError whose file is `file`, whose field is `field`, and whose
/// message contains every one of `facts` (and the file's name).
inline void ExpectInputError(const std::function<void()>& f,
                             const std::string& file,
                             const std::string& field,
                             const std::vector<std::string>& facts = {}) {
  try {
    f();
    ADD_FAILURE() << "no InputError thrown (expected " << file << ": " << field << ")";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_EQ(e.file(), file) << what;
    EXPECT_EQ(e.field(), field) << what;
    EXPECT_NE(what.find(fs::path(file).filename().string()), std::string::npos) << what;
    for (const std::string& fact : facts) {
      EXPECT_NE(what.find(fact), std::string::npos) << "'" << fact << "' missing in: " << what;
    }
  }
}

/// A GeoTIFF on EPSG:4326 (0.001 deg cells from 47.5 N 9.5 E) that declares `cols` x `rows`
/// pixels of `bands` bands but holds none of them (GDAL's SPARSE_OK: 1024 x 1024 tiles, none
/// written, so 10^10 pixels take 150 kB on disk; its tiles read as zeros). Returns `path`.
inline std::string MakeSparseGeoTiff(
    const std::string& path, int cols, int rows, int bands, GDALDataType type) {
  GDALAllRegister();
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  const char* options[] = {"SPARSE_OK=TRUE", "TILED=YES", "BLOCKXSIZE=1024", "BLOCKYSIZE=1024",
                           nullptr};
  std::unique_ptr<GDALDataset> ds(
      driver->Create(path.c_str(), cols, rows, bands, type, const_cast<char**>(options)));
  EXPECT_TRUE(ds) << path;
  if (!ds) return path;
  double gt[6] = {9.5, 0.001, 0.0, 47.5, 0.0, -0.001};
  ds->SetGeoTransform(gt);
  OGRSpatialReference wgs84;
  wgs84.importFromEPSG(4326);
  ds->SetSpatialRef(&wgs84);
  return path;
}

/// GDAL's gdal_translate from `from` into `to` with its command-line arguments (e.g. {"-of",
/// "GTiff", "-ot", "UInt16"}), through the library (GDALTranslate). Returns whether it wrote `to`;
/// a failure is also reported to the running test.
inline bool GdalTranslate(const std::string& from,
                          const std::string& to,
                          const std::vector<std::string>& args) {
  GDALAllRegister();
  GDALDatasetH src = GDALOpen(from.c_str(), GA_ReadOnly);
  EXPECT_NE(src, nullptr) << from;
  if (src == nullptr) return false;
  std::vector<char*> argv;
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  GDALTranslateOptions* options = GDALTranslateOptionsNew(argv.data(), nullptr);
  GDALDatasetH out = GDALTranslate(to.c_str(), src, options, nullptr);
  GDALTranslateOptionsFree(options);
  EXPECT_NE(out, nullptr) << to;
  if (out != nullptr) GDALClose(out);
  GDALClose(src);
  return out != nullptr;
}

/// The EGM96 undulation N as PROJ computes it (WGS84 3-D -> WGS84 + EGM96 height, PROJ's own
/// reading of egm96_15.gtx): an independent check of skerry's lookup. nullopt if PROJ cannot.
/// The transformation is built once per process (building one costs milliseconds).
inline std::optional<double> ProjUndulation(double lat_deg, double lon_deg) {
  static const std::unique_ptr<OGRCoordinateTransformation> t = [] {
    OGRSpatialReference from;
    OGRSpatialReference to;
    std::unique_ptr<OGRCoordinateTransformation> out;
    if (from.importFromEPSG(4979) != OGRERR_NONE) return out;
    if (to.SetFromUserInput("EPSG:4326+5773") != OGRERR_NONE) return out;
    from.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    to.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    out.reset(OGRCreateCoordinateTransformation(&from, &to));
    return out;
  }();
  if (!t) return std::nullopt;
  double x = lon_deg;
  double y = lat_deg;
  double z = 0.0;
  if (!t->Transform(1, &x, &y, &z)) return std::nullopt;
  return -z;  // orthometric H = h - N with h = 0
}

}  // namespace skerry::geo::testing
