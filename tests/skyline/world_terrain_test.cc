// The simulator's world against the estimator's map of it (sim/world_terrain.h), on the real
// Lake Constance tile: the same raster, but no node shared, and between them the two differ by
// the raster's resampling, as a real map differs from the terrain it was made from.

#include "skerry/sim/world_terrain.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <vector>

#include "skerry/geo/dem.h"
#include "skerry/skyline/horizon_for_track.h"

namespace skerry::sim {
namespace {

TEST(WorldTerrain, TheWorldIsTheRasterOnNodesTheMapDoesNotHave) {
  const std::string path = std::string(SKERRY_SHARED_DATA_DIR) + "/dem/N47E009.hgt";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " missing";
  const LocalFrame frame({47.60, 9.40, 438.42});
  const geo::Dem dem(path, frame, geo::DemOptions(geo::VerticalDatum::kEgm96));
  // A box as the estimator's horizon takes it (skyline::HorizonBox, cut to the footprint), off
  // any round number; and the map the estimator resamples from it at its default spacing
  // (skyline::HorizonForTrack: half the raster's cell).
  const Eigen::AlignedBox2d box(Eigen::Vector2d(-7321.4, -3113.9), Eigen::Vector2d(9876.5, 8765.4));
  const double cell = dem.cell_size_m().minCoeff();
  const double map_spacing = skyline::MapSpacing(dem, box, SkylineConfig());
  EXPECT_DOUBLE_EQ(map_spacing, 0.5 * cell);
  const geo::EnuHeightGrid map = dem.ResampleToEnu(box, map_spacing);
  const geo::EnuHeightGrid world = WorldTerrain(dem, box);

  EXPECT_DOUBLE_EQ(world.spacing_m, 0.5 * cell);
  EXPECT_GE(world.cols, map.cols - 2);
  EXPECT_GE(world.rows, map.rows - 2);
  // No world node within a third of the map's spacing of a map node (they sit half of it off, in
  // x and y: 0.71 of it away); nor of a node of a map at the raster's own cell (0.35 cell away).
  for (const double spacing : {map_spacing, cell}) {
    double nearest = 1e9;
    for (int row = 0; row < world.rows; ++row) {
      for (int col = 0; col < world.cols; ++col) {
        const Eigen::Vector2d f = (world.NodePosition(col, row) - map.origin_w) / spacing;
        const Eigen::Vector2d off(f.x() - std::round(f.x()), f.y() - std::round(f.y()));
        nearest = std::min(nearest, off.norm());
      }
    }
    EXPECT_GT(nearest, 1.0 / 3.0) << "a world node is (nearly) one of the map's at " << spacing;
  }

  // Each world node is the raster's surface there, unperturbed: the same as the raster resampled
  // at that one point.
  for (int row = 3; row < world.rows; row += 97) {
    for (int col = 5; col < world.cols; col += 89) {
      const Eigen::Vector2d p = world.NodePosition(col, row);
      const geo::EnuHeightGrid one = dem.ResampleToEnu(Eigen::AlignedBox2d(p, p), 1.0);
      ASSERT_EQ(one.up_m.size(), 1u);
      EXPECT_NEAR(world.at(col, row), one.up_m[0], 1e-6) << "node " << col << ", " << row;
    }
  }

  // At the map's nodes on land the world differs from the map by the raster's resampling:
  // decimetres to metres on these hills, never tens.
  std::vector<double> diff;
  for (int row = 0; row < map.rows; ++row) {
    for (int col = 0; col < map.cols; ++col) {
      const Eigen::Vector2d p = map.NodePosition(col, row);
      const std::optional<double> z = world.UpAt(p.x(), p.y());
      if (!z || !std::isfinite(map.at(col, row))) continue;
      if (!map.LevelAround(col, row, 6371000.0)) diff.push_back(std::abs(*z - map.at(col, row)));
    }
  }
  ASSERT_GT(diff.size(), static_cast<size_t>(map.cols * map.rows / 4));
  std::sort(diff.begin(), diff.end());
  const double median = diff[diff.size() / 2];
  const double p99 = diff[diff.size() * 99 / 100];
  std::printf("|world - map| at the map's nodes on land: median %.3f m, p99 %.3f m, max %.3f m\n",
              median, p99, diff.back());
  EXPECT_GT(p99, 0.2);
  EXPECT_LT(median, 1.0);
  EXPECT_LT(diff.back(), 30.0);
}

}  // namespace
}  // namespace skerry::sim
