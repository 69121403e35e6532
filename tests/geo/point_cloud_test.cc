// Point clouds: the Autzen LAS 1.2 cloud (count, bounds, CRS, ENU against the orthophoto),
// synthetic LAS files for what Autzen lacks (1.4 and formats 6-10, GeoKey CRSs), patched and
// truncated copies for the errors, PCD / PLY written by PCL (with per-point times) and KITTI
// .bin round trips.

#include "skerry/geo/point_cloud.h"

#include <gtest/gtest.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <random>

#include "geo/geo_test_util.h"
#include "geo/las_test_writer.h"
#include "skerry/geo/las_reader.h"
#include "skerry/geo/orthophoto.h"

namespace skerry::geo {
namespace {

namespace fs = std::filesystem;
using testing::ExpectInputError;
using testing::FreshDir;
using testing::kData;
using testing::LasPoint;
using testing::LasSpec;
using testing::MakeLas;
using testing::Poke;

const std::string kAutzenDir = kData + "/autzen";
const std::string kAutzenLas = kAutzenDir + "/autzen_trim.las";

// --- Autzen ------------------------------------------------------------------------------------

TEST(AutzenLas, HeaderCountAndBoundsMatchThePointsRead) {
  SKERRY_SKIP_WITHOUT(kAutzenLas);
  const LasFile las = ReadLas(kAutzenLas);
  const LasHeader& h = las.header;
  EXPECT_EQ(h.version_major, 1);
  EXPECT_EQ(h.version_minor, 2);
  EXPECT_EQ(h.header_size, 227);
  EXPECT_EQ(h.point_format, 3);
  EXPECT_EQ(h.record_length, 34);
  EXPECT_EQ(h.point_count, 110000u);  // the data README's count
  EXPECT_EQ(las.cloud.points.size(), h.point_count);
  EXPECT_EQ(las.cloud.intensity.size(), h.point_count);
  EXPECT_EQ(las.cloud.classification.size(), h.point_count);
  // Header bounds are the points' bounds (to the 0.01 ft scale step; measured 1e-10).
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(las.read_min[a], h.min[a], 0.5 * h.scale[a]) << a;
    EXPECT_NEAR(las.read_max[a], h.max[a], 0.5 * h.scale[a]) << a;
  }
  // The file is classified into unclassified (1) and ground (2) only: a misread bit field
  // (class bits 0-4 of byte 15 in formats 0-5) would show other codes. Returns 1-4 of up to 5,
  // first returns the most common.
  std::vector<int> classes(256, 0);
  for (std::uint8_t c : las.cloud.classification) ++classes[c];
  EXPECT_EQ(classes[1] + classes[2], 110000);
  EXPECT_GT(classes[2], 10000);
  std::vector<int> returns(256, 0);
  for (std::uint8_t r : las.cloud.return_number) ++returns[r];
  EXPECT_EQ(returns[0], 0);
  EXPECT_EQ(std::max_element(returns.begin(), returns.end()) - returns.begin(), 1);
  EXPECT_EQ(returns[1] + returns[2] + returns[3] + returns[4] + returns[5], 110000);
  EXPECT_GT(*std::max_element(las.cloud.intensity.begin(), las.cloud.intensity.end()), 0.0f);
  // CRS from the OGC WKT record, with its foot unit.
  EXPECT_EQ(las.cloud.frame, CloudFrame::kCrs);
  EXPECT_NE(las.cloud.crs_note.find("2112"), std::string::npos) << las.cloud.crs_note;
  EXPECT_NE(las.cloud.crs_wkt.find("0.3048"), std::string::npos);
  EXPECT_EQ(LoadPointCloud(kAutzenLas).points.size(), 110000u);
}

TEST(AutzenLas, InEnuItLiesOnTheOrthophotoExceptAStripSouthOfItsEdge) {
  SKERRY_SKIP_WITHOUT(kAutzenLas);
  const Orthophoto rough(kAutzenDir + "/autzen.jpg", LocalFrame({44.05, -123.07, 100.0}));
  const Eigen::Vector3d centre = rough.frame().ToGeodetic(rough.PixelToEnu(1623.5, 2192.0, 100.0));
  const LocalFrame frame({centre.x(), centre.y(), 100.0});
  const Orthophoto ortho(kAutzenDir + "/autzen.jpg", frame);
  const LasFile las = ReadLas(kAutzenLas);
  const PointCloud enu =
      PointCloudToEnu(las.cloud, frame, CloudToEnuOptions(VerticalDatum::kEgm96));
  ASSERT_EQ(enu.points.size(), las.cloud.points.size());
  EXPECT_EQ(enu.frame, CloudFrame::kLocalEnu);
  // The image's bottom edge is 853362.643 - 4385 ft (its world file); the cloud's header starts
  // at 848935.20 ft: 42.44 ft further south. Those points, and only those, lie off the image.
  const double bottom_ft = 853362.1430851521 + 0.5 - 4385.0;
  int south = 0;
  int off_image = 0;
  double worst_overshoot_px = 0.0;
  Eigen::AlignedBox2d box;
  for (size_t i = 0; i < enu.points.size(); ++i) {
    const bool below = las.cloud.points[i].y() < bottom_ft;
    south += below;
    const Eigen::Vector2d uv = ortho.EnuToPixel(enu.points[i]);
    EXPECT_GE(uv.x(), -0.5);
    EXPECT_LE(uv.x(), ortho.width() - 0.5);
    EXPECT_GE(uv.y(), -0.5);
    if (!ortho.Covers(enu.points[i])) {
      ++off_image;
      worst_overshoot_px = std::max(worst_overshoot_px, uv.y() - (ortho.height() - 0.5));
    }
    box.extend(enu.points[i].head<2>().eval());
  }
  RecordProperty("points_off_image", std::to_string(off_image));
  EXPECT_EQ(off_image, south);
  EXPECT_GT(south, 0);
  // In pixels (= feet) the overshoot is the header's min y below the edge, to the rounding of
  // the ENU round trip (measured 1e-7 px).
  EXPECT_NEAR(worst_overshoot_px, bottom_ft - las.header.min.y(), 1e-3);
  // The cloud's ENU box lies inside the image footprint's box: the grid's 1.8 degree rotation
  // widens the latter by more than the 13 m strip.
  EXPECT_TRUE(ortho.footprint_box_enu().contains(box));
  // Heights: z in feet (the CRS's unit), NAVD88 ~ EGM96. Ground (class 2) lies at the
  // Willamette valley floor, Eugene 130 m above sea: orthometric median within 15 m of that.
  std::vector<double> ground_h;
  for (size_t i = 0; i < enu.points.size(); ++i) {
    if (las.cloud.classification[i] != 2) continue;
    const Eigen::Vector3d llh = frame.ToGeodetic(enu.points[i]);
    ground_h.push_back(llh.z() - *testing::ProjUndulation(llh.x(), llh.y()));
  }
  std::nth_element(ground_h.begin(), ground_h.begin() + ground_h.size() / 2, ground_h.end());
  EXPECT_NEAR(ground_h[ground_h.size() / 2], 130.0, 15.0);
}

// --- Errors on patched copies ------------------------------------------------------------------

class AutzenCopy : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(kAutzenLas)) GTEST_SKIP() << kAutzenLas << " missing";
    bytes_ = testing::ReadBytes(kAutzenLas);
    dir_ = FreshDir("las");
  }
  std::string Write(const std::string& name) {
    const std::string path = dir_ + "/" + name;
    testing::WriteBytes(path, bytes_);
    return path;
  }
  std::vector<std::uint8_t> bytes_;
  std::string dir_;
};

TEST_F(AutzenCopy, AWrongPointCountIsAnInputErrorWithBothNumbers) {
  Poke<std::uint32_t>(bytes_, 107, 110001);
  const std::string more = Write("more.las");
  ExpectInputError([&] { ReadLas(more); }, more, "point_count",
                   {"110001 points", "room for 110000 points"});
  Poke<std::uint32_t>(bytes_, 107, 109999);
  const std::string fewer = Write("fewer.las");
  ExpectInputError([&] { ReadLas(fewer); }, fewer, "point_count",
                   {"109999 points", "holds 110000 records"});
  ExpectInputError([&] { LoadPointCloud(fewer); }, fewer, "point_count");
}

TEST_F(AutzenCopy, ATruncatedFileIsAnInputError) {
  bytes_.resize(2000000);
  const std::string cut = Write("cut.las");
  // (2,000,000 - 2,038) / 34 = 58,763 whole records.
  ExpectInputError([&] { ReadLas(cut); }, cut, "point_count",
                   {"110000 points", "2000000 bytes", "room for 58763 points", "truncated"});
  bytes_.resize(100);
  const std::string stub = Write("stub.las");
  ExpectInputError([&] { ReadLas(stub); }, stub, "header", {"truncated"});
}

TEST_F(AutzenCopy, PointsOutsideTheHeaderBoundsAreAnInputError) {
  Poke<double>(bytes_, 179, 637179.22 - 5.0);  // max x five feet too small
  const std::string path = Write("bounds.las");
  ExpectInputError([&] { ReadLas(path); }, path, "bounds", {"x 636001.76"});
  Poke<double>(bytes_, 179, 637179.22 - 0.005);  // within a scale step: tolerated
  const std::string ok = Write("ok.las");
  EXPECT_NO_THROW(ReadLas(ok));
}

TEST_F(AutzenCopy, LazAndNonLasAreInputErrors) {
  const std::string laz = Write("cloud.laz");
  ExpectInputError([&] { LoadPointCloud(laz); }, laz, "point_format",
                   {"compressed LAS (LAZ) is not supported"});
  bytes_[104] |= 0x80;  // LASzip's compressed-format bit
  const std::string flagged = Write("flagged.las");
  ExpectInputError([&] { ReadLas(flagged); }, flagged, "point_format",
                   {"compressed LAS (LAZ) is not supported"});
  bytes_[0] = 'X';
  const std::string not_las = Write("not.las");
  ExpectInputError([&] { ReadLas(not_las); }, not_las, "signature", {"LASF"});
  const std::string xyz = Write("cloud.xyz");
  ExpectInputError([&] { LoadPointCloud(xyz); }, xyz, "", {".xyz"});
}

// --- Synthetic LAS: 1.4, formats 6-10, GeoKeys -------------------------------------------------

std::vector<LasPoint> SomePoints(int n) {
  std::vector<LasPoint> points;
  for (int i = 0; i < n; ++i) {
    LasPoint p;
    p.x = 1000 * i - 5000;
    p.y = 7 * i * i;
    p.z = -300 + 11 * i;
    p.intensity = static_cast<std::uint16_t>(60000 - 1000 * i);
    p.return_number = static_cast<std::uint8_t>(1 + i % 5);
    p.number_of_returns = 5;
    p.classification = static_cast<std::uint8_t>(i % 3 == 0 ? 2 : 40 + i);  // 40+: 1.4 only
    p.flags = 0xFF;  // every flag bit set: none may leak into the class or return number
    points.push_back(p);
  }
  return points;
}

std::string WktOf(int epsg) {
  OGRSpatialReference crs;
  crs.importFromEPSG(epsg);
  char* wkt = nullptr;
  crs.exportToWkt(&wkt);
  std::string out = wkt;
  CPLFree(wkt);
  return out;
}

TEST(SyntheticLas, Las14Formats6To10WithAnExtendedWktRecord) {
  const std::string dir = FreshDir("las14");
  for (int format = 6; format <= 10; ++format) {
    LasSpec spec;
    spec.minor = 4;
    spec.format = format;
    spec.offset_x = 500000.0;
    spec.offset_y = 7000000.0;
    spec.points = SomePoints(20);
    spec.legacy_count_zero = true;
    spec.evlrs.push_back(testing::WktRecord(WktOf(32633)));
    const std::string path = dir + "/f" + std::to_string(format) + ".las";
    testing::WriteBytes(path, MakeLas(spec));
    const LasFile las = ReadLas(path);
    EXPECT_EQ(las.header.header_size, 375);
    EXPECT_EQ(las.header.legacy_point_count, 0u);
    EXPECT_EQ(las.header.extended_point_count, 20u);
    ASSERT_EQ(las.cloud.points.size(), 20u);
    for (int i = 0; i < 20; ++i) {
      const LasPoint& p = spec.points[i];
      EXPECT_EQ(las.cloud.points[i],
                Eigen::Vector3d(p.x * 0.01 + 500000.0, p.y * 0.01 + 7000000.0, p.z * 0.01));
      EXPECT_EQ(las.cloud.intensity[i], p.intensity);
      EXPECT_EQ(las.cloud.return_number[i], p.return_number) << "format " << format;
      EXPECT_EQ(las.cloud.classification[i], p.classification) << "format " << format;
    }
    ASSERT_EQ(las.vlrs.size(), 1u);
    EXPECT_TRUE(las.vlrs[0].extended);
    EXPECT_NE(las.cloud.crs_note.find("UTM zone 33N"), std::string::npos) << las.cloud.crs_note;
  }
  // Legacy and extended counts that disagree.
  LasSpec spec;
  spec.minor = 4;
  spec.format = 1;
  spec.points = SomePoints(5);
  for (auto& p : spec.points) p.classification = 2;
  std::vector<std::uint8_t> bytes = MakeLas(spec);
  Poke<std::uint32_t>(bytes, 107, 4);
  const std::string path = dir + "/counts.las";
  testing::WriteBytes(path, bytes);
  ExpectInputError([&] { ReadLas(path); }, path, "point_count",
                   {"legacy point count 4", "extended point count 5"});
}

// The WKT record holds WKT: a file name, an "EPSG:" code or a PROJ string in it is no CRS, and
// GDAL is not asked to open the file (SetFromUserInput did, and would have fetched a URL).
TEST(SyntheticLas, TheWktRecordIsReadAsWktAlone) {
  const std::string dir = FreshDir("las_wkt_only");
  testing::WriteText(dir + "/crs.wkt", WktOf(32633));
  for (const std::string& record : {dir + "/crs.wkt", std::string("EPSG:32633"),
                                    std::string("+proj=utm +zone=33 +datum=WGS84")}) {
    LasSpec spec;
    spec.points = SomePoints(3);
    spec.vlrs.push_back(testing::WktRecord(record));
    const std::string path = dir + "/cloud.las";
    testing::WriteBytes(path, MakeLas(spec));
    const LasFile las = ReadLas(path);
    EXPECT_EQ(las.cloud.points.size(), 3u);
    EXPECT_TRUE(las.cloud.crs_wkt.empty()) << record << ": " << las.cloud.crs_note;
    EXPECT_NE(las.cloud.crs_note.find("cannot be parsed as WKT"), std::string::npos)
        << record << ": " << las.cloud.crs_note;
  }
}

TEST(SyntheticLas, Formats0To5AndThe13Header) {
  const std::string dir = FreshDir("legacy");
  for (int format = 0; format <= 5; ++format) {
    LasSpec spec;
    spec.minor = format >= 4 ? 3 : 2;
    spec.format = format;
    spec.points = SomePoints(9);
    for (auto& p : spec.points) p.classification = 31 & p.classification;
    const std::string path = dir + "/f" + std::to_string(format) + ".las";
    testing::WriteBytes(path, MakeLas(spec));
    const LasFile las = ReadLas(path);
    EXPECT_EQ(las.header.header_size, format >= 4 ? 235 : 227);
    ASSERT_EQ(las.cloud.points.size(), 9u);
    for (int i = 0; i < 9; ++i) {
      EXPECT_EQ(las.cloud.classification[i], spec.points[i].classification) << format;
      EXPECT_EQ(las.cloud.return_number[i], spec.points[i].return_number) << format;
      EXPECT_EQ(las.cloud.points[i].z(), spec.points[i].z * 0.01);
    }
    EXPECT_NE(las.cloud.crs_note.find("no CRS record"), std::string::npos);
  }
}

TEST(SyntheticLas, GeoKeysEpsgCodeWithAFootUnitOverride) {
  const std::string dir = FreshDir("geokeys");
  // Two points of UTM 10N: one file in metres (EPSG:32610), one in feet on the same code with
  // ProjLinearUnitsGeoKey = 9002 (foot), as some LAS writers do.
  const double e[2] = {492000.0, 493000.0};
  const double n[2] = {4877000.0, 4876500.0};
  LasSpec metres;
  metres.vlrs.push_back(testing::GeoKeys({{1024, 1}, {3072, 32610}}));
  LasSpec feet;
  feet.vlrs.push_back(testing::GeoKeys({{1024, 1}, {3072, 32610}, {3076, 9002}}));
  for (int k = 0; k < 2; ++k) {
    LasPoint pm;
    pm.x = static_cast<std::int32_t>(std::lround(e[k] / 0.01));
    pm.y = static_cast<std::int32_t>(std::lround(n[k] / 0.01));
    pm.z = 10000;  // 100 m
    metres.points.push_back(pm);
    LasPoint pf = pm;
    pf.x = static_cast<std::int32_t>(std::lround(e[k] / 0.3048 / 0.01));
    pf.y = static_cast<std::int32_t>(std::lround(n[k] / 0.3048 / 0.01));
    pf.z = static_cast<std::int32_t>(std::lround(100.0 / 0.3048 / 0.01));
    feet.points.push_back(pf);
  }
  testing::WriteBytes(dir + "/metres.las", MakeLas(metres));
  testing::WriteBytes(dir + "/feet.las", MakeLas(feet));
  const PointCloud a = LoadPointCloud(dir + "/metres.las");
  const PointCloud b = LoadPointCloud(dir + "/feet.las");
  EXPECT_NE(a.crs_note.find("EPSG:32610"), std::string::npos) << a.crs_note;
  EXPECT_NE(b.crs_note.find("overridden to foot"), std::string::npos) << b.crs_note;
  const LocalFrame frame({44.05, -123.1, 50.0});
  const CloudToEnuOptions options(VerticalDatum::kEllipsoidal);
  const PointCloud ea = PointCloudToEnu(a, frame, options);
  const PointCloud eb = PointCloudToEnu(b, frame, options);
  // Feet rounded to 0.01 ft: 3 mm.
  for (int k = 0; k < 2; ++k) EXPECT_LT((ea.points[k] - eb.points[k]).norm(), 4e-3) << k;
  EXPECT_NEAR((ea.points[1] - ea.points[0]).head<2>().norm(), std::hypot(1000.0, 500.0), 1.0);
}

TEST(SyntheticLas, UserDefinedGeoKeysAreNotDecodedAndNeedAnOverride) {
  const std::string dir = FreshDir("userdefined");
  LasSpec spec;
  spec.vlrs.push_back(testing::GeoKeys({{1024, 1}, {3072, 32767}, {4096, 5703}}));
  LasPoint p;
  p.x = 49200000;
  p.y = 487700000;
  spec.points = {p};
  const std::string path = dir + "/user.las";
  testing::WriteBytes(path, MakeLas(spec));
  const PointCloud cloud = LoadPointCloud(path);
  EXPECT_TRUE(cloud.crs_wkt.empty());
  EXPECT_NE(cloud.crs_note.find("user-defined"), std::string::npos) << cloud.crs_note;
  EXPECT_NE(cloud.crs_note.find("EPSG:5703"), std::string::npos) << cloud.crs_note;
  const LocalFrame frame({44.05, -123.1, 50.0});
  CloudToEnuOptions options(VerticalDatum::kEllipsoidal);
  ExpectInputError([&] { PointCloudToEnu(cloud, frame, options); }, path, "crs",
                   {"CRS is unknown", "user-defined"});
  options.crs = "EPSG:32610";
  const PointCloud enu = PointCloudToEnu(cloud, frame, options);
  EXPECT_LT(enu.points[0].head<2>().norm(), 10000.0);
}

// --- PCD, PLY (PCL) and KITTI .bin -------------------------------------------------------------

pcl::PointCloud<pcl::PointXYZI> SensorCloud() {
  pcl::PointCloud<pcl::PointXYZI> cloud;
  std::mt19937 rng(4);
  std::uniform_int_distribution<int> q(-4000, 4000);
  for (int i = 0; i < 500; ++i) {
    pcl::PointXYZI p;
    // Multiples of 1/16 m below 256 m: exact in float and in PCL's 8-digit ASCII.
    p.x = q(rng) / 16.0f;
    p.y = q(rng) / 16.0f;
    p.z = q(rng) / 256.0f * 4.0f;
    p.intensity = static_cast<float>(i % 256);
    cloud.push_back(p);
  }
  return cloud;
}

void ExpectSame(const pcl::PointCloud<pcl::PointXYZI>& expected, const PointCloud& read) {
  SCOPED_TRACE(read.path);
  ASSERT_EQ(read.points.size(), expected.size());
  ASSERT_EQ(read.intensity.size(), expected.size());
  EXPECT_EQ(read.frame, CloudFrame::kSensor);
  for (size_t i = 0; i < expected.size(); ++i) {
    EXPECT_EQ(read.points[i], Eigen::Vector3d(expected[i].x, expected[i].y, expected[i].z)) << i;
    EXPECT_EQ(read.intensity[i], expected[i].intensity) << i;
  }
  EXPECT_TRUE(read.time_s.empty());
}

TEST(PclClouds, PcdAndPlyWrittenByPclReadBack) {
  const std::string dir = FreshDir("pcl");
  const pcl::PointCloud<pcl::PointXYZI> cloud = SensorCloud();
  ASSERT_EQ(pcl::io::savePCDFileBinary(dir + "/scan_bin.pcd", cloud), 0);
  ASSERT_EQ(pcl::io::savePCDFileASCII(dir + "/scan_ascii.pcd", cloud), 0);
  ASSERT_EQ(pcl::io::savePLYFileBinary(dir + "/scan.ply", cloud), 0);
  ASSERT_EQ(pcl::io::savePLYFileASCII(dir + "/scan_ascii.PLY", cloud), 0);
  ASSERT_EQ(pcl::io::savePCDFileBinaryCompressed(dir + "/scan_lzf.pcd", cloud), 0);
  ExpectSame(cloud, LoadPointCloud(dir + "/scan_lzf.pcd"));
  ExpectSame(cloud, LoadPointCloud(dir + "/scan_bin.pcd"));
  ExpectSame(cloud, LoadPointCloud(dir + "/scan_ascii.pcd"));
  ExpectSame(cloud, LoadPointCloud(dir + "/scan.ply"));
  ExpectSame(cloud, LoadPointCloud(dir + "/scan_ascii.PLY"));

  pcl::PointCloud<pcl::PointXYZ> xyz;
  for (const auto& p : cloud) xyz.push_back(pcl::PointXYZ(p.x, p.y, p.z));
  ASSERT_EQ(pcl::io::savePCDFileBinary(dir + "/xyz.pcd", xyz), 0);
  const PointCloud read = LoadPointCloud(dir + "/xyz.pcd");
  EXPECT_EQ(read.points.size(), 500u);
  EXPECT_TRUE(read.intensity.empty());

  // A sensor-frame cloud is not georeferenced.
  ExpectInputError(
      [&] {
        PointCloudToEnu(read, LocalFrame({0, 0, 0}), CloudToEnuOptions(VerticalDatum::kEgm96));
      },
      dir + "/xyz.pcd", "crs", {"sensor-frame"});
  // Malformed files: PCL 1.13 itself crashes on the first, so the reader checks first.
  testing::WriteText(dir + "/junk.pcd", "this is not a point cloud\n");
  ExpectInputError([&] { LoadPointCloud(dir + "/junk.pcd"); }, dir + "/junk.pcd", "", {"PCD"});
  std::vector<std::uint8_t> bytes = testing::ReadBytes(dir + "/scan_bin.pcd");
  bytes.resize(bytes.size() - 100);
  testing::WriteBytes(dir + "/cut.pcd", bytes);
  ExpectInputError([&] { LoadPointCloud(dir + "/cut.pcd"); }, dir + "/cut.pcd", "",
                   {"announces 500 points", "truncated"});
  testing::WriteText(dir + "/junk.ply", "this is not a point cloud either\n");
  ExpectInputError([&] { LoadPointCloud(dir + "/junk.ply"); }, dir + "/junk.ply", "ply",
                   {"junk.ply:1:", "not a PLY file"});
}

// A scan with per-point times (a deskewing LiDAR driver's, or skerry's simulator's): fields
// x y z intensity t, t as float seconds or as integer nanoseconds (the Ouster driver's uint32).
pcl::PCLPointCloud2 TimedBlob(std::uint8_t time_type, int n) {
  pcl::PCLPointCloud2 blob;
  const std::uint32_t time_size = time_type == pcl::PCLPointField::FLOAT64 ? 8 : 4;
  std::uint32_t offset = 0;
  for (const char* name : {"x", "y", "z", "intensity"}) {
    pcl::PCLPointField f;
    f.name = name;
    f.offset = offset;
    f.datatype = pcl::PCLPointField::FLOAT32;
    f.count = 1;
    blob.fields.push_back(f);
    offset += 4;
  }
  pcl::PCLPointField t;
  t.name = "t";
  t.offset = offset;
  t.datatype = time_type;
  t.count = 1;
  blob.fields.push_back(t);
  blob.point_step = offset + time_size;
  blob.width = static_cast<std::uint32_t>(n);
  blob.height = 1;
  blob.row_step = blob.point_step * blob.width;
  blob.is_dense = true;
  blob.data.resize(blob.row_step);
  for (int i = 0; i < n; ++i) {
    std::uint8_t* p = blob.data.data() + i * blob.point_step;
    const float xyzi[4] = {i * 0.5f, -i * 0.25f, 1.0f, static_cast<float>(i)};
    std::memcpy(p, xyzi, sizeof(xyzi));
    // Times 0.1 ms apart: 0.0001 * i s, or 100000 * i ns.
    if (time_type == pcl::PCLPointField::FLOAT32) {
      const float v = 1e-4f * i;
      std::memcpy(p + offset, &v, 4);
    } else if (time_type == pcl::PCLPointField::FLOAT64) {
      const double v = 1e-4 * i;
      std::memcpy(p + offset, &v, 8);
    } else {
      const std::uint32_t v = 100000u * static_cast<std::uint32_t>(i);
      std::memcpy(p + offset, &v, 4);
    }
  }
  return blob;
}

TEST(PclClouds, PerPointTimesAreReadFromTheTField) {
  const std::string dir = FreshDir("pcl_time");
  pcl::PCDWriter writer;
  struct Case {
    std::uint8_t type;
    const char* file;
    bool binary;
  };
  for (const Case& c : {Case{pcl::PCLPointField::FLOAT32, "/f32.pcd", true},
                        Case{pcl::PCLPointField::FLOAT32, "/f32_ascii.pcd", false},
                        Case{pcl::PCLPointField::FLOAT64, "/f64.pcd", true},
                        Case{pcl::PCLPointField::UINT32, "/ouster_ns.pcd", true}}) {
    SCOPED_TRACE(c.file);
    const std::string path = dir + c.file;
    const pcl::PCLPointCloud2 blob = TimedBlob(c.type, 40);
    ASSERT_EQ(c.binary ? writer.writeBinary(path, blob) : writer.writeASCII(path, blob), 0);
    const PointCloud read = LoadPointCloud(path);
    ASSERT_EQ(read.points.size(), 40u);
    ASSERT_EQ(read.time_s.size(), 40u);
    ASSERT_EQ(read.intensity.size(), 40u);
    for (int i = 0; i < 40; ++i) {
      EXPECT_FLOAT_EQ(read.time_s[i], 1e-4f * i) << i;
      EXPECT_EQ(read.points[i], Eigen::Vector3d(i * 0.5, -i * 0.25, 1.0)) << i;
      EXPECT_EQ(read.intensity[i], static_cast<float>(i)) << i;
    }
  }
  // A time field of another type (8-bit) is refused, naming the field.
  pcl::PCLPointCloud2 bad = TimedBlob(pcl::PCLPointField::FLOAT32, 3);
  bad.fields.back().datatype = pcl::PCLPointField::UINT8;
  ASSERT_EQ(writer.writeBinary(dir + "/bad_t.pcd", bad), 0);
  ExpectInputError([&] { LoadPointCloud(dir + "/bad_t.pcd"); }, dir + "/bad_t.pcd", "t",
                   {"time field"});
}

// Headers that announce more than their files hold, or a layout PCL's conversion would read past:
// PCL sized the cloud from the header before reading it (a 200-byte PCD announcing 10^9 points
// asked for 13 GB, a PLY announcing 4e9 vertices for 48 GB) and copied fields of a garbled SIZE
// line past the data. Each is an InputError naming the file before PCL allocates anything. Found
// by the point_cloud fuzz target (tests/fuzz/corpus/point_cloud holds the inputs).
TEST(PclClouds, HeadersThatOverstateTheirDataAreInputErrors) {
  const std::string dir = FreshDir("pcl_bad_headers");
  // The file `name` written with `content`: refused, naming it, `field` and `facts`.
  const auto refused = [&](const std::string& name, const std::string& content,
                           const std::string& field, const std::vector<std::string>& facts) {
    testing::WriteText(dir + "/" + name, content);
    ExpectInputError([&] { LoadPointCloud(dir + "/" + name); }, dir + "/" + name, field, facts);
  };
  const std::string fields = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\n";
  refused("many.pcd",
          fields +
              "COUNT 1 1 1\nWIDTH 1000000000\nHEIGHT 1\n"
              "POINTS 1000000000\nDATA ascii\n1 2 3\n4 5 6\n",
          "", {"announces 1000000000 points", "(ascii)", "truncated or a wrong count"});
  refused("count.pcd",
          fields +
              "COUNT 1 1-1 1\nWIDTH 2\nHEIGHT 1\nPOINTS 2\n"
              "DATA ascii\n1 2 3\n4 5 6\n",
          "COUNT", {"count.pcd:5:", "'1-1' is not a count"});
  refused("fields.pcd",
          "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1\n"
          "WIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n1 2 3\n",
          "COUNT", {"2 counts for 3 field sizes"});
  // PCL reserves a token per value of a point before reading a line, even for no points: a COUNT
  // of 4294967293 asked for 137 GB (CI's fuzzing found it). A field's SIZE is one of PCL's types.
  refused("values.pcd",
          "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 4294967293\n"
          "WIDTH 0\nHEIGHT 1\nPOINTS 0\nDATA ascii\n",
          "COUNT", {"values.pcd:5:", "more than 65536 values"});
  refused("size.pcd",
          "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 99999999\nTYPE F F F\nCOUNT 1 1 1\n"
          "WIDTH 1\nHEIGHT 1\nPOINTS 1\nDATA ascii\n1 2 3\n",
          "SIZE", {"size.pcd:3:", "a field of 99999999 bytes"});
  // PCL takes a line by its key's first letters: "COUNTI" is a COUNT line, checked as one.
  refused("key.pcd",
          fields +
              "COUNTI 1 1-1 -2.5\nWIDTH 2\nHEIGHT 1\nPOINTS 2\n"
              "DATA ascii\n1 2 3\n4 5 6\n",
          "COUNT", {"key.pcd:5:", "'1-1' is not a count"});
  // A SIZE line PCL does not take as one (the fuzzer's input): fields of no size in a 5-byte
  // record. PCL decides which field it names; the error says the layout does not fit.
  testing::WriteText(dir + "/garbled.pcd",
                     "# .PCON 0.7\nFIELDS x y z intensity t\nSIZET 1 1 1 1 1\nWIDTH 3\n"
                     "HEIGHT 1\nVIEWPOINT 0 0 0= 1 0 0 0\nPOINTS 3\nDATA ascii\n1 2 3 10 0.01\n"
                     "4 5 6 20 0.82\n-1 -2 0.5 5 \n");
  try {
    LoadPointCloud(dir + "/garbled.pcd");
    ADD_FAILURE() << "garbled.pcd was read";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), dir + "/garbled.pcd") << e.what();
    EXPECT_NE(std::string(e.what()).find("does not fit"), std::string::npos) << e.what();
    // Refused from the header PCL parsed, before its ascii reader wrote the 4-byte floats those
    // fields are typed as into 1-byte slots, past the end of its buffer (valgrind saw it; ASan
    // cannot, PCL being uninstrumented).
    EXPECT_NE(std::string(e.what()).find("before PCL reads the body"), std::string::npos)
        << e.what();
  }
  const std::string ply =
      "ply\nformat ascii 1.0\nelement vertex 4000000000\nproperty float x\n"
      "property float y\nproperty float z\nend_header\n1 2 3\n";
  refused("many.ply", ply, "element",
          {"at least 12000000000 bytes (ascii)", "6 bytes after its header"});
  refused("negative.ply",
          "ply\nformat binary_little_endian 1.0\nelement vertex -3\n"
          "property float x\nproperty float y\nproperty float z\nend_header\n",
          "element", {"negative.ply:3:", "'-3' is not a count"});
  // No end_header: PCL began the 2e9 vertices it announced before it found that (CI's fuzzing).
  refused("endless.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 2000000000\nprop\n",
          "end_header", {"announces elements and never ends"});
  // Without a SIZE line PCL still sizes the cloud by POINTS (the fuzzer's 150 bytes asked for
  // 3.6 TB): a value counts at least a byte.
  refused("nosize.pcd",
          "# .PCD 0.7\nFIELDS x y z intensity\nWIDTH 3\nHEIGHT 1\nPOINTS 99999999993\n"
          "DATA ascii\n1 2 3 10\n4 5 6 20\n",
          "", {"announces 99999999993 points", "truncated or a wrong count"});
  // A POINTS line repeated before DATA: PCL sized the cloud at the first (CI's fuzzing: 3.6 TB
  // asked for by a 284-byte file whose second POINTS said 3).
  refused("points-twice.pcd",
          "# .PCD 0.7\nFIELDS x y z intensity\nWIDTH 3\nHEIGHT 1\nPOINTS 99999999993\n"
          "POINTS 3\nDATA ascii\n1 2 3 10\n4 5 6 20\n-1 -2 0.5 5\n",
          "", {"announces 99999999993 points", "truncated or a wrong count"});
  // PCL reads header lines past DATA (a later POINTS counted; a later FIELDS crashed its ascii
  // reader): the header ends at DATA.
  refused("after-data.pcd",
          "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 2\nHEIGHT 1\nPOINTS 2\n"
          "DATA ascii\n# a comment PCL skips\nPOINTS 99999999993\n1 2 3\n4 5 6\n",
          "POINTS", {"after-data.pcd:10:", "a header line after DATA (line 8)"});
  // An element of no properties still counts: PCL steps through each of the 2e9 (a garbled
  // property line, the fuzzer's input, ran past its 10 s).
  refused("empty-elements.ply",
          "ply\nformat binary_little_endian 1.0\nelement vertex 2000000000\npropert\n"
          "end_header\nabcdefghijkl",
          "element", {"at least 2000000000 bytes", "12 bytes after its header"});
  // A compressed PCD body opens with its compressed and uncompressed sizes; PCL sized the cloud
  // by the second (2^31 - 1: 2 GB for a 131-byte file) and copied the header's points past a
  // smaller one.
  const std::string compressed =
      "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 1000\n"
      "HEIGHT 1\nPOINTS 1000\nDATA binary_compressed\n";
  const auto sizes = [](std::uint32_t packed, std::uint32_t unpacked) {
    std::string b(8, '\0');
    std::memcpy(&b[0], &packed, 4);
    std::memcpy(&b[4], &unpacked, 4);
    return b;
  };
  refused("unpacked.pcd", compressed + sizes(1, 0x7fffffff) + "abcde", "DATA",
          {"unpacks to 2147483647 bytes", "1000 points of 12 bytes"});
  refused("small.pcd", compressed + sizes(1, 12) + "abcde", "DATA", {"unpacks to 12 bytes"});
  refused("packed.pcd", compressed + sizes(900, 12000) + "abcde", "DATA",
          {"says 900 bytes", "has 5 after its sizes"});
  std::string ten = compressed;
  ten.replace(ten.find("WIDTH 1000"), 10, "WIDTH 10")
      .replace(ten.find("POINTS 1000"), 11, "POINTS 10");
  refused("nosizes.pcd", ten + "abc", "DATA", {"without its two sizes"});
  // A PLY file begins with the line "ply": PCL's parser, given a one-byte file, compared bytes it
  // never read (valgrind on the fuzzer's input).
  refused("one-byte.ply", "L", "ply", {"one-byte.ply:1:", "not a PLY file", "begins with 'L'"});
  refused("empty.ply", "", "ply", {"not a PLY file: it is empty"});
  refused("binary.ply", std::string("\x01\x02plyx\nformat ascii 1.0\n", 20), "ply",
          {"begins with '??plyx'"});
}

// PCL is loaded on demand (geo/src/pcl_reader.h): when its module cannot be loaded, a PCD is an
// InputError naming the file and saying what is missing, not a crash. In a fresh process, so that
// the module this process has already loaded is not reused.
TEST(PclClouds, AMissingModuleIsAnInputErrorNamingIt) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  const std::string dir = FreshDir("pcl_module");
  ASSERT_EQ(pcl::io::savePCDFileBinary(dir + "/scan.pcd", SensorCloud()), 0);
  EXPECT_EXIT(
      {
        setenv("SKERRY_PCL_READER", "/nonexistent/libskerry_pcl_reader.so", 1);
        int code = 0;
        try {
          LoadPointCloud(dir + "/scan.pcd");
        } catch (const InputError& e) {
          std::cerr << e.what() << "\n";
          code = e.file() == dir + "/scan.pcd" ? 3 : 4;
        }
        std::exit(code);
      },
      ::testing::ExitedWithCode(3),
      "scan.pcd: reading PCD and PLY files needs skerry's PCL module.*nonexistent");
}

TEST(KittiBin, RoundTripAndABadSize) {
  const std::string dir = FreshDir("kitti");
  std::vector<float> raw;
  std::mt19937 rng(9);
  std::normal_distribution<float> g(0.0f, 20.0f);
  for (int i = 0; i < 1234; ++i) {
    raw.insert(raw.end(), {g(rng), g(rng), g(rng) * 0.1f, std::abs(g(rng)) / 100.0f});
  }
  std::vector<std::uint8_t> bytes(raw.size() * sizeof(float));
  std::memcpy(bytes.data(), raw.data(), bytes.size());
  testing::WriteBytes(dir + "/000000.bin", bytes);
  const PointCloud cloud = LoadPointCloud(dir + "/000000.bin");
  ASSERT_EQ(cloud.points.size(), 1234u);
  for (size_t i = 0; i < 1234; ++i) {
    EXPECT_EQ(cloud.points[i], Eigen::Vector3d(raw[4 * i], raw[4 * i + 1], raw[4 * i + 2]));
    EXPECT_EQ(cloud.intensity[i], raw[4 * i + 3]);
  }
  EXPECT_EQ(cloud.frame, CloudFrame::kSensor);
  bytes.resize(bytes.size() - 6);
  testing::WriteBytes(dir + "/bad.bin", bytes);
  ExpectInputError([&] { LoadPointCloud(dir + "/bad.bin"); }, dir + "/bad.bin", "",
                   {"16-byte records", std::to_string(bytes.size()) + " bytes"});
}

}  // namespace
}  // namespace skerry::geo
