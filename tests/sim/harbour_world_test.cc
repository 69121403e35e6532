// The simulated harbour: the ray caster against hand-computed hits (a face at a known range, a
// turned box, grazing, from inside, parallel to a face, missing, the water), the grid walk
// against brute force over every box, box overlap by separating axes, and the built-in layout.

#include "skerry/sim/harbour_world.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>
#include <random>

namespace skerry::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;

HarbourBox Box(double cx,
               double cy,
               double yaw_deg,
               double length,
               double width,
               double bottom,
               double top,
               HarbourObjectKind kind = HarbourObjectKind::kQuay) {
  HarbourBox b;
  b.kind = kind;
  b.centre_w = Eigen::Vector2d(cx, cy);
  b.yaw_rad = yaw_deg * kPi / 180.0;
  b.length_m = length;
  b.width_m = width;
  b.bottom_m = bottom;
  b.top_m = top;
  b.reflectivity = 0.4;
  return b;
}

// Box A: x 9..11, y -2..2, z -1..3; the water at z = -10 (out of the way) unless a test says.
HarbourWorld WorldA(double water = -10.0) {
  return HarbourWorld({Box(10, 0, 0, 2, 4, -1, 3)}, water);
}

void ExpectHit(const std::optional<RayHit>& hit,
               double range,
               const Eigen::Vector3d& point,
               const Eigen::Vector3d& normal) {
  ASSERT_TRUE(hit.has_value());
  EXPECT_NEAR(hit->range_m, range, 1e-12);
  EXPECT_NEAR((hit->point_w - point).norm(), 0.0, 1e-12) << hit->point_w.transpose();
  EXPECT_NEAR((hit->normal_w - normal).norm(), 0.0, 1e-12) << hit->normal_w.transpose();
}

TEST(HarbourWorld, RayHitsAFaceAtTheHandComputedRange) {
  const HarbourWorld w = WorldA();
  // Straight at the west face x = 9.
  ExpectHit(w.Raycast({0, 0, 0}, {1, 0, 0}, 100.0), 9.0, {9, 0, 0}, {-1, 0, 0});
  // The direction need not be unit: the range is in metres along it.
  ExpectHit(w.Raycast({0, 0, 0}, {5, 0, 0}, 100.0), 9.0, {9, 0, 0}, {-1, 0, 0});
  // Obliquely: x = 9 at y = 0.9, range 9 sqrt(1.01).
  ExpectHit(w.Raycast({0, 0, 0}, {1, 0.1, 0}, 100.0), 9.0 * std::sqrt(1.01), {9, 0.9, 0},
            {-1, 0, 0});
  // From above onto the top z = 3.
  ExpectHit(w.Raycast({10, 0, 10}, {0, 0, -1}, 100.0), 7.0, {10, 0, 3}, {0, 0, 1});
  // The reflectivity and index of the box hit come along.
  EXPECT_EQ(w.Raycast({0, 0, 0}, {1, 0, 0}, 100.0)->box, 0);
  EXPECT_DOUBLE_EQ(w.Raycast({0, 0, 0}, {1, 0, 0}, 100.0)->reflectivity, 0.4);
}

TEST(HarbourWorld, RayHitsATurnedBox) {
  // Centre (20, 5), 6 m long along 30 deg, 2 m wide. A ray along +x through its centre: at
  // (20 - s, 5) its box coordinates are (-s cos 30, s sin 30), inside when s cos 30 <= 3 and
  // s / 2 <= 1: it enters at s = 2 through the face at +1 across, whose normal is
  // (-sin 30, cos 30).
  const HarbourWorld w({Box(20, 5, 30, 6, 2, -1, 3)}, -10.0);
  ExpectHit(w.Raycast({0, 5, 0}, {1, 0, 0}, 100.0), 18.0, {18, 5, 0},
            {-0.5, std::sqrt(3.0) / 2.0, 0});
}

TEST(HarbourWorld, GrazingAndEdgeTouchesMissButAnEntryThroughAnEdgeHits) {
  const HarbourWorld w = WorldA();
  EXPECT_FALSE(w.Raycast({0, 2, 0}, {1, 0, 0}, 100.0));  // along the face y = 2
  ExpectHit(w.Raycast({0, 1.999, 0}, {1, 0, 0}, 100.0), 9.0, {9, 1.999, 0}, {-1, 0, 0});
  EXPECT_FALSE(w.Raycast({0, 2.001, 0}, {1, 0, 0}, 100.0));
  EXPECT_FALSE(w.Raycast({0, 0, 3}, {1, 0, 0}, 100.0));  // along the top
  // Touching the vertical edge at (9, 2) from (7, 0) along (1, 1): in and out at once.
  EXPECT_FALSE(w.Raycast({7, 0, 0}, {1, 1, 0}, 100.0));
  // Through the same edge from (5, 6) along (1, -1): it goes on inside, a hit at the edge.
  const std::optional<RayHit> edge = w.Raycast({5, 6, 0}, {1, -1, 0}, 100.0);
  ASSERT_TRUE(edge.has_value());
  EXPECT_NEAR(edge->range_m, 4.0 * std::sqrt(2.0), 1e-12);
  EXPECT_NEAR((edge->point_w - Eigen::Vector3d(9, 2, 0)).norm(), 0.0, 1e-12);
}

TEST(HarbourWorld, ARayFromInsideABoxLeavesItAndHitsWhatLiesBeyond) {
  EXPECT_FALSE(WorldA().Raycast({10, 0, 0}, {1, 0, 0}, 100.0));
  const HarbourWorld two({Box(10, 0, 0, 2, 4, -1, 3), Box(20, 0, 0, 2, 4, -1, 3)}, -10.0);
  const std::optional<RayHit> hit = two.Raycast({10, 0, 0}, {1, 0, 0}, 100.0);
  ExpectHit(hit, 9.0, {19, 0, 0}, {-1, 0, 0});
  EXPECT_EQ(hit->box, 1);
}

TEST(HarbourWorld, ARayParallelToAFaceHitsOnlyInsideItsSlab) {
  const HarbourWorld w = WorldA();
  ExpectHit(w.Raycast({10, -10, 0}, {0, 1, 0}, 100.0), 8.0, {10, -2, 0}, {0, -1, 0});
  EXPECT_FALSE(w.Raycast({12, -10, 0}, {0, 1, 0}, 100.0));
  EXPECT_FALSE(w.Raycast({10, -10, 5}, {0, 1, 0}, 100.0));  // above the top
}

TEST(HarbourWorld, MissesAwayBeyondRangeAndBeyondTheWater) {
  const HarbourWorld w = WorldA();
  EXPECT_FALSE(w.Raycast({0, 0, 0}, {-1, 0, 0}, 100.0));
  EXPECT_FALSE(w.Raycast({0, 0, 0}, {1, 0, 0}, 8.99));
  EXPECT_TRUE(w.Raycast({0, 0, 0}, {1, 0, 0}, 9.01));
  EXPECT_FALSE(w.Raycast({0, 0, 0}, {0, 0, 1}, 100.0));
  // With the water at z = 0: a ray from 2 m up falling 1 in 10 reaches the box's face at x = 9,
  // z = 1.1; one falling 1 in 4 meets the water at x = 8 first and returns nothing.
  const HarbourWorld wet = WorldA(0.0);
  ExpectHit(wet.Raycast({0, 0, 2}, {1, 0, -0.1}, 100.0), 9.0 * std::sqrt(1.01), {9, 0, 1.1},
            {-1, 0, 0});
  EXPECT_FALSE(wet.Raycast({0, 0, 2}, {1, 0, -0.25}, 100.0));
  EXPECT_FALSE(wet.Raycast({0, 0, -0.5}, {1, 0, 0}, 100.0));  // from under the water
}

TEST(HarbourWorld, TheGridWalkFindsWhatBruteForceFinds) {
  HarbourSpec spec;
  spec.enabled = true;
  const HarbourWorld w = BuildHarbour(spec, 1);
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int hits = 0;
  for (int k = 0; k < 3000; ++k) {
    const Eigen::Vector3d o(200 * u(rng), 150 + 250 * u(rng), 3.0 + 2.0 * u(rng));
    const Eigen::Vector3d d = Eigen::Vector3d(u(rng), u(rng), 0.3 * u(rng)).normalized();
    const std::optional<RayHit> fast = w.Raycast(o, d, 100.0, WorldView::kLidar);
    // Brute force: the nearest hit over every present box, cut at the water.
    double best = d.z() < 0 ? std::min(100.0, (w.water_level_m() - o.z()) / d.z()) : 100.0;
    int best_box = -1;
    for (size_t i = 0; i < w.boxes().size(); ++i) {
      if (!w.boxes()[i].in_lidar) continue;
      const std::optional<RayHit> h = RaycastBox(ToOrientedBox(w.boxes()[i]), o, d, best);
      if (h && h->range_m < best) {
        best = h->range_m;
        best_box = static_cast<int>(i);
      }
    }
    ASSERT_EQ(fast.has_value(), best_box >= 0) << k;
    if (fast) {
      ++hits;
      EXPECT_NEAR(fast->range_m, best, 1e-9) << k;
    }
  }
  EXPECT_GT(hits, 300);
}

TEST(HarbourWorld, BoxesOverlapBySeparatingAxes) {
  OrientedBox a;  // the unit cube at the origin
  OrientedBox b;
  b.R_w_box = Eigen::AngleAxisd(kPi / 4, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  // b turned 45 deg about z reaches sqrt(2)/2 = 0.707 along x: they overlap when its centre is
  // nearer than 1.207.
  b.centre_w = Eigen::Vector3d(1.2, 0, 0);
  EXPECT_TRUE(BoxesOverlap(a, b));
  b.centre_w = Eigen::Vector3d(1.22, 0, 0);
  EXPECT_FALSE(BoxesOverlap(a, b));
  // Touching faces count as overlapping.
  b.R_w_box.setIdentity();
  b.centre_w = Eigen::Vector3d(1.0, 0.3, 0.2);
  EXPECT_TRUE(BoxesOverlap(a, b));
  // A cube of half size 1 turned 45 deg about x reaches sqrt(2) down: above [-1, 1]^3 it
  // overlaps while its centre is below 1 + sqrt(2) = 2.414.
  OrientedBox big;
  big.half_size_m = Eigen::Vector3d::Ones();
  OrientedBox tilted = big;
  tilted.R_w_box = Eigen::AngleAxisd(kPi / 4, Eigen::Vector3d::UnitX()).toRotationMatrix();
  tilted.centre_w = Eigen::Vector3d(0.3, 0, 2.40);
  EXPECT_TRUE(BoxesOverlap(big, tilted));
  tilted.centre_w.z() = 2.43;
  EXPECT_FALSE(BoxesOverlap(big, tilted));
  EXPECT_FALSE(BoxesOverlap(tilted, big));
  // Only one of b's own axes separates: a slab 4 x 0.2 across the diagonal u = (1, 1)/sqrt(2),
  // its centre c u. Along u the unit cube reaches 0.707 and the slab 0.1 (apart when
  // c > 0.807); along x the slab reaches 1.485 (apart only when c / sqrt(2) > 1.985).
  const Eigen::Vector3d u = Eigen::Vector3d(1, 1, 0).normalized();
  OrientedBox slab;
  slab.half_size_m = Eigen::Vector3d(2.0, 0.1, 0.5);
  slab.R_w_box = Eigen::AngleAxisd(-kPi / 4, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  slab.centre_w = 0.9 * u;
  EXPECT_FALSE(BoxesOverlap(a, slab));
  EXPECT_FALSE(BoxesOverlap(slab, a));
  slab.centre_w = 0.75 * u;
  EXPECT_TRUE(BoxesOverlap(a, slab));
  // A thin plate of half size 2 x 2 x 0.05 turned generically (no axis of it square to one of
  // the cube's, so that no edge-edge axis is its normal n), its centre c n: apart exactly when
  // c > r + 0.05, r = 0.5 (|n_x| + |n_y| + |n_z|) the unit cube's reach along n.
  OrientedBox plate;
  plate.half_size_m = Eigen::Vector3d(2.0, 2.0, 0.05);
  plate.R_w_box = (Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()) *
                   Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitY()) *
                   Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitX()))
                      .toRotationMatrix();
  const Eigen::Vector3d n = plate.R_w_box.col(2);
  const double reach = 0.5 * n.cwiseAbs().sum() + 0.05;
  plate.centre_w = (reach + 0.02) * n;
  EXPECT_FALSE(BoxesOverlap(a, plate));
  EXPECT_FALSE(BoxesOverlap(plate, a));
  plate.centre_w = (reach - 0.02) * n;
  EXPECT_TRUE(BoxesOverlap(a, plate));
  // Only an edge-edge axis separates: the cube [-1, 1]^3 and a cube of half size 1 with an edge
  // along e1 = (1, -1, 0)/sqrt(2) pointing at the cube's vertical edge (1, 1, z), its centre c u.
  // Along u = z x e1 they reach sqrt(2) and sqrt(2): apart when c > 2.828; along any face axis
  // of either they are apart only when c > 3.828.
  OrientedBox wedge = big;
  const Eigen::Vector3d e1 = Eigen::Vector3d(1, -1, 0).normalized();
  wedge.R_w_box.col(0) = e1;
  wedge.R_w_box.col(1) = (u + Eigen::Vector3d::UnitZ()).normalized();
  wedge.R_w_box.col(2) = (-u + Eigen::Vector3d::UnitZ()).normalized();
  ASSERT_NEAR(wedge.R_w_box.determinant(), 1.0, 1e-12);
  wedge.centre_w = 3.3 * u;
  EXPECT_FALSE(BoxesOverlap(big, wedge));
  wedge.centre_w = 2.7 * u;
  EXPECT_TRUE(BoxesOverlap(big, wedge));
}

TEST(HarbourWorld, IntersectsAndTerrainHeightSeeOnlyTheirView) {
  HarbourBox gone = Box(0, 0, 0, 8, 4, -1, 2, HarbourObjectKind::kBoat);
  gone.in_lidar = false;
  HarbourBox quay = Box(30, 0, 0, 20, 20, -5, 1.8);
  const HarbourWorld w({gone, quay}, 0.0);
  OrientedBox hull;
  hull.half_size_m = Eigen::Vector3d(7.5, 2.25, 1.25);
  EXPECT_TRUE(w.Intersects(hull, WorldView::kAll));
  EXPECT_TRUE(w.Intersects(hull, WorldView::kImage));
  EXPECT_FALSE(w.Intersects(hull, WorldView::kLidar));
  // x 4.7..19.7: clear of the boat (to x = 4) and of the quay's face at x = 20.
  hull.centre_w.x() = 12.2;
  EXPECT_FALSE(w.Intersects(hull, WorldView::kAll));
  // Turned by 0.3 rad it reaches 7.5 cos 0.3 + 2.25 sin 0.3 = 7.83 m either way: into the quay.
  hull.R_w_box = Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  EXPECT_TRUE(w.Intersects(hull, WorldView::kAll));
  EXPECT_DOUBLE_EQ(w.TerrainHeight({30, 0}, WorldView::kLidar), 1.8);
  EXPECT_DOUBLE_EQ(w.TerrainHeight({0, 0}, WorldView::kAll), 0.0);  // a boat is not terrain
  EXPECT_DOUBLE_EQ(w.TerrainHeight({-100, 0}, WorldView::kAll), 0.0);
}

TEST(HarbourWorld, TheBuiltInHarbourHasItsPartsAndItsBoatsFromTheSeed) {
  HarbourSpec spec;
  spec.enabled = true;
  spec.centre_east_m = 100.0;
  spec.centre_north_m = -50.0;
  const HarbourWorld w = BuildHarbour(spec, 7);
  std::map<HarbourObjectKind, int> kinds;
  int image_only = 0, lidar_only = 0, both = 0;
  for (const HarbourBox& b : w.boxes()) {
    ++kinds[b.kind];
    if (b.kind != HarbourObjectKind::kBoat) {
      EXPECT_TRUE(b.in_image && b.in_lidar);
      continue;
    }
    image_only += b.in_image && !b.in_lidar;
    lidar_only += !b.in_image && b.in_lidar;
    both += b.in_image && b.in_lidar;
  }
  // Each boat is a hull and a cabin.
  EXPECT_EQ(both, 2 * spec.boats_moored);
  EXPECT_EQ(image_only, 2 * spec.boats_image_only);
  EXPECT_EQ(lidar_only, 2 * spec.boats_lidar_only);
  EXPECT_EQ(kinds[HarbourObjectKind::kPier], 3);
  EXPECT_EQ(kinds[HarbourObjectKind::kBreakwater], 2);
  EXPECT_GE(kinds[HarbourObjectKind::kBuilding], 6);
  EXPECT_GE(kinds[HarbourObjectKind::kBollard], 40);
  EXPECT_GE(kinds[HarbourObjectKind::kPole], 10);
  EXPECT_EQ(kinds[HarbourObjectKind::kCraneLeg], 4);
  // The basin's centre is water, and the channel a 40 m wide gap between two quays over at
  // least 150 m, empty of anything standing in it.
  const HarbourLayout layout = HarbourLayoutOf(spec);
  EXPECT_EQ(layout.basin_centre_w, Eigen::Vector2d(100, -50));
  EXPECT_DOUBLE_EQ(w.TerrainHeight(layout.basin_centre_w, WorldView::kAll), 0.0);
  const Eigen::Vector2d along = (layout.channel_end_w - layout.channel_mouth_w).normalized();
  const Eigen::Vector2d across(-along.y(), along.x());
  EXPECT_GE((layout.channel_end_w - layout.channel_mouth_w).norm(), 150.0);
  for (double s = 5.0; s < 235.0; s += 10.0) {
    const Eigen::Vector2d c = layout.channel_mouth_w + s * along;
    EXPECT_DOUBLE_EQ(w.TerrainHeight(c + 19.0 * across, WorldView::kAll), 0.0) << s;
    EXPECT_DOUBLE_EQ(w.TerrainHeight(c - 19.0 * across, WorldView::kAll), 0.0) << s;
    EXPECT_DOUBLE_EQ(w.TerrainHeight(c + 21.0 * across, WorldView::kAll), 1.8) << s;
    EXPECT_DOUBLE_EQ(w.TerrainHeight(c - 21.0 * across, WorldView::kAll), 1.8) << s;
    OrientedBox gap;
    gap.centre_w = Eigen::Vector3d(c.x(), c.y(), 0.0);
    gap.half_size_m = Eigen::Vector3d(4.9, 19.9, 30.0);
    EXPECT_FALSE(w.Intersects(gap, WorldView::kAll)) << s;
  }
  // The same seed gives the same boats, another seed others.
  const HarbourWorld again = BuildHarbour(spec, 7);
  const HarbourWorld other = BuildHarbour(spec, 8);
  ASSERT_EQ(again.boxes().size(), w.boxes().size());
  bool same = true, differ = false;
  for (size_t i = 0; i < w.boxes().size(); ++i) {
    same = same && again.boxes()[i].centre_w == w.boxes()[i].centre_w;
    differ =
        differ || i >= other.boxes().size() || other.boxes()[i].centre_w != w.boxes()[i].centre_w;
  }
  EXPECT_TRUE(same);
  EXPECT_TRUE(differ);
  // Too many boats for the quays.
  spec.boats_moored = 150;
  EXPECT_THROW(BuildHarbour(spec, 1), std::invalid_argument);
}

}  // namespace
}  // namespace skerry::sim
