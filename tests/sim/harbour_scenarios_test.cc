// The harbour LiDAR scenarios (issue 12): prior work's three runs with both GNSS disturbances and
// the ten-minute tour are as briefed, every one keeps its hull clear of the harbour and every scan
// sees the harbour; and a short harbour run end to end through Simulate, the aerial image, the
// LiDAR scans, WriteDataset and LoadDataset.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "sim/sim_test_util.h"
#include "skerry/geo/orthophoto.h"
#include "skerry/geo/point_cloud.h"
#include "skerry/io/dataset.h"
#include "skerry/sim/aerial_render.h"
#include "skerry/sim/harbour_world.h"
#include "skerry/sim/lidar_scans.h"
#include "skerry/sim/simulator.h"

namespace skerry::sim {
namespace {

const std::vector<std::string> kRuns = {"enter-starboard", "enter-turn", "stationary"};

std::vector<std::string> AllNames() {
  std::vector<std::string> names;
  for (const std::string& run : kRuns) {
    names.push_back("harbour-lidar-" + run + "-drift");
    names.push_back("harbour-lidar-" + run + "-jump");
  }
  names.push_back("harbour-lidar-tour");
  return names;
}

TEST(HarbourScenarios, PriorWorksRunsAndTheTourAreAsBriefed) {
  for (const std::string& run : kRuns) {
    SCOPED_TRACE(run);
    const ScenarioConfig drift = testing::SourceScenario("harbour-lidar-" + run + "-drift");
    const ScenarioConfig jump = testing::SourceScenario("harbour-lidar-" + run + "-jump");
    for (const ScenarioConfig* c : {&drift, &jump}) {
      EXPECT_GE(c->duration_s, 60.0);
      EXPECT_LE(c->duration_s, 120.0);
      EXPECT_TRUE(c->gnss.rate_hz == 5.0 || c->gnss.rate_hz == 10.0);
      EXPECT_TRUE(c->water_surface_enabled);
      EXPECT_TRUE(c->harbour.enabled && c->harbour.aerial_image.enabled && c->lidar.enabled);
      EXPECT_DOUBLE_EQ(c->harbour.aerial_image.resolution_m, 0.16);
      EXPECT_EQ(c->lidar.beams, 32);
      EXPECT_DOUBLE_EQ(c->lidar.rotation_rate_hz, 10.0);
      EXPECT_DOUBLE_EQ(c->lidar.max_range_m, 100.0);
      EXPECT_DOUBLE_EQ(c->lidar.range_noise_sigma_m, 0.03);
      // A slow drift of a few metres.
      EXPECT_GE(c->gnss.drift_sigma_horizontal_m, 1.0);
      EXPECT_GE(c->gnss.drift_tau_s, c->duration_s);
      EXPECT_TRUE(c->gnss.outages.empty());
    }
    EXPECT_TRUE(drift.gnss.jumps.empty());
    ASSERT_EQ(jump.gnss.jumps.size(), 1u);
    EXPECT_DOUBLE_EQ(jump.gnss.jumps[0].offset_enu_m.norm(), 14.5);
    EXPECT_GE(jump.gnss.jumps[0].duration_s, 10.0);
    EXPECT_LE(jump.gnss.jumps[0].start_s + jump.gnss.jumps[0].duration_s, jump.duration_s);
    // The two disturbances of a run share everything else.
    EXPECT_EQ(drift.trajectory.legs.size(), jump.trajectory.legs.size());
    EXPECT_EQ(drift.trajectory.start_enu_m, jump.trajectory.start_enu_m);
    EXPECT_EQ(drift.gnss.drift_sigma_horizontal_m, jump.gnss.drift_sigma_horizontal_m);
    EXPECT_EQ(drift.imu.grade, jump.imu.grade);
  }
  EXPECT_DOUBLE_EQ(
      testing::SourceScenario("harbour-lidar-stationary-drift").trajectory.start_speed_m_s, 0.0);
  // The tour: ten minutes, GNSS lost after the first to the end, moderate waves, heel in turns.
  const ScenarioConfig tour = testing::SourceScenario("harbour-lidar-tour");
  EXPECT_DOUBLE_EQ(tour.duration_s, 600.0);
  ASSERT_EQ(tour.gnss.outages.size(), 1u);
  EXPECT_DOUBLE_EQ(tour.gnss.outages[0].start_s, 60.0);
  EXPECT_GE(tour.gnss.outages[0].start_s + tour.gnss.outages[0].duration_s, tour.duration_s);
  EXPECT_GT(tour.trajectory.heel_deg_per_m_s2, 0.0);
  ASSERT_FALSE(tour.waves.roll_deg.empty());
  EXPECT_GE(tour.waves.roll_deg[0].amplitude, 1.0);
}

class HarbourRun : public ::testing::TestWithParam<std::string> {};

// The hull at every truth state clear of every box (those of the photograph's time too), and
// every scan (at a coarser azimuth step, to keep the test short) with returns from the harbour,
// not only from the own hull. The tour passes along the channel for at least 150 m.
TEST_P(HarbourRun, TheHullStaysInTheWaterAndEveryScanSeesTheHarbour) {
  ScenarioConfig c = testing::SourceScenario(GetParam());
  c.imu.rate_hz = 20.0;  // the truth does not depend on it; the test runs faster
  const Dataset d = Simulate(c, c.seed);
  const HarbourWorld world = BuildHarbour(c.harbour, c.seed);
  int touching = 0;
  for (const NavState& s : d.truth_states) {
    OrientedBox hull;
    hull.R_w_box = s.q_w_b.toRotationMatrix();
    hull.centre_w = s.p_w_b + hull.R_w_box * c.lidar.hull_centre_b_m;
    hull.half_size_m = 0.5 * c.lidar.hull_size_m;
    if (world.Intersects(hull, WorldView::kAll)) {
      if (++touching < 5)
        ADD_FAILURE() << "the hull touches the harbour at " << NsToSeconds(s.t_ns);
    }
  }
  EXPECT_EQ(touching, 0);

  ASSERT_EQ(d.lidar_scans.size(), 1u);
  EXPECT_GE(d.lidar_scans[0].size(), static_cast<size_t>(c.duration_s * c.lidar.write_rate_hz) - 1);
  LidarModelSim coarse = c.lidar;
  coarse.azimuth_step_deg = 2.0;
  const BodyPoseAt pose = [&d](TimeNs t, Eigen::Quaterniond* q, Eigen::Vector3d* p) {
    // The truth at 50 Hz; the nearest state is close enough for counting returns.
    const size_t k = static_cast<size_t>(std::llround(NsToSeconds(t) * 50.0));
    if (k >= d.truth_states.size()) return false;
    *q = d.truth_states[k].q_w_b;
    *p = d.truth_states[k].p_w_b;
    return true;
  };
  size_t fewest = 1000000;
  double fewest_at = 0.0;
  for (const SensorFrame& f : d.lidar_scans[0]) {
    size_t harbour = 0;
    for (const LidarPoint& p : SimulateLidarScan(world, coarse, pose, f.t_ns, 1).points) {
      harbour += !p.hull;
    }
    if (harbour < fewest) {
      fewest = harbour;
      fewest_at = NsToSeconds(f.t_ns);
    }
  }
  EXPECT_GE(fewest, 10u) << "at " << fewest_at << " s";

  if (GetParam() == "harbour-lidar-tour") {
    const HarbourLayout l = HarbourLayoutOf(c.harbour);
    const Eigen::Vector2d along = (l.channel_end_w - l.channel_mouth_w).normalized();
    const double length = (l.channel_end_w - l.channel_mouth_w).norm();
    double in_channel = 0.0;
    for (size_t k = 1; k < d.truth_states.size(); ++k) {
      const Eigen::Vector2d p = d.truth_states[k].p_w_b.head<2>() - l.channel_mouth_w;
      const double s = p.dot(along);
      if (s > 0.0 && s < length && std::abs(p.x() * along.y() - p.y() * along.x()) < 20.0) {
        in_channel += (d.truth_states[k].p_w_b - d.truth_states[k - 1].p_w_b).head<2>().norm();
      }
    }
    EXPECT_GE(in_channel, 2 * 200.0);  // up the channel and back down it
  }
}

INSTANTIATE_TEST_SUITE_P(Scenarios,
                         HarbourRun,
                         ::testing::ValuesIn(AllNames()),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                           std::string name =
                               info.param.substr(std::string("harbour-lidar-").size());
                           for (char& ch : name) {
                             if (ch == '-') ch = '_';
                           }
                           return name;
                         });

TEST(HarbourScenarios, AShortRunEndToEndThroughTheDatasetFolder) {
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(SKERRY_TEST_TMP_DIR) / "harbour_end_to_end";
  fs::remove_all(dir);
  fs::create_directories(dir);
  {
    std::ofstream out(dir / "short.yaml");
    out << R"(name: short-harbour
duration_s: 5
origin: {lat_deg: 47.6, lon_deg: 9.45, height_m: 440}
imu: {rate_hz: 50}
gnss: {rate_hz: 5}
water_surface: {enabled: true}
harbour:
  aerial_image: {resolution_m: 1.0, margin_m: 10}
lidar:
  write_rate_hz: 2
  time_offset_s: 0.13
  azimuth_step_deg: 1.0
trajectory:
  start: {east_m: 80, north_m: -60, heading_deg: 0, speed_m_s: 3}
)";
  }
  const ScenarioConfig c = LoadScenario((dir / "short.yaml").string());
  Dataset d = Simulate(c, 1);
  ASSERT_EQ(d.lidars.size(), 1u);
  // Sweeps starting at 0.13 + k / 2 s and ending by 5 s: 0.13 ... 4.63.
  ASSERT_EQ(d.lidar_scans[0].size(), 10u);
  std::vector<double> progress;
  RenderAerialImage(c, 1, &d, (dir / "out").string());
  RenderLidarScans(c, 1, &d, (dir / "out").string(), [&](double f) { progress.push_back(f); });
  ASSERT_EQ(progress.size(), 10u);
  EXPECT_DOUBLE_EQ(progress.back(), 1.0);
  ASSERT_TRUE(d.orthophoto.has_value());
  WriteDataset(d, (dir / "out").string());

  const Dataset loaded = LoadDataset((dir / "out").string());
  ASSERT_EQ(loaded.lidars.size(), 1u);
  EXPECT_EQ(loaded.lidars[0].name, "lidar");
  EXPECT_EQ(loaded.lidars[0].T_b_l.p_b_s, Eigen::Vector3d(0, 0, 3));
  EXPECT_TRUE(loaded.lidars[0].T_b_l.q_b_s.isApprox(Eigen::Quaterniond::Identity()));
  ASSERT_EQ(loaded.lidar_scans[0].size(), 10u);
  for (size_t k = 0; k < 10; ++k) {
    const SensorFrame& f = loaded.lidar_scans[0][k];
    EXPECT_EQ(f.t_ns, d.lidar_scans[0][k].t_ns);
    EXPECT_EQ(f.t_ns, SecondsToNs(0.13 + 0.5 * k));
    const geo::PointCloud cloud =
        geo::LoadPointCloud((fs::path(loaded.lidars[0].scan_dir) / f.file).string());
    ASSERT_GT(cloud.points.size(), 500u) << f.file;
    ASSERT_EQ(cloud.time_s.size(), cloud.points.size());
    for (const float t : cloud.time_s) {
      ASSERT_GE(t, 0.0f);
      ASSERT_LT(t, 0.1f);
    }
  }
  // The photograph loads (world file, .prj) and covers the whole track.
  ASSERT_TRUE(loaded.orthophoto.has_value());
  const geo::Orthophoto ortho(loaded.orthophoto->path, LocalFrame(loaded.origin));
  EXPECT_NEAR(ortho.ground_sample_distance_m(), 1.0, 0.01);
  for (const StampedPose& p : loaded.groundtruth) EXPECT_TRUE(ortho.Covers(p.p_w_b));
  ASSERT_TRUE(loaded.water_surface.has_value());
  // A configuration built in code that LoadScenario would refuse, or with more boats than fit
  // along the quays, is refused by Simulate before anything is rendered.
  ScenarioConfig crowded = c;
  crowded.harbour.boats_moored = 150;
  EXPECT_THROW(Simulate(crowded, 1), std::invalid_argument);
  ScenarioConfig nowhere = c;
  nowhere.harbour.enabled = false;
  EXPECT_THROW(Simulate(nowhere, 1), std::invalid_argument);
}

}  // namespace
}  // namespace skerry::sim
