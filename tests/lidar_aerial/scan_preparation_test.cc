// PrepareScan: which columns of a scan are edges an aerial image shows (walls, low rims,
// ground-level intensity edges), which are not (the inside of a quay, a tall tree), levelling,
// the filters and the cap, on synthetic scans whose structure is known.

#include "skerry/lidar_aerial/scan_preparation.h"

#include <gtest/gtest.h>

#include <random>

#include "lidar_aerial/synthetic_scene.h"

namespace skerry::lidar_aerial {
namespace {

using geo::testing::FreshDir;

// Distance (m) from a grid point to the nearest box outline of the scene.
double ToOutline(const testing::Scene& s, const Eigen::Vector2d& g) {
  double best = HUGE_VAL;
  for (const testing::Box& b : s.boxes) {
    const std::vector<Eigen::Vector2d> c = testing::Scene::Corners(b);
    for (size_t k = 0; k < c.size(); ++k) {
      const Eigen::Vector2d a = c[k], d = c[(k + 1) % c.size()] - a;
      const double t = std::clamp((g - a).dot(d) / d.squaredNorm(), 0.0, 1.0);
      best = std::min(best, (a + t * d - g).norm());
    }
  }
  return best;
}

TEST(ScanPreparation, OnAHarbourEveryPointIsOnAnOutlineAndEveryOutlineInRangeHasPoints) {
  const testing::Scene scene = testing::Harbour();
  const geo::Orthophoto ortho =
      testing::LoadScene(testing::WriteAerialImage(scene, FreshDir("harbour")));
  // Sensor on the water off the quays' corner, facing north-east.
  const PlanarPose sensor{testing::GridToEnu(scene, ortho, {100, 80}), 0.7};
  const testing::Scan scan = testing::SampleScan(scene, ortho, sensor, 60.0);
  ScanPreparationOptions o;
  o.max_points = 0;
  // Blurred by 1 m (the default, against LiDAR speckle), the two edges of the 1 m wide paint
  // lines move 1 m apart from each other; by 0.5 m they stay on the paint's sides.
  o.intensity_blur_m = 0.5;
  const PreparedScan p =
      PrepareScan(scan.points_l, scan.intensity, Eigen::Quaterniond::Identity(), o);
  EXPECT_EQ(p.input, static_cast<int>(scan.points_l.size()));
  EXPECT_GT(p.wall_columns, 300);
  EXPECT_GT(p.intensity_columns, 50);  // the paint
  EXPECT_EQ(p.dropped_high, 0);        // nothing here stands 3 m above its floor
  ASSERT_GT(p.points_s.size(), 500u);
  // Back to grid metres: sensor pose, then the scene's affine grid.
  const Eigen::Vector2d o0 = testing::GridToEnu(scene, ortho, {0, 0});
  Eigen::Matrix2d A;
  A.col(0) = (testing::GridToEnu(scene, ortho, {100, 0}) - o0) / 100.0;
  A.col(1) = (testing::GridToEnu(scene, ortho, {0, 100}) - o0) / 100.0;
  const Eigen::Matrix2d A_inv = A.inverse();
  int on_outline = 0;
  for (const Eigen::Vector3d& q : p.points_s) {
    const Eigen::Vector2d g = A_inv * (sensor.Apply(q.head<2>()) - o0);
    on_outline += ToOutline(scene, g) <= 0.75;
  }
  EXPECT_GE(on_outline, static_cast<int>(0.98 * p.points_s.size()));
  // Coverage: samples along the outlines of the pier (in range), each within 1 m of a point.
  const testing::Box& pier = scene.boxes[2];
  const std::vector<Eigen::Vector2d> c = testing::Scene::Corners(pier);
  int covered = 0, samples = 0;
  for (size_t k = 0; k < c.size(); ++k) {
    for (double t = 0.05; t < 1.0; t += 0.1) {
      const Eigen::Vector2d g = c[k] + t * (c[(k + 1) % c.size()] - c[k]);
      const Eigen::Vector2d l = sensor.R().transpose() * (o0 + A * g - sensor.t);
      if (l.norm() > 58.0) continue;
      ++samples;
      bool near = false;
      for (const Eigen::Vector3d& q : p.points_s) near |= (q.head<2>() - l).norm() <= 1.0;
      covered += near;
    }
  }
  EXPECT_GT(samples, 20);
  EXPECT_EQ(covered, samples);
}

// A tree: canopy 5-9 m over the ground, returns from both (airborne, through gaps). Its rim
// stands too high to be where an orthophoto shows it; its columns are not walls (gap under the
// crown); nothing of it is kept. A 1 m kerb beside it is.
TEST(ScanPreparation, ATallTreeGivesNoPointsAndALowKerbDoes) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Eigen::Vector3d> pts;
  for (double x = -15; x < 15; x += 0.3) {
    for (double y = -15; y < 15; y += 0.3) {
      const double kerb = (x > 8.0 && x < 9.0) ? 1.0 : 0.0;
      pts.emplace_back(x, y, kerb);
      if (std::hypot(x, y) < 4.0) pts.emplace_back(x, y, 5.0 + 4.0 * u(rng));
    }
  }
  ScanPreparationOptions o;
  o.min_vertical_extent_m = 0.8;
  o.max_points = 0;
  const PreparedScan p = PrepareScan(pts, {}, Eigen::Quaterniond::Identity(), o);
  EXPECT_GT(p.dropped_high, 100);
  EXPECT_EQ(p.wall_columns, 0);
  int kerb = 0;
  for (const Eigen::Vector3d& q : p.points_s) {
    EXPECT_GT(std::hypot(q.x(), q.y()), 5.0) << q.transpose();
    kerb += std::abs(q.x() - 8.0) < 0.6 || std::abs(q.x() - 9.0) < 0.6;
  }
  EXPECT_GT(kerb, 40);
  EXPECT_EQ(kerb, static_cast<int>(p.points_s.size()));
}

TEST(ScanPreparation, ATiltedScanLevelledByItsAttitudeGivesTheSamePoints) {
  const testing::Scene scene = testing::Harbour();
  const geo::Orthophoto ortho =
      testing::LoadScene(testing::WriteAerialImage(scene, FreshDir("harbour")));
  const PlanarPose sensor{testing::GridToEnu(scene, ortho, {100, 80}), 0.2};
  const testing::Scan scan = testing::SampleScan(scene, ortho, sensor, 40.0, 0.3);
  const PreparedScan level =
      PrepareScan(scan.points_l, scan.intensity, Eigen::Quaterniond::Identity());
  // The sensor rolled 6 deg and pitched -4: its points are R_s_l p_l.
  const Eigen::Quaterniond q_l_s(Eigen::AngleAxisd(0.10, Eigen::Vector3d::UnitX()) *
                                 Eigen::AngleAxisd(-0.07, Eigen::Vector3d::UnitY()));
  std::vector<Eigen::Vector3d> tilted;
  for (const Eigen::Vector3d& p : scan.points_l) tilted.push_back(q_l_s.inverse() * p);
  const PreparedScan p = PrepareScan(tilted, scan.intensity, q_l_s);
  ASSERT_EQ(p.points_s.size(), level.points_s.size());
  double worst = 0.0;
  for (size_t k = 0; k < p.points_s.size(); ++k) {
    worst = std::max(worst, (q_l_s * p.points_s[k] - level.points_s[k]).norm());
  }
  EXPECT_LT(worst, 1e-9);
  // Not levelled, the same scan is another scan.
  const PreparedScan wrong = PrepareScan(tilted, scan.intensity, Eigen::Quaterniond::Identity());
  EXPECT_NE(wrong.points_s.size(), level.points_s.size());
}

TEST(ScanPreparation, FiltersAreCountedAndTheCapSharesBetweenKinds) {
  const testing::Scene scene = testing::Harbour();
  const geo::Orthophoto ortho =
      testing::LoadScene(testing::WriteAerialImage(scene, FreshDir("harbour")));
  const PlanarPose sensor{testing::GridToEnu(scene, ortho, {100, 80}), 0.0};
  testing::Scan scan = testing::SampleScan(scene, ortho, sensor, 50.0, 0.3);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  scan.points_l.emplace_back(nan, 0.0, 0.0);
  scan.intensity.push_back(1.0f);
  scan.points_l.emplace_back(0.5, 0.5, 0.5);  // on the own hull
  scan.intensity.push_back(1.0f);
  ScanPreparationOptions o;
  o.hull_s = Eigen::AlignedBox3d(Eigen::Vector3d(-1, -1, -1), Eigen::Vector3d(1, 1, 1));
  o.min_range_m = 2.0;
  o.max_range_m = 45.0;
  o.min_height_m = 0.3;  // the water (and the ground of this scene) goes
  o.max_points = 0;
  const PreparedScan all =
      PrepareScan(scan.points_l, scan.intensity, Eigen::Quaterniond::Identity(), o);
  EXPECT_EQ(all.dropped_invalid, 1);
  EXPECT_EQ(all.dropped_hull, 1);
  EXPECT_GT(all.dropped_range, 1000);
  EXPECT_GT(all.dropped_low, 1000);
  for (const Eigen::Vector3d& q : all.points_s) {
    EXPECT_GE(q.head<2>().norm(), 2.0);
    EXPECT_LE(q.head<2>().norm(), 45.0);
  }
  const int structure = all.wall_columns + all.rim_columns;
  ASSERT_GT(structure, 100);
  ASSERT_GT(all.intensity_columns, 20);
  // A cap of 2 (intensity + 10): half each, and what the intensity edges do not use goes to
  // the structure.
  o.max_points = 2 * (all.intensity_columns + 10);
  const PreparedScan capped =
      PrepareScan(scan.points_l, scan.intensity, Eigen::Quaterniond::Identity(), o);
  EXPECT_EQ(static_cast<int>(capped.points_s.size()), o.max_points);
  // The fullest structure columns first.
  EXPECT_TRUE(std::is_sorted(capped.returns.begin(),
                             capped.returns.begin() + (o.max_points - all.intensity_columns),
                             std::greater<>()));
  // Bad calls.
  EXPECT_THROW(PrepareScan(scan.points_l, {1.0f}, Eigen::Quaterniond::Identity()),
               std::invalid_argument);
  ScanPreparationOptions bad;
  bad.cell_m = 0.0;
  EXPECT_THROW(PrepareScan(scan.points_l, {}, Eigen::Quaterniond::Identity(), bad),
               std::invalid_argument);
  EXPECT_TRUE(PrepareScan({}, {}, Eigen::Quaterniond::Identity()).points_s.empty());
  // A stray return 1e15 m away: an error saying so, not an overflow (no range limit here).
  std::vector<Eigen::Vector3d> stray = {Eigen::Vector3d(1.0, 2.0, 0.0),
                                        Eigen::Vector3d(1e15, 0.0, 0.0)};
  EXPECT_THROW(PrepareScan(stray, {}, Eigen::Quaterniond::Identity()), std::invalid_argument);
}

}  // namespace
}  // namespace skerry::lidar_aerial
