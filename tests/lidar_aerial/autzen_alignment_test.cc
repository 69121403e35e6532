// Real data: the Autzen airborne LiDAR cloud against the orthophoto of the same place, both in
// NAD83(HARN) Oregon Lambert (feet). The cloud, centred on its own middle, is registered from
// starts 10 m and 5 degrees off its CRS registration in four directions. What the data show
// (bench/aerial_alignment.cc, docs/results.md): every start lands on one solution, 2.6 m east and
// north-east of where the two files put the cloud and 0.8 degrees turned; the files agree to a
// few metres, as aerial orthophotos' georeferencing does, so that solution is the alignment of
// the data and the test holds the search to it: the starts agree with each other, and with the
// CRS registration to the files' few metres.

#include <gtest/gtest.h>

#include "geo/geo_test_util.h"
#include "skerry/core/geodesy.h"
#include "skerry/geo/orthophoto.h"
#include "skerry/geo/point_cloud.h"
#include "skerry/lidar_aerial/scan_preparation.h"
#include "skerry/lidar_aerial/scan_registration.h"

namespace skerry::lidar_aerial {
namespace {

using geo::testing::kData;
constexpr double kDeg = M_PI / 180.0;

TEST(AutzenAlignment, StartsTenMetresAndFiveDegreesOffLandOnOneSolutionNearTheCrsRegistration) {
  const std::string dir = kData + "/autzen";
  SKERRY_SKIP_WITHOUT(dir + "/autzen_trim.las");
  const geo::Orthophoto rough(dir + "/autzen.jpg", LocalFrame({44.05, -123.07, 100.0}));
  const Eigen::Vector3d llh = rough.frame().ToGeodetic(
      rough.PixelToEnu(0.5 * (rough.width() - 1), 0.5 * (rough.height() - 1), 100.0));
  const LocalFrame frame({llh.x(), llh.y(), 100.0});
  const geo::Orthophoto ortho(dir + "/autzen.jpg", frame);
  const geo::PointCloud cloud =
      geo::PointCloudToEnu(geo::LoadPointCloud(dir + "/autzen_trim.las"), frame,
                           geo::CloudToEnuOptions(geo::VerticalDatum::kEgm96));
  Eigen::AlignedBox2d box;
  for (const Eigen::Vector3d& p : cloud.points) box.extend(p.head<2>().eval());
  const Eigen::Vector2d c = box.center();
  std::vector<Eigen::Vector3d> scan;
  for (const Eigen::Vector3d& p : cloud.points)
    scan.push_back(p - Eigen::Vector3d(c.x(), c.y(), 0));
  const PreparedScan prepared = PrepareScan(scan, cloud.intensity, Eigen::Quaterniond::Identity());
  // What the scene gives: trees standing too high to use, ground-level intensity edges (the
  // path loop, kerbs), a few low rims.
  EXPECT_GT(prepared.dropped_high, 5000);
  EXPECT_GT(prepared.intensity_columns, 500);
  ASSERT_GT(prepared.points_s.size(), 1000u);

  const AerialMap map(ortho, Eigen::AlignedBox2d(box.min() - Eigen::Vector2d(60, 60),
                                                 box.max() + Eigen::Vector2d(60, 60)));
  const auto field = std::make_shared<EdgeDistanceField>(map);
  std::vector<PlanarPose> found;
  for (int k = 0; k < 4; ++k) {
    const double a = k * M_PI / 2 + 0.4;
    const PlanarPose start{c + 10.0 * Eigen::Vector2d(std::cos(a), std::sin(a)),
                           (k % 2 ? 5.0 : -5.0) * kDeg};
    const Registration r = RegisterScan(map, field, prepared.points_s, start);
    ASSERT_TRUE(r.valid) << k;
    found.push_back(r.pose);
    RecordProperty("solution_" + std::to_string(k), std::to_string(r.pose.t.x() - c.x()) + " " +
                                                        std::to_string(r.pose.t.y() - c.y()) + " " +
                                                        std::to_string(r.pose.yaw / kDeg));
    // Within the files' agreement of the CRS registration.
    EXPECT_LT((r.pose.t - c).norm(), 4.0) << k;
    EXPECT_LT(std::abs(r.pose.yaw), 1.5 * kDeg) << k;
  }
  for (size_t i = 0; i < found.size(); ++i) {
    for (size_t j = i + 1; j < found.size(); ++j) {
      // The sweep's headings and the search's cells lie on fixed grids: one solution.
      EXPECT_LT((found[i].t - found[j].t).norm(), 0.05) << i << " " << j;
      EXPECT_LT(std::abs(WrapAngle(found[i].yaw - found[j].yaw)), 0.05 * kDeg) << i << " " << j;
    }
  }
}

}  // namespace
}  // namespace skerry::lidar_aerial
