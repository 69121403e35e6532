// geo::SharpenTerrain against a ridge blurred by a known footprint: the crest comes back towards
// the ridge's own height, the mean over the land is kept, water and voids are left alone, and bad
// arguments are refused.

#include "skerry/geo/terrain_sharpening.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

namespace skerry::geo {
namespace {

constexpr double kEarthRadiusM = 6371000.0;

// A grid of 121 x 41 nodes at 10 m, the origin at its centre (so the Earth's curvature hardly
// enters the water test: at 600 m it is 3 cm).
EnuHeightGrid Grid(double (*height)(double x, double y)) {
  EnuHeightGrid g;
  g.spacing_m = 10.0;
  g.cols = 121;
  g.rows = 41;
  g.origin_w = Eigen::Vector2d(-600.0, -200.0);
  g.up_m.resize(121 * 41);
  for (int r = 0; r < g.rows; ++r) {
    for (int c = 0; c < g.cols; ++c) {
      const Eigen::Vector2d p = g.NodePosition(c, r);
      g.up_m[r * g.cols + c] = height(p.x(), p.y()) - p.squaredNorm() / (2.0 * kEarthRadiusM);
    }
  }
  return g;
}

// A ridge running north-south, 200 m high with flanks of slope 1, on land rising gently (1 in 50)
// east of x = -500 m; level water (0 m) west of it.
double Ridge(double x, double /*y*/) {
  return x < -500.0 ? 0.0 : std::max(0.0, 200.0 - std::abs(x)) + 1.0 + 0.02 * (x + 500.0);
}

// The ridge averaged over a Gaussian footprint of 20 m (1-D along x: the ridge does not vary
// along y), by quadrature: the raster a sensor with that footprint would give.
double BlurredRidge(double x, double y) {
  if (x < -500.0) return 0.0;
  double sum = 0.0, weight = 0.0;
  for (double u = -80.0; u <= 80.0; u += 0.5) {
    const double w = std::exp(-0.5 * u * u / (20.0 * 20.0));
    sum += w * Ridge(std::max(-500.0, x + u), y);
    weight += w;
  }
  return sum / weight;
}

double Up(const EnuHeightGrid& g, int c, int r) {
  const Eigen::Vector2d p = g.NodePosition(c, r);
  return g.at(c, r) + p.squaredNorm() / (2.0 * kEarthRadiusM);
}

TEST(TerrainSharpening, ARidgeBlurredByItsFootprintComesBackTowardsItsCrest) {
  EnuHeightGrid g = Grid(BlurredRidge);
  const EnuHeightGrid before = g;
  SharpenTerrain({1.0, 20.0}, kEarthRadiusM, &g);
  // The crest (x = 0: column 60): the blurred raster is sigma sqrt(2 / pi) = 16.0 m low; one
  // van Cittert iteration gives back sqrt(2) - 1 of that at a kink (the raster blurred twice
  // is sqrt(2) sigma wide: the crest 6.6 m up, 9.4 m still missing), and does not overshoot.
  const double crest_before = Up(before, 60, 20), crest_after = Up(g, 60, 20);
  EXPECT_NEAR(crest_before, 211.0 - 20.0 * std::sqrt(2.0 / M_PI), 0.1);
  EXPECT_NEAR(crest_after - crest_before, 20.0 * std::sqrt(2.0 / M_PI) * (std::sqrt(2.0) - 1.0),
              0.3);
  // Mid-flank (x = 100 m, five footprints from the crest and the foot) the ridge is straight:
  // nothing to restore there.
  EXPECT_NEAR(Up(g, 70, 20), Up(before, 70, 20), 0.05);
  // The mean over the land around the ridge is kept (the high-pass has zero mean): the feet
  // sink by what the crest gains.
  double sum_before = 0.0, sum_after = 0.0;
  for (int r = 0; r < g.rows; ++r) {
    for (int c = 20; c < g.cols; ++c) {
      sum_before += Up(before, c, r);
      sum_after += Up(g, c, r);
    }
  }
  const double n = g.rows * (g.cols - 20);
  EXPECT_NEAR(sum_after / n, sum_before / n, 0.01);
  // Water (level over its 3 x 3 nodes) is kept to the bit.
  for (int r = 0; r < g.rows; ++r) {
    for (int c = 0; c < 9; ++c) EXPECT_EQ(g.at(c, r), before.at(c, r)) << c << ", " << r;
  }
}

TEST(TerrainSharpening, VoidsStayVoidAndDoNotPullTheirNeighboursDown) {
  EnuHeightGrid g = Grid([](double x, double y) { return 500.0 + 0.1 * x + 0.05 * y; });
  g.up_m[20 * g.cols + 60] = NAN;
  const EnuHeightGrid before = g;
  SharpenTerrain({1.0, 20.0}, kEarthRadiusM, &g);
  EXPECT_TRUE(std::isnan(g.at(60, 20)));
  // A plane is its own blur, and where its nodes are all there sharpening leaves it (the
  // Earth's curvature bends it by millimetres; away from the grid's edges, where the blur's
  // reflection bends the plane). Next to the void the blur's centre of mass
  // moves off the missing node, by a few hundredths of a node on a slope of 1 m per node: the
  // plane moves there by centimetres, never by the 500 m a blur taking the void for 0 would.
  for (int r = 10; r < g.rows - 10; ++r) {
    for (int c = 10; c < g.cols - 10; ++c) {
      if (c == 60 && r == 20) continue;
      const bool near_void = std::abs(c - 60) <= 8 && std::abs(r - 20) <= 8;
      EXPECT_NEAR(g.at(c, r), before.at(c, r), near_void ? 0.08 : 2e-3) << c << ", " << r;
    }
  }
}

// A lake's shore: level water west of x = 0, a bank rising from 5 m at 1 in 5 east of it. The
// bank is a plane, so nothing is to be restored anywhere on it: with the water in the blur's mean
// the shore would rise into a wall (a lake's skyline is mostly its shores), and a mean over the
// land alone leans uphill and would sink it; the taper keeps it.
TEST(TerrainSharpening, AShoreIsNeitherAWallNorAPit) {
  EnuHeightGrid g = Grid([](double x, double) { return x < 0.0 ? 0.0 : 5.0 + 0.2 * x; });
  const EnuHeightGrid before = g;
  SharpenTerrain({2.0, 20.0}, kEarthRadiusM, &g);
  double worst = 0.0;
  for (int r = 10; r < g.rows - 10; ++r) {
    for (int c = 0; c < g.cols - 10; ++c)
      worst = std::max(worst, std::abs(g.at(c, r) - before.at(c, r)));
  }
  EXPECT_LT(worst, 0.4);
  EXPECT_DOUBLE_EQ(ShoreTaper(0.5), 0.0);
  EXPECT_DOUBLE_EQ(ShoreTaper(0.9), 0.0);
  EXPECT_NEAR(ShoreTaper(0.95), 0.5, 1e-12);
  EXPECT_DOUBLE_EQ(ShoreTaper(1.0), 1.0);
}

TEST(TerrainSharpening, GainZeroChangesNothingAndBadArgumentsAreRefused) {
  EnuHeightGrid g = Grid(BlurredRidge);
  const std::vector<double> before = g.up_m;
  SharpenTerrain({0.0, 0.0}, kEarthRadiusM, &g);
  EXPECT_EQ(g.up_m, before);
  EXPECT_THROW(SharpenTerrain({-1.0, 20.0}, kEarthRadiusM, &g), std::invalid_argument);
  EXPECT_THROW(SharpenTerrain({NAN, 20.0}, kEarthRadiusM, &g), std::invalid_argument);
  EXPECT_THROW(SharpenTerrain({1.0, 0.0}, kEarthRadiusM, &g), std::invalid_argument);
  EXPECT_THROW(SharpenTerrain({1.0, INFINITY}, kEarthRadiusM, &g), std::invalid_argument);
  EXPECT_EQ(g.up_m, before);
}

}  // namespace
}  // namespace skerry::geo
