// A simulated camera dataset end to end (skerry simulate's path: Simulate, RenderCameraImages,
// WriteDataset, LoadDataset, DatasetSensors, RunWindow), and the bad input the issue lists: an
// image of the wrong size, a mask with no sky, a camera without a DEM, a DEM that misses the
// track. Clear errors naming the file, or a frame skipped and counted; never a crash.

#include <gtest/gtest.h>

#include <cmath>
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
  EstimatorConfig config = LoadPreset("default");
  // No time limit per solve: with the default's 0.2 s a slow machine (a sanitizer build beside
  // other tests) stops some solves early, and the two runs below would differ by the clock.
  config.ceres.max_time_s = 0.0;
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
  // Per frame (the run folder's blocks.csv): every frame's samples, and for every frame the
  // window decided on, its weight and map term as the window made its block.
  const FrontendBlockTable table = run.sensors.live_frontend_blocks.at("camera")();
  ASSERT_EQ(table.columns,
            (std::vector<std::string>{"samples", "frame_weight", "crest_shift_m", "map_sigma_px"}));
  ASSERT_EQ(table.rows.size(), 40u);
  for (const auto& [t, row] : table.rows) EXPECT_GE(row[0], config.skyline.min_samples);
  int decided = 0;
  for (const SensorRecord& d : run.sensors.decisions) {
    if (d.sensor != static_cast<SensorId>(camera) || d.decision == SensorDecision::kDropped) {
      continue;
    }
    const std::vector<double>& row = table.rows.at(d.t_ns);
    EXPECT_GT(row[1], 0.0);
    EXPECT_LE(row[1], 1.0);
    EXPECT_GE(row[3], 0.0);  // dem_sigma_m is on in the default preset
    ++decided;
  }
  EXPECT_GE(decided, 38);
  // The first frame has no frame before it to measure its crests' shift against.
  EXPECT_TRUE(std::isnan(table.rows.begin()->second[2]));
  EXPECT_GT(config.skyline.dem_sigma_m, 0.0);

  // skyline.threads (`skerry run -j 3`): the frames read and their horizons traced on three
  // threads give the same estimate to the last bit.
  EstimatorConfig threaded = config;
  threaded.skyline.threads = 3;
  const WindowRun again = RunWindow(data, threaded, {}, nullptr, DatasetSensors(data, threaded));
  ASSERT_EQ(again.records.size(), run.records.size());
  ASSERT_GT(run.records.size(), 100u);
  for (size_t i = 0; i < run.records.size(); ++i) {
    const NavState& a = run.records[i].state;
    const NavState& b = again.records[i].state;
    ASSERT_EQ(a.t_ns, b.t_ns);
    ASSERT_EQ(a.q_w_b.coeffs(), b.q_w_b.coeffs()) << i;
    ASSERT_EQ(a.p_w_b, b.p_w_b) << i;
    ASSERT_EQ(a.v_w, b.v_w) << i;
    ASSERT_EQ(run.records[i].covariance, again.records[i].covariance) << i;
  }
}

// The DEM's error (sim/dem_error.h) changes the world the frames are rendered from, not the map
// the dataset names: the skyline moves by a fraction of a pixel to a few pixels (crests 20-40 km
// away, 8 m of height error), and with no error the frames are the same files as before.
TEST_F(SkylineDataset, TheDemErrorChangesTheWorldAndNotTheMap) {
  sim::ScenarioConfig sc =
      sim::LoadScenario(std::string(SKERRY_SOURCE_DIR) + "/bench/figures/cote-dazur-skyline.yaml");
  sc.duration_s = 3.0;
  const Dataset data = sim::Simulate(sc, 2);
  const auto render = [&](double sigma_m, const std::string& name) {
    sim::ScenarioConfig with = sc;
    with.dem->error = {sigma_m, 1000.0};
    Dataset d = data;
    const std::string dir = std::string(SKERRY_TEST_TMP_DIR) + "/" + name;
    fs::remove_all(dir);
    sim::RenderCameraImages(with, 2, &d, dir);
    EXPECT_EQ(d.dem->path, data.dem->path);
    std::vector<cv::Mat> masks;
    for (const SensorFrame& f : d.camera_frames[0]) {
      masks.push_back(cv::imread(d.cameras[0].image_dir + "/" + f.file, cv::IMREAD_UNCHANGED));
    }
    return masks;
  };
  const std::vector<cv::Mat> plain = render(0.0, "dem_err_0"), again = render(0.0, "dem_err_0b");
  const std::vector<cv::Mat> wrong = render(8.0, "dem_err_8");
  ASSERT_EQ(plain.size(), 3u);
  ASSERT_EQ(wrong.size(), 3u);
  int moved_columns = 0, columns = 0;
  for (size_t k = 0; k < plain.size(); ++k) {
    EXPECT_EQ(cv::countNonZero(plain[k] != again[k]), 0);
    // Per column, the sky's lowest row: where the skyline is.
    for (int u = 0; u < plain[k].cols; u += 4) {
      const auto sky_rows = [u](const cv::Mat& m) { return cv::countNonZero(m.col(u)); };
      const int a = sky_rows(plain[k]), b = sky_rows(wrong[k]);
      if (a == 0 || a == plain[k].rows) continue;
      ++columns;
      if (a != b) ++moved_columns;
      EXPECT_LE(std::abs(a - b), 6) << "frame " << k << " column " << u;
    }
  }
  ASSERT_GT(columns, 500);
  EXPECT_GT(moved_columns, columns / 20);
}

// Frames rendered on several threads are the files one thread writes: each frame's noise seed is
// drawn in order before any is rendered.
TEST_F(SkylineDataset, FramesRenderedInParallelAreTheSameFiles) {
  sim::ScenarioConfig sc =
      sim::LoadScenario(std::string(SKERRY_SOURCE_DIR) + "/bench/figures/cote-dazur-skyline.yaml");
  sc.duration_s = 4.0;
  sc.camera.ring = true;      // four cameras: frames of several cameras in flight at once
  sc.camera.images = "grey";  // the shaded image carries the seeded pixel noise
  sc.camera.width_px = 480;   // small frames: the test is about threads, not pixels
  sc.camera.height_px = 270;
  Dataset data = sim::Simulate(sc, 5);
  const std::string one = std::string(SKERRY_TEST_TMP_DIR) + "/cam_threads_1";
  const std::string three = std::string(SKERRY_TEST_TMP_DIR) + "/cam_threads_3";
  fs::remove_all(one);
  fs::remove_all(three);
  Dataset a = data, b = data;
  sim::RenderCameraImages(sc, 5, &a, one, {}, 1);
  int calls = 0;
  double last = 0.0;
  sim::RenderCameraImages(
      sc, 5, &b, three,
      [&](double f) {
        ++calls;
        last = f;
      },
      3);
  ASSERT_EQ(a.cameras.size(), 4u);
  size_t frames = 0;
  for (size_t k = 0; k < a.cameras.size(); ++k) {
    for (const SensorFrame& f : a.camera_frames[k]) {
      const auto read = [](const std::string& path) {
        std::ifstream in(path, std::ios::binary);
        return std::string(std::istreambuf_iterator<char>(in), {});
      };
      const std::string x = read(a.cameras[k].image_dir + "/" + f.file);
      ASSERT_FALSE(x.empty()) << f.file;
      EXPECT_EQ(x, read(b.cameras[k].image_dir + "/" + f.file))
          << a.cameras[k].name << " " << f.file;
      ++frames;
    }
  }
  EXPECT_EQ(frames, 16u);
  EXPECT_EQ(calls, 16);
  EXPECT_EQ(last, 1.0);
  // Two frames of one camera differ (their noise seeds do): the comparison can fail.
  const std::string d = a.cameras[0].image_dir + "/";
  std::ifstream f0(d + a.camera_frames[0][0].file, std::ios::binary),
      f1(d + a.camera_frames[0][1].file, std::ios::binary);
  EXPECT_NE(std::string(std::istreambuf_iterator<char>(f0), {}),
            std::string(std::istreambuf_iterator<char>(f1), {}));
}

TEST_F(SkylineDataset, BadImagesAndMaps) {
  const std::string dir = MakeDataset("cam_bad", 6.0);
  EstimatorConfig config = LoadPreset("default");
  // Every check below builds the frontend's map again: at 200 m instead of half the DEM's cell
  // it takes a fortieth of the time, and no check here is about the map's detail.
  config.skyline.dem_spacing_m = 200.0;
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
  // A header announcing 30000 x 30000 16-bit RGB pixels in 23 bytes: refused from its header,
  // before OpenCV would ask for 5.4 GB to decode it.
  {
    std::ofstream(first, std::ios::binary) << "P6\n30000 30000\n65535\nabc";
    try {
      DatasetSensors(data, config);
      FAIL() << "expected an InputError";
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), first);
      EXPECT_NE(e.message().find("image is 30000x30000, the camera's 1920x1080"), std::string::npos)
          << e.what();
    }
  }
  // A file that is not an image.
  { std::ofstream(first) << "not a png"; }
  EXPECT_THROW(DatasetSensors(data, config), InputError);
  // Frames read on several threads (skyline.threads): the same counts, and of two bad frames
  // the error names the earlier, whichever thread meets which first.
  {
    EstimatorConfig threaded = config;
    threaded.skyline.threads = 3;
    const std::string fifth = data.cameras[0].image_dir + "/" + data.camera_frames[0][4].file;
    cv::imwrite(fifth, cv::Mat(480, 640, CV_8UC1, cv::Scalar(255)));
    for (int repeat = 0; repeat < 5; ++repeat) {
      try {
        DatasetSensors(data, threaded);
        FAIL() << "expected an InputError";
      } catch (const InputError& e) {
        EXPECT_EQ(e.file(), first);
        EXPECT_NE(e.message().find("cannot be read"), std::string::npos) << e.what();
      }
    }
    Dataset rest = data;  // without the first frame: the fifth is the first bad one
    rest.camera_frames[0].erase(rest.camera_frames[0].begin());
    try {
      DatasetSensors(rest, threaded);
      FAIL() << "expected an InputError";
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), fifth);
      EXPECT_NE(std::string(e.what()).find("640x480"), std::string::npos) << e.what();
    }
    // Without the fifth and the sixth too: the frame without sky and two good ones.
    rest.camera_frames[0].resize(3);
    const SensorLog log = DatasetSensors(rest, threaded);
    EXPECT_EQ(log.frontend_stats.at("camera").at("skipped_no_sky"), 1.0);
    EXPECT_EQ(log.frontend_stats.at("camera").at("blocks"), 2.0);
  }
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
