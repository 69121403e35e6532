// skerry align-aerial end to end: the real Autzen cloud registered to its orthophoto (the result
// and the figure written, a second run refused without --overwrite; the same with a 16-bit copy of
// the photo), and bad input (a cloud in
// its sensor's frame without a start, a malformed start, a cloud the image does not cover, a
// missing file), each an exit status 2 naming the file and what is wrong.

#include <gdal_priv.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "apps/cli_test_util.h"
#include "core/test_util.h"
#include "geo/geo_test_util.h"

namespace skerry {
namespace {

namespace fs = std::filesystem;
using testing::CliResult;
using testing::FreshDir;
using testing::Quote;
using testing::RunCli;

const std::string kAutzen = std::string(SKERRY_SHARED_DATA_DIR) + "/autzen";

// A levelled scan in its sensor's frame as an ASCII PCD: a 20 m square wall, 2 m high.
std::string WritePcd(const std::string& dir) {
  std::string points;
  int n = 0;
  for (double t = -10.0; t <= 10.0; t += 0.1) {
    for (double z = 0.0; z <= 2.0; z += 0.25) {
      for (const auto& [x, y] :
           {std::pair(t, -10.0), std::pair(t, 10.0), std::pair(-10.0, t), std::pair(10.0, t)}) {
        points += std::to_string(x) + " " + std::to_string(y) + " " + std::to_string(z) + "\n";
        ++n;
      }
    }
  }
  const std::string path = dir + "/scan.pcd";
  testing::WriteText(path,
                     "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
                     "WIDTH " +
                         std::to_string(n) +
                         "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\n"
                         "POINTS " +
                         std::to_string(n) + "\nDATA ascii\n" + points);
  return path;
}

TEST(AlignAerialCli, RegistersTheAutzenCloudToItsPhotoAndKeepsItsResults) {
  if (!fs::exists(kAutzen + "/autzen_trim.las")) GTEST_SKIP() << kAutzen << " missing";
  const std::string out = FreshDir("align");
  const std::string args = "align-aerial --cloud " + Quote(kAutzen + "/autzen_trim.las") +
                           " --image " + Quote(kAutzen + "/autzen.jpg") + " --out " + Quote(out);
  const CliResult r = RunCli(args);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("aligned"), std::string::npos) << r.out;
  const nlohmann::json j = nlohmann::json::parse(testing::ReadText(out + "/alignment.json"));
  const nlohmann::json& a = j["alignment"];
  // Where the alignment of these two files lies (docs/results.md: 2.6 m, 0.8 degrees), with the
  // start where the files put the cloud.
  EXPECT_EQ(j["start_from"], "the cloud's CRS");
  EXPECT_LT(std::hypot(a["shift_east_m"].get<double>(), a["shift_north_m"].get<double>()), 4.0);
  EXPECT_LT(std::abs(a["turn_clockwise_deg"].get<double>()), 1.5);
  EXPECT_GT(j["cloud"]["edge_points"].get<int>(), 1000);
  EXPECT_FALSE(j["coarse_search"]["ambiguous"].get<bool>());
  EXPECT_GT(fs::file_size(out + "/alignment.png"), 10000u);
  // The stated sd is the spatial jackknife's (16 blocks by default), not the curvature's: the
  // same cloud against four tone curves of the same photo spreads 0.61 m east and 0.81 degrees
  // (docs/results.md), where the curvature says 0.1 m and 0.07 degrees.
  ASSERT_TRUE(j["jackknife"].is_object()) << j.dump(2);
  EXPECT_EQ(j["jackknife"]["groups"].get<int>(), 16);
  EXPECT_GT(a["sd_east_m"].get<double>(), 0.3);
  EXPECT_GT(a["sd_heading_deg"].get<double>(), 0.3);
  EXPECT_LT(a["curvature_sd_east_m"].get<double>(), 0.2);
  for (const char* k : {"east_m", "north_m", "heading_deg"}) {
    EXPECT_GE(a[std::string("sd_") + k].get<double>(),
              a[std::string("curvature_sd_") + k].get<double>());
  }
  // Results are never replaced silently.
  const CliResult again = RunCli(args);
  EXPECT_EQ(again.status, 2);
  EXPECT_NE(again.err.find("alignment.json"), std::string::npos) << again.err;
  // Without the jackknife, the curvature alone; a 1 x 1 "jackknife" is refused.
  ASSERT_EQ(RunCli(args + " --overwrite --jackknife 0").status, 0);
  const nlohmann::json k = nlohmann::json::parse(testing::ReadText(out + "/alignment.json"));
  EXPECT_TRUE(k["jackknife"].is_null());
  EXPECT_EQ(k["alignment"]["sd_east_m"], k["alignment"]["curvature_sd_east_m"]);
  const CliResult one = RunCli(args + " --overwrite --jackknife 1");
  EXPECT_EQ(one.status, 2);
  EXPECT_NE(one.err.find("--jackknife"), std::string::npos) << one.err;
}

// A 16-bit GeoTIFF copy of the photo (each 8-bit value v as 257 v, the CRS embedded) is read by
// stretching it back onto 8 bits, and registers as the photo does.
TEST(AlignAerialCli, RegistersTheCloudToASixteenBitCopyOfThePhoto) {
  if (!fs::exists(kAutzen + "/autzen_trim.las")) GTEST_SKIP() << kAutzen << " missing";
  const std::string dir = FreshDir("deep");
  const std::string tif = dir + "/autzen16.tif";
  ASSERT_TRUE(geo::testing::GdalTranslate(kAutzen + "/autzen.jpg", tif,
                                          {"-of", "GTiff", "-ot", "UInt16", "-scale", "0", "255",
                                           "0", "65535", "-a_srs", kAutzen + "/autzen-srs.wkt"}));

  const CliResult r = RunCli("align-aerial --cloud " + Quote(kAutzen + "/autzen_trim.las") +
                             " --image " + Quote(tif) + " --out " + Quote(dir + "/out"));
  fs::remove(tif);  // 85 MB
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json j = nlohmann::json::parse(testing::ReadText(dir + "/out/alignment.json"));
  EXPECT_EQ(j["image"]["crs_source"], "file");
  // The stretch's ends: 16-bit values, inside the photo's, 0.5 % of its cells beyond each.
  const double lo = j["image"]["value_range"][0].get<double>();
  const double hi = j["image"]["value_range"][1].get<double>();
  EXPECT_GT(lo, 0.0);
  EXPECT_LT(hi, 65535.0);
  EXPECT_GT(hi - lo, 100.0 * 257.0);
  const nlohmann::json& a = j["alignment"];
  EXPECT_LT(std::hypot(a["shift_east_m"].get<double>(), a["shift_north_m"].get<double>()), 4.0);
  EXPECT_LT(std::abs(a["turn_clockwise_deg"].get<double>()), 1.5);
  EXPECT_GT(j["cloud"]["edge_points"].get<int>(), 1000);
}

// Writes 0 into every band of `tif` (an 8-bit GeoTIFF declaring no-data 0) on rows
// [0, rows) and columns [0, cols).
void BlankCorner(const std::string& tif, int rows, int cols) {
  std::unique_ptr<GDALDataset> ds(GDALDataset::FromHandle(GDALOpen(tif.c_str(), GA_Update)));
  ASSERT_TRUE(ds);
  rows = std::min(rows, ds->GetRasterYSize());
  cols = std::min(cols, ds->GetRasterXSize());
  std::vector<std::uint8_t> zeros(static_cast<size_t>(rows) * cols, 0);
  for (int b = 1; b <= ds->GetRasterCount(); ++b) {
    ASSERT_EQ(ds->GetRasterBand(b)->RasterIO(GF_Write, 0, 0, cols, rows, zeros.data(), cols, rows,
                                             GDT_Byte, 0, 0, nullptr),
              CE_None);
  }
}

nlohmann::json::array_t Shift(const nlohmann::json& j) {
  const nlohmann::json& a = j["alignment"];
  return {a["shift_east_m"], a["shift_north_m"], a["turn_clockwise_deg"]};
}

// A mosaic that ends 12 m north of the cloud (its pixels beyond set to 0, declared no-data):
// the cloud registers as it does to the whole photo, since the step at the mosaic's end is no
// edge (taken for one, it pulled the result 0.7 m north). A mosaic that holds data under less
// than half of the cloud is refused, saying so.
TEST(AlignAerialCli, PixelsWithoutDataNeitherPullTheAlignmentNorCountAsCoverage) {
  if (!fs::exists(kAutzen + "/autzen_trim.las")) GTEST_SKIP() << kAutzen << " missing";
  const std::string dir = FreshDir("nodata");
  const std::string cloud = " --cloud " + Quote(kAutzen + "/autzen_trim.las");
  CliResult r = RunCli("align-aerial" + cloud + " --image " + Quote(kAutzen + "/autzen.jpg") +
                       " --out " + Quote(dir + "/whole"));
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json whole =
      nlohmann::json::parse(testing::ReadText(dir + "/whole/alignment.json"));

  const std::string tif = dir + "/mosaic.tif";
  ASSERT_TRUE(geo::testing::GdalTranslate(
      kAutzen + "/autzen.jpg", tif,
      {"-of", "GTiff", "-a_nodata", "0", "-a_srs", kAutzen + "/autzen-srs.wkt"}));
  // The photo's top row is at northing 853362.6 ft, one foot a row; the cloud's north end at
  // 849497.9 ft: the mosaic ends at 849510 ft.
  BlankCorner(tif, 3853, 1 << 20);
  r = RunCli("align-aerial" + cloud + " --image " + Quote(tif) + " --out " + Quote(dir + "/ends"));
  ASSERT_EQ(r.status, 0) << r.err;
  const nlohmann::json ends =
      nlohmann::json::parse(testing::ReadText(dir + "/ends/alignment.json"));
  // The map reaches from the photo's south edge (row 4385: 848977.6 ft) to the north of its box
  // around the cloud (its rows); the part south of the mosaic's end holds data.
  const double map_height_m =
      ends["map"]["rows"].get<double>() * ends["map"]["resolution_m"].get<double>();
  EXPECT_NEAR(ends["map"]["valid_share"].get<double>(),
              (849509.6 - 848977.6) * 0.3048 / map_height_m, 0.02);
  EXPECT_GT(whole["map"]["valid_share"].get<double>(), 0.95);  // the corners the CRS turns off
  for (int k = 0; k < 2; ++k) EXPECT_NEAR(Shift(ends)[k], Shift(whole)[k], 0.2) << k;
  EXPECT_NEAR(Shift(ends)[2], Shift(whole)[2], 0.2);

  // Data east of easting 636900 ft only (column 1285): under a quarter of the cloud.
  BlankCorner(tif, 1 << 20, 1285);
  r = RunCli("align-aerial" + cloud + " --image " + Quote(tif) + " --out " + Quote(dir + "/east"));
  fs::remove(tif);  // 43 MB
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("autzen_trim.las"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("coverage"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("that hold data"), std::string::npos) << r.err;
}

TEST(AlignAerialCli, BadInputIsAnErrorNamingTheFileAndWhatIsWrong) {
  if (!fs::exists(kAutzen + "/autzen.jpg")) GTEST_SKIP() << kAutzen << " missing";
  const std::string dir = FreshDir("bad");
  const std::string pcd = WritePcd(dir);
  const std::string image = " --image " + Quote(kAutzen + "/autzen.jpg");
  // A cloud in its sensor's frame needs a start.
  CliResult r =
      RunCli("align-aerial --cloud " + Quote(pcd) + image + " --out " + Quote(dir + "/a"));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("scan.pcd"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("--start"), std::string::npos) << r.err;
  // A malformed start.
  r = RunCli("align-aerial --cloud " + Quote(pcd) + image + " --start 44.05,oops,10 --out " +
             Quote(dir + "/b"));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("LAT,LON,HEADING_DEG"), std::string::npos) << r.err;
  r = RunCli("align-aerial --cloud " + Quote(pcd) + image + " --start 44.05,-123.07,10deg --out " +
             Quote(dir + "/b2"));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("LAT,LON,HEADING_DEG"), std::string::npos) << r.err;
  // A georeferenced cloud starts where its file puts it: no --start.
  if (fs::exists(kAutzen + "/autzen_trim.las")) {
    r = RunCli("align-aerial --cloud " + Quote(kAutzen + "/autzen_trim.las") + image +
               " --start 44.05,-123.07,0 --out " + Quote(dir + "/b3"));
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("autzen_trim.las"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("georeferenced"), std::string::npos) << r.err;
  }
  // A start the image does not cover (a kilometre south of it).
  r = RunCli("align-aerial --cloud " + Quote(pcd) + image + " --start 44.04,-123.07,0 --out " +
             Quote(dir + "/c"));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("coverage"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("does not cover"), std::string::npos) << r.err;
  // A search that is not a number: CLI11's own checks let nan through, and the search then
  // asked for a vector larger than max_size (exit 1).
  for (const char* option : {"--search-radius nan", "--heading-range nan", "--heading-range 200"}) {
    r = RunCli("align-aerial --cloud " + Quote(pcd) + image + " --start 44.0507,-123.0712,0 " +
               option + " --out " + Quote(dir + "/nan"));
    EXPECT_EQ(r.status, 2) << option;
    EXPECT_NE(r.err.find("must be a finite number"), std::string::npos) << r.err;
  }
  // An image without a CRS: the error names the flag that gives one, and the flag mends it.
  fs::copy_file(kAutzen + "/autzen.jpg", dir + "/bare.jpg");
  fs::copy_file(kAutzen + "/autzen.wld", dir + "/bare.wld");
  const std::string bare = " --image " + Quote(dir + "/bare.jpg");
  r = RunCli("align-aerial --cloud " + Quote(pcd) + bare + " --start 44.0507,-123.0712,0 --out " +
             Quote(dir + "/f"));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("bare.jpg: crs:"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("as --image-crs"), std::string::npos) << r.err;
  r = RunCli("align-aerial --cloud " + Quote(pcd) + bare + " --image-crs " +
             Quote(kAutzen + "/autzen-srs.wkt") + " --start 44.0507,-123.0712,0 --out " +
             Quote(dir + "/g"));
  EXPECT_EQ(r.status, 0) << r.err;
  // A missing cloud.
  r = RunCli("align-aerial --cloud " + Quote(dir + "/none.las") + image + " --out " +
             Quote(dir + "/d"));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("none.las"), std::string::npos) << r.err;
  // Over the image, the square registers (the photo has no such square: whatever it finds, it
  // says how much to trust it, and exits 0).
  r = RunCli("align-aerial --cloud " + Quote(pcd) + image + " --start 44.0507,-123.0712,0 --out " +
             Quote(dir + "/e"));
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("ambiguity"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace skerry
