// Prior work's matcher (stacked points, RANSAC lines, unpadded FFT correlation, a particle swarm
// over heading, a 2 m gate) on a synthetic harbour whose registration is exact: it finds the
// pose from a prior inside its reach, its gate refuses a match far from the prior, and bad calls.

#include <gtest/gtest.h>

#include "lidar_aerial/synthetic_scene.h"
#include "skerry/lidar_aerial/baseline_pso_matcher.h"

namespace skerry::lidar_aerial {
namespace {

using geo::testing::FreshDir;
constexpr double kDeg = M_PI / 180.0;

struct Harbour {
  testing::Scene scene = testing::Harbour();
  std::unique_ptr<geo::Orthophoto> ortho;
  std::unique_ptr<AerialMap> map;
  PlanarPose truth;
  std::vector<Eigen::Vector3d> scan;

  Harbour() {
    ortho = std::make_unique<geo::Orthophoto>(
        testing::LoadScene(testing::WriteAerialImage(scene, FreshDir("harbour"))));
    AerialMapOptions o;
    o.resolution_m = 0.16;
    map = std::make_unique<AerialMap>(*ortho, ortho->footprint_box_enu(), o);
    truth = {testing::GridToEnu(scene, *ortho, {100, 80}), 0.7};
    scan = testing::SampleScan(scene, *ortho, truth, 38.0, 0.3).points_l;
  }
  // Prior work's 150 m tile is 938 pixels (2 x 7 x 67: a slow DFT); the tests use 512.
  static baseline::BaselineOptions Options() {
    baseline::BaselineOptions o;
    o.tile_m = 512 * o.cell_m;
    return o;
  }
};

TEST(BaselinePsoMatcher, FindsThePoseFromAPriorInsideItsReach) {
  const Harbour h;
  const PlanarPose prior{h.truth.t + Eigen::Vector2d(1.0, -0.8), h.truth.yaw + 2.0 * kDeg};
  const baseline::BaselineMatch m =
      baseline::MatchBaseline(*h.map, h.scan, prior, Harbour::Options());
  ASSERT_TRUE(m.valid);
  EXPECT_FALSE(m.gated);
  EXPECT_EQ(m.evaluations, 70);  // 10 particles, evaluated then moved 6 times
  EXPECT_LT((m.pose.t - h.truth.t).norm(), 0.5);
  EXPECT_LT(std::abs(WrapAngle(m.pose.yaw - h.truth.yaw)), 1.0 * kDeg);
  EXPECT_GT(m.score, 0.05);
}

TEST(BaselinePsoMatcher, ItsGateRefusesAMatchFarFromThePrior) {
  const Harbour h;
  const PlanarPose prior{h.truth.t + Eigen::Vector2d(6.0, 5.0), h.truth.yaw + 1.0 * kDeg};
  const baseline::BaselineMatch m =
      baseline::MatchBaseline(*h.map, h.scan, prior, Harbour::Options());
  ASSERT_TRUE(m.valid);
  // It finds the pose, 7.8 m away, and its gate does not let it move there.
  EXPECT_LT((m.matched.t - h.truth.t).norm(), 0.5);
  EXPECT_TRUE(m.gated);
  EXPECT_EQ(m.pose.t, prior.t);
  baseline::BaselineOptions wide = Harbour::Options();
  wide.gate_m = 20.0;
  EXPECT_FALSE(baseline::MatchBaseline(*h.map, h.scan, prior, wide).gated);
}

TEST(BaselinePsoMatcher, WrongResolutionNoPointsOrNoMapAreNoMatch) {
  const Harbour h;
  baseline::BaselineOptions o = Harbour::Options();
  o.cell_m = 0.25;
  EXPECT_THROW(baseline::MatchBaseline(*h.map, h.scan, h.truth, o), std::invalid_argument);
  EXPECT_FALSE(baseline::MatchBaseline(*h.map, {}, h.truth, Harbour::Options()).valid);
  EXPECT_FALSE(baseline::MatchBaseline(*h.map, h.scan, {h.truth.t + Eigen::Vector2d(5000, 0), 0.0},
                                       Harbour::Options())
                   .valid);
}

}  // namespace
}  // namespace skerry::lidar_aerial
