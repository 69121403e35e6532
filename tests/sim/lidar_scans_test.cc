// The simulated spinning LiDAR: a wall at a known range with the range noise's statistics, the
// skew of a moving or turning vessel's sweep, no returns from the water, returns from the own
// hull, dropout rising with range, and the binary PCD read back by geo::LoadPointCloud.

#include "skerry/sim/lidar_scans.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "skerry/geo/point_cloud.h"

namespace skerry::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;

HarbourBox Wall(double x0, double x1, double y0, double y1) {
  HarbourBox b;
  b.kind = HarbourObjectKind::kQuay;
  b.centre_w = Eigen::Vector2d(0.5 * (x0 + x1), 0.5 * (y0 + y1));
  b.length_m = x1 - x0;
  b.width_m = y1 - y0;
  b.bottom_m = -5.0;
  b.top_m = 12.0;
  b.reflectivity = 0.4;
  return b;
}

// A wall whose face is the plane x = 20, 100 m wide; the water at 0.
HarbourWorld WallAhead() { return HarbourWorld({Wall(20, 30, -50, 50)}, 0.0); }

// The default LiDAR (32 beams, -25..15 deg, 0.4 deg, 3 m above the body origin), without its
// hull and dropout unless a test wants them.
LidarModelSim Model() {
  LidarModelSim m;
  m.enabled = true;
  m.hull_size_m.setZero();
  m.dropout_at_max_range = 0.0;
  return m;
}

BodyPoseAt Static(const Eigen::Vector3d& p = Eigen::Vector3d::Zero()) {
  return [p](TimeNs, Eigen::Quaterniond* q, Eigen::Vector3d* out) {
    q->setIdentity();
    *out = p;
    return true;
  };
}

TEST(LidarScans, AWallAtAKnownRangeWithTheRangeNoiseAsModelled) {
  const LidarModelSim model = Model();
  const LidarScan scan = SimulateLidarScan(WallAhead(), model, Static(), 0, 5);
  const std::vector<double> elevations = LidarBeamElevations(model);
  ASSERT_EQ(elevations.size(), 32u);
  EXPECT_NEAR(elevations.front(), -25.0 * kPi / 180.0, 1e-12);
  EXPECT_NEAR(elevations.back(), 15.0 * kPi / 180.0, 1e-12);
  // A point on the wall is d (r + n) with d its beam's direction: its x is 20 + d_x n, so
  // n = (x - 20) / d_x. Nothing else is in the world, and nothing below the water.
  double sum = 0.0, sum2 = 0.0;
  int n = 0;
  for (const LidarPoint& p : scan.points) {
    const Eigen::Vector3d pl = p.p_l.cast<double>();
    const Eigen::Vector3d d = pl.normalized();
    ASSERT_GT(pl.x(), 15.0);
    EXPECT_GE(pl.z() + 3.0, -0.15) << "below the water";
    const double noise = (pl.x() - 20.0) / d.x();
    sum += noise;
    sum2 += noise * noise;
    ++n;
    // On one of the beams, with the Lambertian intensity 100 * 0.4 * cos(incidence).
    const double e = std::asin(d.z());
    double nearest = 1.0;
    for (const double b : elevations) nearest = std::min(nearest, std::abs(b - e));
    EXPECT_LT(nearest, 1e-3);
    EXPECT_NEAR(p.intensity, 40.0 * d.x(), 0.01);
    EXPECT_FALSE(p.hull);
  }
  // The wall spans +-68 deg of azimuth (340 steps of 0.4 deg) and the 18 beams from -6.9 to 15
  // deg reach it above the water.
  ASSERT_GT(n, 4000);
  const double mean = sum / n;
  const double sigma = std::sqrt(sum2 / n - mean * mean);
  EXPECT_LT(std::abs(mean), 4.0 * 0.03 / std::sqrt(n));
  EXPECT_NEAR(sigma, 0.03, 0.03 * 4.0 / std::sqrt(2.0 * n));  // 4 sigma of a sample sigma
  // No noise: every point exactly on the wall.
  LidarModelSim exact = model;
  exact.range_noise_sigma_m = 0.0;
  for (const LidarPoint& p : SimulateLidarScan(WallAhead(), exact, Static(), 0, 5).points) {
    EXPECT_NEAR(p.p_l.x(), 20.0, 1e-4);
  }
}

TEST(LidarScans, AMovingVesselsScanIsSkewedAsTheMotionPredicts) {
  LidarModelSim model = Model();
  model.range_noise_sigma_m = 0.0;
  const TimeNs t0 = SecondsToNs(1.0);
  // Standing 5 m from the origin: the wall 15 m ahead whatever the time. Moving at 5 m/s towards
  // it, there at the stamp (1 s): a point fired t after the stamp sees it 20 - 5 (1 + t) m
  // ahead, 0.5 m nearer at the end of the sweep's 0.1 s than at its start.
  const double v = 5.0;
  const BodyPoseAt moving = [v](TimeNs t, Eigen::Quaterniond* q, Eigen::Vector3d* p) {
    q->setIdentity();
    *p = Eigen::Vector3d(v * NsToSeconds(t), 0, 0);
    return true;
  };
  const LidarScan still = SimulateLidarScan(WallAhead(), model, Static({5, 0, 0}), t0, 1);
  const LidarScan scan = SimulateLidarScan(WallAhead(), model, moving, t0, 1);
  ASSERT_GT(scan.points.size(), 4000u);
  EXPECT_EQ(scan.t_ns, t0);
  float x_min = 1e9f, x_max = -1e9f;
  float last_t = 0.0f;
  for (const LidarPoint& p : scan.points) {
    EXPECT_GE(p.t_s, last_t);  // in firing order
    last_t = p.t_s;
    EXPECT_LT(p.t_s, 0.1f);
    EXPECT_NEAR(p.p_l.x(), 20.0 - v * (1.0 + p.t_s), 2e-4);
    x_min = std::min(x_min, p.p_l.x());
    x_max = std::max(x_max, p.p_l.x());
  }
  // The azimuths facing the wall (+-73 deg about ahead) span 0.4 of the sweep: 0.2 m.
  EXPECT_GT(x_max - x_min, 0.18);
  for (const LidarPoint& p : still.points) EXPECT_NEAR(p.p_l.x(), 15.0, 1e-4);
  // Turning at 0.5 rad/s in place: a point fired at t leaves in the world direction
  // Rz(0.5 (1 + t)) d_l and meets the wall at 20 / (that direction's x).
  const double omega = 0.5;
  const BodyPoseAt turning = [omega](TimeNs t, Eigen::Quaterniond* q, Eigen::Vector3d* p) {
    *q = Eigen::AngleAxisd(omega * NsToSeconds(t), Eigen::Vector3d::UnitZ());
    p->setZero();
    return true;
  };
  const LidarScan turned = SimulateLidarScan(WallAhead(), model, turning, t0, 1);
  ASSERT_GT(turned.points.size(), 4000u);
  double worst = 0.0;
  for (const LidarPoint& p : turned.points) {
    const Eigen::Vector3d d = p.p_l.cast<double>().normalized();
    const Eigen::Vector3d d_w =
        Eigen::AngleAxisd(omega * (1.0 + p.t_s), Eigen::Vector3d::UnitZ()) * d;
    worst = std::max(worst, std::abs(p.p_l.cast<double>().norm() - 20.0 / d_w.x()));
  }
  EXPECT_LT(worst, 2e-3);
}

TEST(LidarScans, NoReturnsFromTheWaterButFromTheOwnHull) {
  // Nothing within range but the water: no returns at all.
  const HarbourWorld open_water({Wall(300, 310, -5, 5)}, 0.0);
  LidarModelSim model = Model();
  EXPECT_TRUE(SimulateLidarScan(open_water, model, Static(), 0, 1).points.empty());
  // With the hull (15 x 4.5 m, deck 1.5 m above the body origin, 1.5 m below the LiDAR): its
  // returns lie on the deck, flagged.
  model.hull_size_m = Eigen::Vector3d(15.0, 4.5, 2.5);
  model.hull_centre_b_m = Eigen::Vector3d(0.0, 0.0, 0.25);
  const LidarScan scan = SimulateLidarScan(open_water, model, Static(), 0, 1);
  ASSERT_GT(scan.points.size(), 1000u);
  for (const LidarPoint& p : scan.points) {
    ASSERT_TRUE(p.hull);
    const Eigen::Vector3d p_b = p.p_l.cast<double>() + Eigen::Vector3d(0, 0, 3);
    EXPECT_NEAR(p_b.z(), 1.5, 0.15);
    EXPECT_LE(std::abs(p_b.x()), 7.6);
    EXPECT_LE(std::abs(p_b.y()), 2.35);
  }
  // Heeled 45 deg to starboard, the deck's starboard edge is under water (its up coordinate is
  // (y + 1.5) sin 45 deg): no returns from there, the rest of the deck still seen.
  const Eigen::Quaterniond heel(Eigen::AngleAxisd(45.0 * kPi / 180.0, Eigen::Vector3d::UnitX()));
  const BodyPoseAt heeled = [&heel](TimeNs, Eigen::Quaterniond* q, Eigen::Vector3d* p) {
    *q = heel;
    p->setZero();
    return true;
  };
  const LidarScan heeled_scan = SimulateLidarScan(open_water, model, heeled, 0, 1);
  EXPECT_GT(heeled_scan.points.size(), 500u);
  for (const LidarPoint& p : heeled_scan.points) {
    const Eigen::Vector3d p_w = heel * (p.p_l.cast<double>() + Eigen::Vector3d(0, 0, 3));
    EXPECT_GE(p_w.z(), -0.15);
  }
}

TEST(LidarScans, DropoutRisesWithRange) {
  // Four walls at 20, 40, 60 and 80 m (ahead, to port, aft, to starboard).
  const HarbourWorld world({Wall(20, 22, -10, 10), Wall(-20, 20, 40, 42), Wall(-62, -60, -30, 30),
                            Wall(-60, 60, -82, -80)},
                           0.0);
  auto wall_of = [](const LidarPoint& p) {
    if (p.p_l.x() > 15) return 0;
    if (p.p_l.y() > 35) return 1;
    if (p.p_l.x() < -55) return 2;
    return 3;
  };
  LidarModelSim model = Model();
  model.range_noise_sigma_m = 0.0;
  // Without dropout: the returns each wall can give, and the probability of losing each.
  const LidarScan all = SimulateLidarScan(world, model, Static(), 0, 2);
  model.dropout_at_max_range = 0.5;
  model.dropout_range_exponent = 2.0;
  std::map<int, double> expected, variance, total;
  for (const LidarPoint& p : all.points) {
    const double r = p.p_l.cast<double>().norm();
    const double lost = 0.5 * (r / 100.0) * (r / 100.0);
    expected[wall_of(p)] += 1.0 - lost;
    variance[wall_of(p)] += lost * (1.0 - lost);
    total[wall_of(p)] += 1.0;
  }
  std::map<int, double> kept;
  for (const LidarPoint& p : SimulateLidarScan(world, model, Static(), 0, 2).points) {
    kept[wall_of(p)] += 1.0;
  }
  double last_share = 1.0;
  for (int k = 0; k < 4; ++k) {
    SCOPED_TRACE(k);
    ASSERT_GT(total[k], 300.0);
    EXPECT_NEAR(kept[k], expected[k], 4.0 * std::sqrt(variance[k]));
    const double share = kept[k] / total[k];
    EXPECT_LT(share, last_share);  // 0.98, 0.92, 0.82, 0.68
    last_share = share;
  }
}

TEST(LidarScans, ABinaryPcdReadsBackWithItsTimes) {
  LidarModelSim model = Model();
  model.hull_size_m = Eigen::Vector3d(15.0, 4.5, 2.5);
  const LidarScan scan = SimulateLidarScan(WallAhead(), model, Static(), SecondsToNs(2.5), 3);
  const std::filesystem::path dir = std::filesystem::path(SKERRY_TEST_TMP_DIR) / "lidar_scans";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "scan.pcd").string();
  WriteLidarScanPcd(scan, path);
  std::ifstream in(path, std::ios::binary);
  std::stringstream header;
  header << in.rdbuf();
  EXPECT_NE(header.str().find("FIELDS x y z intensity t\n"), std::string::npos);
  EXPECT_NE(header.str().find("DATA binary\n"), std::string::npos);
  // 20 bytes a point after the header.
  EXPECT_GT(std::filesystem::file_size(path), 20 * scan.points.size());
  EXPECT_LT(std::filesystem::file_size(path), 20 * scan.points.size() + 400);

  const geo::PointCloud cloud = geo::LoadPointCloud(path);
  ASSERT_EQ(cloud.points.size(), scan.points.size());
  ASSERT_EQ(cloud.intensity.size(), scan.points.size());
  ASSERT_EQ(cloud.time_s.size(), scan.points.size());
  for (size_t i = 0; i < scan.points.size(); ++i) {
    EXPECT_EQ(cloud.points[i], scan.points[i].p_l.cast<double>()) << i;
    EXPECT_EQ(cloud.intensity[i], scan.points[i].intensity) << i;
    EXPECT_EQ(cloud.time_s[i], scan.points[i].t_s) << i;
  }
  // An empty scan is a valid, empty file.
  WriteLidarScanPcd(LidarScan{}, (dir / "empty.pcd").string());
  EXPECT_TRUE(geo::LoadPointCloud((dir / "empty.pcd").string()).points.empty());
}

}  // namespace
}  // namespace skerry::sim
