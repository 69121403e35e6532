#include "skerry/skyline/horizon_for_track.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "skerry/geo/dem.h"
#include "skerry/geo/terrain_sharpening.h"
#include "skerry/skyline/crest_correlation.h"

namespace skerry::skyline {
namespace {

constexpr double kDeg = M_PI / 180.0;

const std::string kCoteDazurDem = std::string(SKERRY_SHARED_DATA_DIR) + "/dem/N43E007.hgt";

// The Côte d'Azur tile in the ENU frame of the skyline scenario off Nice.
geo::Dem CoteDazurDem() {
  return geo::Dem(kCoteDazurDem, LocalFrame({43.62, 7.25, 48.0}),
                  geo::DemOptions(geo::VerticalDatum::kEgm96));
}

// The map's spacing: the key when set, else the DEM's cell over the oversampling, cut back to
// what kMaxOversampledMapNodes holds on a large box, never coarser than the cell.
TEST(MapSpacing, OversamplesTheCellWithinItsBudget) {
  if (!std::filesystem::exists(kCoteDazurDem)) GTEST_SKIP() << kCoteDazurDem << " missing";
  const geo::Dem dem = CoteDazurDem();
  const double cell = dem.cell_size_m().minCoeff();
  const Eigen::AlignedBox2d box(Eigen::Vector2d(-50000, -50000), Eigen::Vector2d(50000, 50000));
  SkylineConfig config;
  EXPECT_DOUBLE_EQ(MapSpacing(dem, box, config), cell / 2);
  config.dem_oversampling = 1;
  EXPECT_DOUBLE_EQ(MapSpacing(dem, box, config), cell);
  config.dem_oversampling = 3;
  EXPECT_DOUBLE_EQ(MapSpacing(dem, box, config), cell / 3);
  config.dem_spacing_m = 50.0;
  EXPECT_DOUBLE_EQ(MapSpacing(dem, box, config), 50.0);
  // A box too large for half the cell: as fine as the budget allows, and the cell at most.
  config = SkylineConfig();
  const Eigen::AlignedBox2d large(Eigen::Vector2d(-150000, -150000),
                                  Eigen::Vector2d(150000, 150000));
  const double spacing = MapSpacing(dem, large, config);
  EXPECT_GT(spacing, cell / 2);
  EXPECT_LT(spacing, cell);
  EXPECT_NEAR(300000.0 * 300000.0 / (spacing * spacing), kMaxOversampledMapNodes,
              0.01 * kMaxOversampledMapNodes);
  const Eigen::AlignedBox2d huge(Eigen::Vector2d(-1e6, -1e6), Eigen::Vector2d(1e6, 1e6));
  EXPECT_DOUBLE_EQ(MapSpacing(dem, huge, config), cell);
}

// Why the map is oversampled, on the real Côte d'Azur DEM (3": a 67 m cell) and without the
// simulator: the raster's own bilinear surface (sampled at a quarter of its cell, the reference)
// against maps of it at its cell and at half of it, all from one box corner. A camera 4 m above
// the sea off Nice looks north at the Maritime Alps 10-50 km away; per azimuth over 30°, where the
// three horizons are land on the same ridge, the map's horizon minus the reference's, in pixels
// of the simulated camera (1371 px/rad). At the raster's cell the map's nodes fall between the
// raster's and every crest is cut: the skyline sinks by 0.13 px on average (at 30 km, 50 m of
// range). At half the cell it sinks by 0.05 px. The loss grows about linearly with the spacing
// (a crest is a kink of the raster's surface), so the reference itself is some 0.04 px low and
// half the cell leaves about half of the loss at the cell.
TEST(MapSpacing, HalfTheCellHalvesTheCrestsLoss) {
  if (!std::filesystem::exists(kCoteDazurDem)) GTEST_SKIP() << kCoteDazurDem << " missing";
  const geo::Dem dem = CoteDazurDem();
  const double cell = dem.cell_size_m().minCoeff();
  const Eigen::AlignedBox2d box(Eigen::Vector2d(-16000, -1000), Eigen::Vector2d(16000, 56000));
  const HorizonPredictor reference(dem.ResampleToEnu(box, cell / 4));
  const HorizonPredictor at_cell(dem.ResampleToEnu(box, cell));
  const HorizonPredictor at_half(dem.ResampleToEnu(box, cell / 2));
  const Eigen::Vector3d camera(0.0, 0.0, 4.0);
  constexpr double kPxPerRad = 1371.0;
  double sum_cell = 0, sum_half = 0;
  int n = 0;
  for (double a = -15.0; a <= 15.0; a += 0.05) {
    const HorizonSample r = reference.Trace(camera, a * kDeg);
    const HorizonSample c = at_cell.Trace(camera, a * kDeg);
    const HorizonSample h = at_half.Trace(camera, a * kDeg);
    if (!r.valid || !c.valid || !h.valid || r.truncated || c.truncated || h.truncated) continue;
    if (r.distance_m < 5000.0 || HorizonOnWater(reference, r.point_w)) continue;
    if (std::abs(c.distance_m - r.distance_m) > 300.0) continue;
    if (std::abs(h.distance_m - r.distance_m) > 300.0) continue;
    sum_cell += (c.elevation_rad - r.elevation_rad) * kPxPerRad;
    sum_half += (h.elevation_rad - r.elevation_rad) * kPxPerRad;
    ++n;
  }
  ASSERT_GT(n, 300);
  const double mean_cell = sum_cell / n, mean_half = sum_half / n;
  std::printf(
      "%d azimuths: the map's skyline against the raster's, mean %+.3f px at the cell "
      "(%.1f m), %+.3f px at half of it\n",
      n, mean_cell, cell, mean_half);
  EXPECT_LT(mean_cell, -0.08);
  EXPECT_LT(mean_half, 0.0);
  EXPECT_GT(mean_half, 0.5 * mean_cell);
}

// skyline.dem_sharpening reaches the map: the predictor's grid is the plain map sharpened with
// the configured gain and a footprint of dem_footprint_cells of the DEM's cell, to the bit; the
// land changes by metres and the sea not at all.
TEST(HorizonForTrack, SharpensTheMapWhenConfigured) {
  if (!std::filesystem::exists(kCoteDazurDem)) GTEST_SKIP() << kCoteDazurDem << " missing";
  const geo::Dem dem = CoteDazurDem();
  SkylineConfig config;
  config.max_range_m = 8000.0;
  const geo::EnuHeightGrid plain = HorizonForTrack(dem, {}, config)->grid();
  config.dem_sharpening = 1.0;
  config.dem_footprint_cells = 0.6;
  const geo::EnuHeightGrid sharp = HorizonForTrack(dem, {}, config)->grid();
  geo::EnuHeightGrid expected = plain;
  geo::SharpenTerrain({1.0, 0.6 * dem.cell_size_m().minCoeff()}, 6371000.0, &expected);
  ASSERT_EQ(sharp.up_m.size(), plain.up_m.size());
  double largest = 0.0;
  int sea = 0;
  for (int row = 0; row < plain.rows; ++row) {
    for (int col = 0; col < plain.cols; ++col) {
      const size_t i = static_cast<size_t>(row) * plain.cols + col;
      if (std::isnan(expected.up_m[i])) {
        EXPECT_TRUE(std::isnan(sharp.up_m[i])) << col << ", " << row;
        continue;
      }
      EXPECT_EQ(sharp.up_m[i], expected.up_m[i]) << col << ", " << row;
      largest = std::max(largest, std::abs(sharp.up_m[i] - plain.up_m[i]));
      if (plain.LevelAround(col, row, 6371000.0)) {
        ++sea;
        EXPECT_EQ(sharp.up_m[i], plain.up_m[i]);
      }
    }
  }
  EXPECT_GT(largest, 1.0);
  EXPECT_GT(sea, 1000);
}

// skyline.dem_sharpening_sigma > 0: the gain is estimated, so the map stays plain (even with a
// dem_sharpening, which is then the prior) and carries the detail a gain of 1 would add, 0 on
// the sea; DetailAt reads it, 0 off the map.
TEST(HorizonForTrack, CarriesTheMapsDetailWhenTheGainIsEstimated) {
  if (!std::filesystem::exists(kCoteDazurDem)) GTEST_SKIP() << kCoteDazurDem << " missing";
  const geo::Dem dem = CoteDazurDem();
  SkylineConfig config;
  config.max_range_m = 8000.0;
  const auto plain = HorizonForTrack(dem, {}, config);
  EXPECT_FALSE(plain->has_detail());
  EXPECT_EQ(plain->DetailAt(0.0, 0.0), 0.0);
  config.dem_sharpening = 0.5;
  config.dem_sharpening_sigma = 1.0;
  config.dem_footprint_cells = 0.6;
  const auto estimated = HorizonForTrack(dem, {}, config);
  ASSERT_TRUE(estimated->has_detail());
  const geo::EnuHeightGrid& g = estimated->grid();
  geo::EnuHeightGrid once = plain->grid();
  geo::SharpenTerrain({1.0, 0.6 * dem.cell_size_m().minCoeff()}, 6371000.0, &once);
  double largest = 0.0;
  int sea = 0;
  for (int row = 0; row < g.rows; ++row) {
    for (int col = 0; col < g.cols; ++col) {
      const size_t i = static_cast<size_t>(row) * g.cols + col;
      if (std::isnan(g.up_m[i])) continue;
      EXPECT_EQ(g.up_m[i], plain->grid().up_m[i]) << col << ", " << row;
      const Eigen::Vector2d p = g.NodePosition(col, row);
      if (!g.UpAt(p.x(), p.y())) continue;  // the border, or beside a void: no bilinear value
      const double detail = estimated->DetailAt(p.x(), p.y());
      EXPECT_NEAR(detail, once.up_m[i] - g.up_m[i], 1e-6) << col << ", " << row;
      largest = std::max(largest, std::abs(detail));
      if (g.LevelAround(col, row, 6371000.0)) {
        ++sea;
        EXPECT_EQ(detail, 0.0);
      }
    }
  }
  EXPECT_GT(largest, 1.0);
  EXPECT_GT(sea, 1000);
  EXPECT_EQ(estimated->DetailAt(1e7, 0.0), 0.0);
  // A detail of another geometry is refused.
  auto other = std::make_shared<HorizonPredictor>(plain->grid());
  geo::EnuHeightGrid wrong = plain->grid();
  wrong.cols -= 1;
  EXPECT_THROW(other->AttachDetail(wrong), std::invalid_argument);
}

}  // namespace
}  // namespace skerry::skyline
