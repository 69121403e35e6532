#include "skerry/io/trajectory.h"

#include <gtest/gtest.h>

#include <cmath>

#include "core/test_util.h"
#include "skerry/core/so3.h"

namespace skerry {
namespace {

using testing::ExpectInputError;
using testing::FreshDir;
using testing::WriteText;

std::vector<StampedPose> MakePoses() {
  std::vector<StampedPose> poses;
  for (int k = 0; k < 5; ++k) {
    StampedPose p;
    p.t_ns = 1403715273262142976LL + k * 50000001LL;
    p.p_w_b = Eigen::Vector3d(0.1 * k, -2.0 + k, 1.0 / 3.0);
    p.q_w_b = ExpQ(Eigen::Vector3d(0.1 * k, -0.2, 0.3 * k));
    poses.push_back(p);
  }
  return poses;
}

TEST(TumTest, RoundTripIsExact) {
  const std::string path = FreshDir("tum") + "/traj.tum";
  const std::vector<StampedPose> poses = MakePoses();
  WriteTum(path, poses);
  const std::vector<StampedPose> back = ReadTum(path);
  ASSERT_EQ(back.size(), poses.size());
  for (std::size_t k = 0; k < poses.size(); ++k) {
    EXPECT_EQ(back[k].t_ns, poses[k].t_ns);
    EXPECT_EQ(back[k].p_w_b, poses[k].p_w_b);
    EXPECT_NEAR(back[k].q_w_b.angularDistance(poses[k].q_w_b), 0.0, 1e-15);
  }
}

TEST(TumTest, BadInput) {
  const std::string dir = FreshDir("tum_bad");
  WriteText(dir + "/a.tum", "# t x y z qx qy qz qw\n1.0 0 0 0 0 0 0 1\n1.0 0 0 0 0 0 0 1\n");
  ExpectInputError([&] { ReadTum(dir + "/a.tum"); }, "a.tum", 3, "t");
  WriteText(dir + "/b.tum", "1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 0.5 1\n");
  ExpectInputError([&] { ReadTum(dir + "/b.tum"); }, "b.tum", 2, "qw");
  WriteText(dir + "/c.tum", "1.0 0 0 0 0 0 0 1\n2.0 0 NaN 0 0 0 0 1\n");
  ExpectInputError([&] { ReadTum(dir + "/c.tum"); }, "c.tum", 2, "y");
  WriteText(dir + "/d.tum", "1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 0\n");
  ExpectInputError([&] { ReadTum(dir + "/d.tum"); }, "d.tum", 2, "qw");
  // Slightly off-unit quaternions (printing precision) are accepted and normalised.
  WriteText(dir + "/e.tum", "1.0 0 0 0 0 0 0 1.0004\n");
  EXPECT_NEAR(ReadTum(dir + "/e.tum")[0].q_w_b.norm(), 1.0, 1e-15);
}

TEST(InterpolateTest, LinearAndSlerp) {
  std::vector<StampedPose> poses(2);
  poses[0].t_ns = 1000;
  poses[1].t_ns = 2000;
  poses[1].p_w_b = Eigen::Vector3d(10.0, -4.0, 2.0);
  poses[1].q_w_b = ExpQ(Eigen::Vector3d(0.0, 0.0, 1.2));
  StampedPose out;
  ASSERT_TRUE(InterpolatePose(poses, 1250, &out));
  EXPECT_EQ(out.t_ns, 1250);
  EXPECT_LT((out.p_w_b - Eigen::Vector3d(2.5, -1.0, 0.5)).norm(), 1e-12);
  EXPECT_LT((LogQ(out.q_w_b) - Eigen::Vector3d(0.0, 0.0, 0.3)).norm(), 1e-12);
  ASSERT_TRUE(InterpolatePose(poses, 2000, &out));  // end points are inside the span
  EXPECT_EQ(out.p_w_b, poses[1].p_w_b);
  ASSERT_TRUE(InterpolatePose(poses, 1000, &out));
  EXPECT_EQ(out.p_w_b, poses[0].p_w_b);
  EXPECT_FALSE(InterpolatePose(poses, 999, &out));
  EXPECT_FALSE(InterpolatePose(poses, 2001, &out));
  EXPECT_FALSE(InterpolatePose(poses, 1500, &out, 999));  // gap longer than allowed
  EXPECT_FALSE(InterpolatePose({}, 0, &out));
}

TEST(InterpolateTest, SlerpTakesTheShortArc) {
  std::vector<StampedPose> poses(2);
  poses[0].t_ns = 0;
  poses[1].t_ns = 10;
  poses[1].q_w_b = ExpQ(Eigen::Vector3d(0.0, 0.0, 0.2));
  poses[1].q_w_b.coeffs() *= -1.0;  // same rotation, other sign
  StampedPose out;
  ASSERT_TRUE(InterpolatePose(poses, 5, &out));
  EXPECT_NEAR(out.q_w_b.angularDistance(ExpQ(Eigen::Vector3d(0.0, 0.0, 0.1))), 0.0, 1e-12);
}

}  // namespace
}  // namespace skerry
