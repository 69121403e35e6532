// The coarse search and single-scan registration on synthetic scenes whose registration is
// exact: perturb and recover, the peak's covariance and the degeneracy along parallel quays,
// ambiguity between two identical buildings, and what happens without points or map.

#include <gtest/gtest.h>

#include <map>

#include "lidar_aerial/synthetic_scene.h"
#include "skerry/lidar_aerial/coarse_search.h"
#include "skerry/lidar_aerial/scan_preparation.h"
#include "skerry/lidar_aerial/scan_registration.h"

namespace skerry::lidar_aerial {
namespace {

using geo::testing::FreshDir;
constexpr double kDeg = M_PI / 180.0;

struct World {
  testing::Scene scene;
  std::unique_ptr<geo::Orthophoto> ortho;
  std::unique_ptr<AerialMap> map;
  std::shared_ptr<EdgeDistanceField> field;

  explicit World(const testing::Scene& s) : scene(s) {
    ortho = std::make_unique<geo::Orthophoto>(
        testing::LoadScene(testing::WriteAerialImage(scene, FreshDir("scene"))));
    map = std::make_unique<AerialMap>(*ortho, ortho->footprint_box_enu());
    field = std::make_shared<EdgeDistanceField>(*map);
  }
  std::vector<Eigen::Vector3d> Scan(const PlanarPose& sensor, double range) const {
    const testing::Scan scan = testing::SampleScan(scene, *ortho, sensor, range, 0.3);
    return PrepareScan(scan.points_l, scan.intensity, Eigen::Quaterniond::Identity()).points_s;
  }
  Eigen::Vector2d Enu(double x, double y) const {
    return testing::GridToEnu(scene, *ortho, {x, y});
  }
};

TEST(ScanRegistration, AHarbourScanIsRecoveredFrom20MetresAnd10DegreesOff) {
  const World w(testing::Harbour());
  const PlanarPose truth{w.Enu(100, 80), 0.7};
  const std::vector<Eigen::Vector3d> points = w.Scan(truth, 60.0);
  ASSERT_GT(points.size(), 1000u);
  for (int k = 0; k < 4; ++k) {
    const double a = k * M_PI / 2 + 0.3;
    const PlanarPose start{truth.t + 20.0 * Eigen::Vector2d(std::cos(a), std::sin(a)),
                           truth.yaw + (k % 2 ? 10.0 : -10.0) * kDeg};
    const Registration r = RegisterScan(*w.map, w.field, points, start);
    ASSERT_TRUE(r.valid);
    EXPECT_LT((r.coarse.pose.t - truth.t).norm(), 1.0) << k;
    EXPECT_LT(std::abs(WrapAngle(r.coarse.pose.yaw - truth.yaw)), 1.0 * kDeg) << k;
    EXPECT_FALSE(r.coarse.ambiguous) << r.coarse.ambiguity;
    // Within 0.15 m: the scan's 0.5 m columns and the map's 0.25 m cells leave a bias of about
    // a tenth of a metre (measured 0.11 m here, 0.05 m without the paint's intensity edges).
    EXPECT_LT((r.pose.t - truth.t).norm(), 0.15) << k;
    EXPECT_LT(std::abs(WrapAngle(r.pose.yaw - truth.yaw)), 0.1 * kDeg) << k;
    EXPECT_GT(r.inlier_share, 0.9);
    EXPECT_GT(r.constraint_ratio, 0.2);
    // The fine covariance is positive definite and says centimetres.
    EXPECT_GT(r.covariance.determinant(), 0.0);
    EXPECT_LT(std::sqrt(r.covariance(0, 0)), 0.1);
  }
}

// Prior work's other failure: boats present in one source only. Three boats moored 1.5 m off
// the west and the south quay, in the scan but not in the photograph: their faces lie metres from
// any edge of the map, and under Huber's loss every one of their points pulls with a constant force
// towards the nearest edge; Geman-McClure's lets them go (map_alignment_residual.h).
TEST(ScanRegistration, BoatsOnlyInTheScanDoNotPullUnderGemanMcClure) {
  const World w(testing::Harbour());
  testing::Scene with_boats = w.scene;
  with_boats.boxes.push_back({{83.5, 100}, {4, 12}, 0.0, 2.0, 0, 70});
  with_boats.boxes.push_back({{83.5, 118}, {4, 14}, 0.0, 2.0, 0, 70});
  with_boats.boxes.push_back({{100, 58.5}, {12, 4}, 0.0, 2.0, 0, 70});
  const PlanarPose truth{w.Enu(100, 95), 0.4};
  const testing::Scan scan = testing::SampleScan(with_boats, *w.ortho, truth, 60.0, 0.3);
  const std::vector<Eigen::Vector3d> points =
      PrepareScan(scan.points_l, scan.intensity, Eigen::Quaterniond::Identity()).points_s;
  std::map<DistanceLoss, double> error_m, error_deg;
  for (const DistanceLoss loss : {DistanceLoss::kGemanMcClure, DistanceLoss::kHuber}) {
    RegistrationOptions o;
    o.fine.loss = loss;
    const Registration r =
        RegisterScan(*w.map, w.field, points, {truth.t + Eigen::Vector2d(2, -1), truth.yaw}, o);
    ASSERT_TRUE(r.valid) << ToString(loss);
    error_m[loss] = (r.pose.t - truth.t).norm();
    error_deg[loss] = std::abs(WrapAngle(r.pose.yaw - truth.yaw)) / kDeg;
  }
  const DistanceLoss gm = DistanceLoss::kGemanMcClure, huber = DistanceLoss::kHuber;
  EXPECT_LT(error_m[gm], 0.15) << "Huber: " << error_m[huber] << " m";
  EXPECT_LT(error_deg[gm], 0.1) << "Huber: " << error_deg[huber] << " deg";
  EXPECT_LT(error_m[gm], 0.5 * error_m[huber]);
}

// Prior work's failure: only parallel quays in view, the position along them is not observable.
TEST(ScanRegistration, BetweenParallelQuaysThePositionAlongThemIsFlaggedAsWeak) {
  testing::Scene s;
  s.boxes = {{{100, 80}, {200, 20}, 0.0, 2.0, 170, 50}, {{100, 130}, {200, 20}, 0.0, 2.0, 170, 50}};
  const World w(s);
  const PlanarPose truth{w.Enu(100, 105), 0.3};
  const std::vector<Eigen::Vector3d> points = w.Scan(truth, 40.0);
  const Registration r = RegisterScan(*w.map, w.field, points,
                                      {truth.t + Eigen::Vector2d(3, 2), truth.yaw + 2 * kDeg});
  ASSERT_TRUE(r.valid);
  EXPECT_LT(r.constraint_ratio, 0.05);
  // The quays run east (grid x ~ ENU east here): the weak direction is east, up to sign.
  EXPECT_GT(std::abs(r.weak_direction.x()), 0.98) << r.weak_direction.transpose();
  // Across the quays and in heading it is still found.
  EXPECT_LT(std::abs(r.pose.t.y() - truth.t.y()), 0.1);
  EXPECT_LT(std::abs(WrapAngle(r.pose.yaw - truth.yaw)), 0.1 * kDeg);
  // The coarse peak says so too: long along the quays.
  EXPECT_GT(r.coarse.covariance(0, 0), 10.0 * r.coarse.covariance(1, 1));
}

TEST(CoarseSearch, TwoIdenticalBuildingsAreAmbiguousAndOneIsNot) {
  testing::Scene s;
  s.boxes = {{{70, 100}, {12, 8}, 0.2, 2.5, 220, 60}, {{130, 100}, {12, 8}, 0.2, 2.5, 220, 60}};
  const World twins(s);
  const PlanarPose truth{twins.Enu(70, 100), 0.0};
  CoarseSearchOptions o;
  o.search_radius_m = 70.0;
  const CoarseMatch both = CoarseSearch(*twins.map, twins.Scan(truth, 15.0), truth, o);
  ASSERT_TRUE(both.valid);
  EXPECT_GT(both.ambiguity, 0.9);
  EXPECT_TRUE(both.ambiguous);
  s.boxes.pop_back();
  const World single(s);
  const CoarseMatch one = CoarseSearch(*single.map, single.Scan(truth, 15.0), truth, o);
  ASSERT_TRUE(one.valid);
  EXPECT_LT(one.ambiguity, 0.8);
  EXPECT_FALSE(one.ambiguous);
  EXPECT_LT((one.pose.t - truth.t).norm(), 1.0);
}

TEST(CoarseSearch, TheMatchDoesNotDependOnWhereBetweenTwoStepsThePriorLies) {
  const World w(testing::Harbour());
  const PlanarPose truth{w.Enu(100, 80), 0.7};
  const std::vector<Eigen::Vector3d> points = w.Scan(truth, 50.0);
  const CoarseMatch a =
      CoarseSearch(*w.map, points, {truth.t + Eigen::Vector2d(4.3, -2.2), truth.yaw + 0.3 * kDeg});
  const CoarseMatch b =
      CoarseSearch(*w.map, points, {truth.t + Eigen::Vector2d(-3.1, 5.6), truth.yaw - 4.6 * kDeg});
  ASSERT_TRUE(a.valid && b.valid);
  EXPECT_LT((a.pose.t - b.pose.t).norm(), 1e-9);
  EXPECT_LT(std::abs(a.pose.yaw - b.pose.yaw), 1e-12);
  EXPECT_DOUBLE_EQ(a.score, b.score);
}

TEST(CoarseSearch, NoPointsNoMapUnderTheWindowOrNoEdgesIsNoMatch) {
  const World w(testing::Harbour());
  const PlanarPose at{w.Enu(100, 80), 0.0};
  EXPECT_FALSE(CoarseSearch(*w.map, {}, at).valid);
  const std::vector<Eigen::Vector3d> points = w.Scan(at, 30.0);
  EXPECT_FALSE(CoarseSearch(*w.map, points, {at.t + Eigen::Vector2d(5000, 0), 0.0}).valid);
  EXPECT_FALSE(RegisterScan(*w.map, w.field, {}, at).valid);
  // Options that cannot make a sweep.
  CoarseSearchOptions bad;
  bad.heading_step_deg = 0.0;
  EXPECT_THROW(CoarseSearch(*w.map, points, at, bad), std::invalid_argument);
  bad = {};
  bad.resolution_m = -1.0;
  EXPECT_THROW(CoarseSearch(*w.map, points, at, bad), std::invalid_argument);
  // A map without edges (the image of a scene with nothing in it): nothing to register to.
  testing::Scene empty;
  const World blank(empty);
  EXPECT_EQ(cv::countNonZero(blank.map->edges()), 0);
  EXPECT_FALSE(CoarseSearch(*blank.map, points, {blank.Enu(100, 80), 0.0}).valid);
  EXPECT_FALSE(RegisterScan(*blank.map, blank.field, points, {blank.Enu(100, 80), 0.0}).valid);
}

}  // namespace
}  // namespace skerry::lidar_aerial
