// A simulated camera dataset end to end (skerry simulate's path: Simulate, RenderCameraImages,
// WriteDataset, LoadDataset, DatasetSensors, RunWindow), and the bad input the issue lists: an
// image of the wrong size, a mask with no sky, a camera without a DEM, a DEM that misses the
// track. Clear errors naming the file, or a frame skipped and counted; never a crash.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>

#include "skerry/core/input_error.h"
#include "skerry/frontends/dataset_sensors.h"
#include "skerry/geo/dem.h"
#include "skerry/sim/scenario.h"
#include "skerry/sim/simulator.h"
#include "skerry/solvers/pipeline.h"

namespace skerry {
namespace {

namespace fs = std::filesystem;

const std::string kDem = std::string(SKERRY_SHARED_DATA_DIR) + "/dem/N43E007.hgt";

// The Côte d'Azur scenario cut to 40 s (GNSS throughout), written to a fresh folder.
std::string MakeDataset(const std::string& name, double duration_s = 40.0) {
  sim::ScenarioConfig sc =
      sim::LoadScenario(std::string(SKERRY_SOURCE_DIR) + "/bench/figures/cote-dazur-skyline.yaml");
  sc.duration_s = duration_s;
  sc.gnss.outages.clear();
  const std::string dir = std::string(SKERRY_TEST_TMP_DIR) + "/" + name;
  fs::remove_all(dir);
  Dataset data = sim::Simulate(sc, 3);
  sim::RenderCameraImages(sc, 3, &data, dir);
  WriteDataset(data, dir);
  return dir;
}

class SkylineDataset : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(kDem)) GTEST_SKIP() << kDem << " missing";
  }
};

TEST_F(SkylineDataset, SimulatedFramesBecomeBlocksAndTheWindowTakesThem) {
  const std::string dir = MakeDataset("cam_ok");
  const Dataset data = LoadDataset(dir);
  ASSERT_EQ(data.cameras.size(), 1u);
  ASSERT_EQ(data.camera_frames[0].size(), 40u);
  const EstimatorConfig config = LoadPreset("default");
  const SensorLog log = DatasetSensors(data, config);
  ASSERT_EQ(log.frontend_stats.count("camera"), 1u);
  EXPECT_EQ(log.frontend_stats.at("camera").at("blocks"), 40.0);
  const WindowRun run = RunWindow(data, config, {}, nullptr, log);
  size_t camera = 0;
  while (camera < run.sensors.sensors.size() && run.sensors.sensors[camera].name != "camera") {
    ++camera;
  }
  ASSERT_LT(camera, run.sensor_stats.size());
  EXPECT_GE(run.sensor_stats[camera].accepted, 37);
  EXPECT_LE(run.sensor_stats[camera].rejected, 2);
}

TEST_F(SkylineDataset, BadImagesAndMaps) {
  const std::string dir = MakeDataset("cam_bad", 6.0);
  const EstimatorConfig config = LoadPreset("default");
  Dataset data = LoadDataset(dir);
  const std::string first = data.cameras[0].image_dir + "/" + data.camera_frames[0][0].file;
  const std::string second = data.cameras[0].image_dir + "/" + data.camera_frames[0][1].file;
  // A mask without sky: the frame is skipped and counted.
  cv::imwrite(second, cv::Mat(1080, 1920, CV_8UC1, cv::Scalar(0)));
  {
    const SensorLog log = DatasetSensors(data, config);
    EXPECT_EQ(log.frontend_stats.at("camera").at("skipped_no_sky"), 1.0);
    EXPECT_EQ(log.frontend_stats.at("camera").at("blocks"), 5.0);
  }
  // An image of the wrong size: an error naming the file and both sizes.
  cv::imwrite(first, cv::Mat(480, 640, CV_8UC1, cv::Scalar(255)));
  try {
    DatasetSensors(data, config);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(first), std::string::npos) << what;
    EXPECT_NE(what.find("640x480"), std::string::npos) << what;
  }
  // A file that is not an image.
  { std::ofstream(first) << "not a png"; }
  EXPECT_THROW(DatasetSensors(data, config), InputError);
  // A camera without a DEM.
  Dataset no_dem = data;
  no_dem.dem.reset();
  EXPECT_THROW(DatasetSensors(no_dem, config), std::invalid_argument);
  // A DEM that does not cover the track: moved 200 km north.
  Dataset far = data;
  for (auto& s : far.truth_states) s.p_w_b.y() += 200000.0;
  for (auto& g : far.groundtruth) g.p_w_b.y() += 200000.0;
  EXPECT_THROW(DatasetSensors(far, config), InputError);
}

// The named skyline scenarios keep the vessel on water, at least 300 m from any shore, and
// floating on the DEM's water surface (the origin's height is the water's).
TEST_F(SkylineDataset, ScenarioTracksStayOnWater) {
  for (const char* name : {"cote-dazur-skyline", "lake-constance-skyline"}) {
    const sim::ScenarioConfig sc =
        sim::LoadScenario(std::string(SKERRY_SOURCE_DIR) + "/bench/figures/" + name + ".yaml");
    ASSERT_TRUE(sc.dem.has_value());
    if (!fs::exists(sc.dem->path)) GTEST_SKIP() << sc.dem->path << " missing";
    sim::ScenarioConfig fast = sc;
    fast.camera.enabled = false;
    fast.imu.rate_hz = 20.0;
    const Dataset data = sim::Simulate(fast, 1);
    const LocalFrame frame(data.origin);
    const geo::Dem dem(sc.dem->path, frame, geo::DemOptions(geo::VerticalDatum::kEgm96));
    const double water = *dem.RasterHeight(sc.origin.lat_deg, sc.origin.lon_deg);
    EXPECT_NEAR(*dem.EllipsoidalHeight(sc.origin.lat_deg, sc.origin.lon_deg), sc.origin.height_m,
                0.05)
        << name;
    for (size_t i = 0; i < data.truth_states.size(); i += 100) {
      for (int k = 0; k < 8; ++k) {
        const Eigen::Vector3d p =
            data.truth_states[i].p_w_b +
            300.0 * Eigen::Vector3d(std::sin(k * M_PI / 4), std::cos(k * M_PI / 4), 0.0);
        const Eigen::Vector3d llh = frame.ToGeodetic(p);
        const auto h = dem.RasterHeight(llh.x(), llh.y());
        ASSERT_TRUE(h.has_value()) << name;
        ASSERT_NEAR(*h, water, 0.5)
            << name << " leaves the water at t=" << NsToSeconds(data.truth_states[i].t_ns);
      }
    }
  }
}

}  // namespace
}  // namespace skerry
