// The maps a dataset names, loaded and checked against its track at load time (real SRTM and
// Autzen files under ../shared/data), and the configuration's sensors against the dataset's.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "geo/geo_test_util.h"
#include "skerry/core/input_error.h"
#include "skerry/frontends/dataset_maps.h"
#include "skerry/frontends/dataset_sensors.h"
#include "skerry/solvers/estimator_config.h"

namespace skerry {
namespace {

const std::string kData = SKERRY_SHARED_DATA_DIR;

// A dataset on Lake Constance (the N47E009 tile) whose track is the given ENU points.
Dataset LakeDataset(const std::vector<Eigen::Vector3d>& track) {
  Dataset d;
  d.name = "lake";
  d.origin = {47.60, 9.45, 440.0};
  for (size_t k = 0; k < track.size(); ++k) {
    StampedPose p;
    p.t_ns = static_cast<TimeNs>(k) * 1'000'000'000;
    p.p_w_b = track[k];
    d.groundtruth.push_back(p);
  }
  d.dem.emplace();
  d.dem->path = kData + "/dem/N47E009.hgt";
  d.dem->vertical_datum = "egm96";
  return d;
}

class DatasetMapsTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!std::filesystem::exists(kData + "/dem/N47E009.hgt")) GTEST_SKIP() << "no shared data";
  }
};

TEST_F(DatasetMapsTest, DemCoveringTheTrackLoads) {
  const DatasetMaps maps =
      LoadDatasetMaps(LakeDataset({{0, 0, 0}, {2000, 1000, 0}, {-3000, 500, 0}}), 500.0);
  ASSERT_TRUE(maps.dem.has_value());
  // The lake surface under the origin: SRTM's 392 m plus EGM96's 46.4 m, ellipsoidal.
  const std::optional<double> h = maps.dem->HeightAt(Eigen::Vector3d::Zero());
  ASSERT_TRUE(h.has_value());
  EXPECT_NEAR(*h, 438.4, 4.0);
}

// A DEM too large to hold (the Lake Constance tile inside a 40000 x 40000 cell VRT, voids
// around it: a country's mosaic) is read only within the cameras' reach of the track: heights on
// the track are the tile's, the window spans the track's box and the reach, and a DEM that fits
// is still read whole.
TEST_F(DatasetMapsTest, ADemTooLargeToHoldIsReadWithinTheCamerasReachOfTheTrack) {
  const std::string dir = geo::testing::FreshDir("dem_window");
  const std::string vrt = dir + "/country.vrt";
  ASSERT_TRUE(
      geo::testing::GdalTranslate(kData + "/dem/N47E009.hgt", vrt,
                                  {"-of", "VRT", "-srcwin", "-18000", "-18000", "40000", "40000"}));
  const std::vector<Eigen::Vector3d> track = {{0, 0, 0}, {2000, 1000, 0}, {-3000, 500, 0}};
  const DatasetMaps tile = LoadDatasetMaps(LakeDataset(track), 500.0, 20000.0);
  EXPECT_EQ(tile.dem->cols(), 1201);  // it fits: whole (3" SRTM)
  Dataset country = LakeDataset(track);
  country.dem->path = vrt;
  const DatasetMaps maps = LoadDatasetMaps(country, 500.0, 20000.0);
  ASSERT_TRUE(maps.dem.has_value());
  // 45 km x 41 km at 3" (63 m x 93 m): about 720 x 450 cells, against 1.6 billion.
  EXPECT_LT(std::int64_t{maps.dem->cols()} * maps.dem->rows(), 400'000);
  const Eigen::AlignedBox2d reach(Eigen::Vector2d(-23000, -20000), Eigen::Vector2d(22000, 21000));
  EXPECT_TRUE(maps.dem->footprint_enu().contains(reach));
  EXPECT_LT(maps.dem->footprint_enu().volume(), 1.05 * reach.volume());
  for (const Eigen::Vector3d& p : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(-3000, 500, 0),
                                   Eigen::Vector3d(15000, -18000, 0)}) {
    ASSERT_TRUE(maps.dem->HeightAt(p).has_value()) << p.transpose();
    EXPECT_NEAR(*maps.dem->HeightAt(p), *tile.dem->HeightAt(p), 1e-6) << p.transpose();
  }
  // Without a window the VRT is refused by its size.
  try {
    geo::Dem(vrt, LocalFrame(country.origin), geo::DemOptions(geo::VerticalDatum::kEgm96));
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "size") << e.what();
  }
}

TEST_F(DatasetMapsTest, DemMissingTheTrackIsAnErrorNamingTheFile) {
  // 60 km east of the origin is past 10 E, off the tile.
  try {
    LoadDatasetMaps(LakeDataset({{0, 0, 0}, {60000, 0, 0}}));
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("N47E009.hgt"), std::string::npos) << e.what();
  }
}

TEST_F(DatasetMapsTest, OrthophotoMissingTheTrackIsAnError) {
  Dataset d;
  d.name = "autzen";
  d.origin = {44.0600, -123.0750, 120.0};  // near the Autzen stadium
  d.orthophoto.emplace();
  d.orthophoto->path = kData + "/autzen/autzen.jpg";
  StampedPose far;
  far.p_w_b = Eigen::Vector3d(5000.0, 0.0, 0.0);
  d.groundtruth = {far};
  try {
    LoadDatasetMaps(d);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("autzen.jpg"), std::string::npos) << e.what();
  }
}

// maps.orthophoto.clip_fraction reaches the orthophoto (which checks it before reading a pixel).
TEST_F(DatasetMapsTest, OrthophotoClipFractionReachesTheReader) {
  Dataset d;
  d.name = "autzen";
  d.origin = {44.0600, -123.0750, 120.0};
  d.orthophoto.emplace();
  d.orthophoto->path = kData + "/autzen/autzen.jpg";
  d.orthophoto->clip_fraction = 0.7;
  EXPECT_THROW(LoadDatasetMaps(d), std::invalid_argument);
  d.orthophoto->clip_fraction = 0.0;
  EXPECT_TRUE(LoadDatasetMaps(d).orthophoto.has_value());
}

// A map without a CRS names the dataset.yaml key that gives one, not the library's option.
TEST_F(DatasetMapsTest, AMapWithoutACrsNamesTheKeyThatGivesOne) {
  const std::string dir = ::testing::TempDir() + "/dataset_maps_no_crs";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  for (const char* f : {"autzen.jpg", "autzen.wld"}) {
    std::filesystem::copy_file(kData + "/autzen/" + f, dir + "/" + f);
  }
  Dataset d;
  d.name = "autzen";
  d.directory = dir;
  d.origin = {44.0600, -123.0750, 120.0};
  d.orthophoto.emplace();
  d.orthophoto->path = dir + "/autzen.jpg";
  try {
    LoadDatasetMaps(d);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), dir + "/autzen.jpg");
    EXPECT_EQ(e.field(), "crs");
    EXPECT_NE(e.message().find("maps.orthophoto.crs in " + dir + "/dataset.yaml"),
              std::string::npos)
        << e.what();
  }
  d.orthophoto->crs = kData + "/autzen/autzen-srs.wkt";
  EXPECT_TRUE(LoadDatasetMaps(d).orthophoto.has_value());
}

TEST(DatasetSensorsTest, ConfigurationNamingAnAbsentSensorIsAnError) {
  Dataset d;
  d.name = "no pose fixes";
  EstimatorConfig config;
  config.sensors["pose_fixes"] = SensorOptions();
  EXPECT_THROW(DatasetSensors(d, config), std::invalid_argument);
  config.sensors.clear();
  EXPECT_TRUE(DatasetSensors(d, config).sensors.empty());
}

}  // namespace
}  // namespace skerry
