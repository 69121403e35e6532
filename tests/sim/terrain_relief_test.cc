// The relief the raster averaged away, given back to the simulator's world (terrain_relief.h):
// a ridge seen through the footprint the model assumes comes back towards its crest, further
// than one iteration brings it, straight slopes and water stay as they are, and bad arguments
// are refused.

#include "skerry/sim/terrain_relief.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

namespace skerry::sim {
namespace {

constexpr double kEarthRadiusM = 6371000.0;
constexpr double kCellM = 60.0;                // the raster's cell; the world's grid at half of it
constexpr double kFootprintM = 0.75 * kCellM;  // TerrainReliefSpec's default footprint

// A ridge along y, 400 m high with flanks of slope 1, on land 1 m high east of x = -800 m;
// level water at 0 west of it.
double Ridge(double x) { return x < -800.0 ? 0.0 : std::max(0.0, 400.0 - std::abs(x)) + 1.0; }

// The ridge as a raster holds it: its mean over a Gaussian footprint of kFootprintM (1-D: the
// ridge does not vary along y), by quadrature.
double Raster(double x) {
  if (x < -800.0) return 0.0;
  double sum = 0.0, weight = 0.0;
  for (double u = -5 * kFootprintM; u <= 5 * kFootprintM; u += 0.5) {
    const double w = std::exp(-0.5 * u * u / (kFootprintM * kFootprintM));
    sum += w * Ridge(std::max(-800.0, x + u));
    weight += w;
  }
  return sum / weight;
}

geo::EnuHeightGrid World() {
  geo::EnuHeightGrid g;
  g.spacing_m = 0.5 * kCellM;
  g.cols = 81;
  g.rows = 21;
  g.origin_w = Eigen::Vector2d(-1200.0, -300.0);
  g.up_m.resize(g.cols * g.rows);
  for (int r = 0; r < g.rows; ++r) {
    for (int c = 0; c < g.cols; ++c) {
      const Eigen::Vector2d p = g.NodePosition(c, r);
      g.up_m[r * g.cols + c] = Raster(p.x()) - p.squaredNorm() / (2.0 * kEarthRadiusM);
    }
  }
  return g;
}

double Up(const geo::EnuHeightGrid& g, int c, int r) {
  return g.at(c, r) + g.NodePosition(c, r).squaredNorm() / (2.0 * kEarthRadiusM);
}

TEST(TerrainRelief, ARidgeSeenThroughItsFootprintComesBackTowardsItsCrest) {
  const geo::EnuHeightGrid before = World();
  geo::EnuHeightGrid world = before;
  AddTerrainRelief({1.0}, kCellM, kEarthRadiusM, &world);
  // The crest (x = 0: column 40): the raster is sigma sqrt(2 / pi) = 35.9 m low. One van
  // Cittert iteration gives back sqrt(2) - 1 of that at a kink (TerrainSharpening's test);
  // three give back more, and never more than the loss.
  const double loss = 401.0 - Up(before, 40, 10);
  EXPECT_NEAR(loss, kFootprintM * std::sqrt(2.0 / M_PI), 0.1);
  const double gained = Up(world, 40, 10) - Up(before, 40, 10);
  EXPECT_GT(gained, (std::sqrt(2.0) - 1.0) * loss + 1.0);
  EXPECT_LT(gained, loss);
  // Halfway down the flank (x = 200 m) the slope is straight: next to nothing to give back.
  EXPECT_NEAR(Up(world, 47, 10), Up(before, 47, 10), 0.1);
  // Water is kept to the bit; the gain scales the relief.
  for (int r = 0; r < world.rows; ++r) {
    for (int c = 0; c < 12; ++c) EXPECT_EQ(world.at(c, r), before.at(c, r)) << c << ", " << r;
  }
  geo::EnuHeightGrid half = before;
  AddTerrainRelief({0.5}, kCellM, kEarthRadiusM, &half);
  EXPECT_NEAR(Up(half, 40, 10) - Up(before, 40, 10), 0.5 * gained, 1e-9);
}

TEST(TerrainRelief, GainZeroChangesNothingAndBadArgumentsAreRefused) {
  geo::EnuHeightGrid world = World();
  const std::vector<double> before = world.up_m;
  AddTerrainRelief({0.0}, 0.0, kEarthRadiusM, &world);
  EXPECT_EQ(world.up_m, before);
  EXPECT_THROW(AddTerrainRelief({-0.5}, kCellM, kEarthRadiusM, &world), std::invalid_argument);
  EXPECT_THROW(AddTerrainRelief({NAN}, kCellM, kEarthRadiusM, &world), std::invalid_argument);
  EXPECT_THROW(AddTerrainRelief({1.0}, 0.0, kEarthRadiusM, &world), std::invalid_argument);
  EXPECT_THROW(AddTerrainRelief({1.0}, NAN, kEarthRadiusM, &world), std::invalid_argument);
  EXPECT_THROW(AddTerrainRelief({1.0, 0.0}, kCellM, kEarthRadiusM, &world), std::invalid_argument);
  EXPECT_EQ(world.up_m, before);
}

}  // namespace
}  // namespace skerry::sim
