// The aerial photograph of the simulated harbour: terrain edges where they are, a tall
// building's roof displaced outward by h r / H, shadows on the side away from the sun, the
// deliberate georeferencing offset, and the written PNG + world file + .prj read back by
// geo::Orthophoto to within a millimetre.

#include "skerry/sim/aerial_render.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <opencv2/core.hpp>

#include "skerry/geo/orthophoto.h"

namespace skerry::sim {
namespace {

const GeoOrigin kOrigin{47.60, 9.45, 440.0};

HarbourBox Box(double x0,
               double x1,
               double y0,
               double y1,
               double bottom,
               double top,
               double albedo,
               HarbourObjectKind kind) {
  HarbourBox b;
  b.kind = kind;
  b.centre_w = Eigen::Vector2d(0.5 * (x0 + x1), 0.5 * (y0 + y1));
  b.length_m = x1 - x0;
  b.width_m = y1 - y0;
  b.bottom_m = bottom;
  b.top_m = top;
  b.albedo = albedo;
  return b;
}

// A quay (terrain, top 2 m above the water at 0) over x 0..60, y -30..30, and on it a building
// over x 35..45, y -5..5 with its roof 22 m up: 20 m above the quay.
HarbourWorld QuayAndBuilding() {
  return HarbourWorld({Box(0, 60, -30, 30, -5, 2, 0.3, HarbourObjectKind::kQuay),
                       Box(35, 45, -5, 5, 1.5, 22, 0.9, HarbourObjectKind::kBuilding)},
                      0.0);
}

AerialImageSim Options() {
  AerialImageSim o;
  o.resolution_m = 0.16;
  o.camera_height_m = 800.0;
  o.noise_grey = 0.0;
  o.sun_azimuth_deg = 135.0;  // south-east
  o.sun_elevation_deg = 40.0;
  return o;
}

// The camera over (-200, 0): the quay's edge 200 m east of its nadir, the building 235..245 m.
AerialPhoto Render(const AerialImageSim& options) {
  return RenderAerialPhoto(QuayAndBuilding(), kOrigin, options,
                           Eigen::AlignedBox2d(Eigen::Vector2d(-20, -40), Eigen::Vector2d(80, 40)),
                           Eigen::Vector2d(-200, 0), 1);
}

int GreyAt(const AerialPhoto& photo, const Eigen::Vector2d& p_w) {
  const Eigen::Vector2d uv = photo.EnuToPixel(p_w);
  const int u = static_cast<int>(std::lround(uv.x()));
  const int v = static_cast<int>(std::lround(uv.y()));
  EXPECT_TRUE(u >= 0 && v >= 0 && u < photo.grey.cols && v < photo.grey.rows) << p_w.transpose();
  return photo.grey.at<std::uint8_t>(v, u);
}

// Walking east along north = y from x0, the first x where the grey crosses `threshold`.
double EdgeAlongEast(const AerialPhoto& photo, double y, double x0, double x1, int threshold) {
  const bool above = GreyAt(photo, {x0, y}) > threshold;
  for (double x = x0; x <= x1; x += 0.01) {
    if ((GreyAt(photo, {x, y}) > threshold) != above) return x;
  }
  ADD_FAILURE() << "no edge between " << x0 << " and " << x1;
  return NAN;
}

double MeanGrey(const AerialPhoto& photo, const Eigen::Vector2d& centre) {
  double sum = 0.0;
  int n = 0;
  for (double dx = -1.0; dx <= 1.0; dx += 0.16) {
    for (double dy = -1.0; dy <= 1.0; dy += 0.16) {
      sum += GreyAt(photo, centre + Eigen::Vector2d(dx, dy));
      ++n;
    }
  }
  return sum / n;
}

TEST(AerialRender, TerrainEdgesLieWhereTheyAreAndARoofLeansOutwardByHrOverH) {
  const AerialPhoto photo = Render(Options());
  EXPECT_NEAR(photo.resolution_m, 0.16, 1e-12);
  EXPECT_EQ(photo.utm_zone, 32);
  // Water (albedo 0.09, here in the quay's shadow) to the quay's top (0.3, lit: grey 77): the
  // terrain is what the photograph is rectified to, so the edge is at x = 0 within a pixel
  // (rectified to the water instead, it would lie 2 m * 200 / 798 = 0.5 m further out).
  EXPECT_NEAR(EdgeAlongEast(photo, 0.0, -5.0, 5.0, 45), 0.0, 0.17);
  // The roof's east edge (x = 45, 20 m above the quay, 245 m from the nadir). The ray from the
  // camera (800 m above the water: H = 798 m above the quay) through it meets the quay at
  // -200 + 245 * 798 / 778 = 51.298: displaced by h r' / H = 20 * 251.298 / 798 = 6.298 m.
  const double east = EdgeAlongEast(photo, 0.0, 45.0, 60.0, 150);
  EXPECT_NEAR(east, 51.298, 0.17);
  EXPECT_NEAR(east - 45.0, 20.0 * (east + 200.0) / 798.0, 0.17);
  // Its west edge (x = 35, 235 m out) is displaced by 6.04 m over the building's west wall,
  // which faces the camera and, turned from the sun, shows at under half the roof's grey.
  EXPECT_NEAR(EdgeAlongEast(photo, 0.0, 34.0, 45.0, 170), -200.0 + 235.0 * 798.0 / 778.0, 0.17);
  const double ambient_share = 0.35 / (0.35 + 0.65 * std::sin(40.0 * M_PI / 180.0));
  EXPECT_NEAR(GreyAt(photo, {38.0, 0.0}), 255 * 0.9 * ambient_share, 0.15 * 106);
}

TEST(AerialRender, ShadowsFallOnTheSideAwayFromTheSun) {
  AerialImageSim options = Options();
  // Sun in the south-east: the building's shadow (23.8 m long) falls north-west of it.
  const AerialPhoto se = Render(options);
  const double north_west = MeanGrey(se, {33.0, 8.0});
  const double south_east = MeanGrey(se, {48.0, -8.0});
  EXPECT_NEAR(south_east, 77.0, 12.0);  // the lit quay
  EXPECT_LT(north_west, 0.6 * south_east);
  // Sun in the north-west: the other way round.
  options.sun_azimuth_deg = 315.0;
  const AerialPhoto nw = Render(options);
  EXPECT_LT(MeanGrey(nw, {48.0, -8.0}), 0.6 * MeanGrey(nw, {33.0, 8.0}));
}

TEST(AerialRender, AnImageOffsetMovesEverythingByIt) {
  AerialImageSim options = Options();
  options.image_offset_east_m = 3.0;
  const AerialPhoto photo = Render(options);
  EXPECT_NEAR(EdgeAlongEast(photo, 0.0, -5.0, 10.0, 45), 3.0, 0.17);
  EXPECT_NEAR(EdgeAlongEast(photo, 0.0, 45.0, 60.0, 150), 51.298 + 3.0, 0.17);
}

TEST(AerialRender, TheWorldFileAndPrjRoundTripThroughTheOrthophotoReader) {
  AerialImageSim options = Options();
  options.noise_grey = 2.0;
  const AerialPhoto photo = Render(options);
  const std::filesystem::path dir = std::filesystem::path(SKERRY_TEST_TMP_DIR) / "aerial_render";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "photo.png").string();
  WriteAerialPhoto(photo, path);
  ASSERT_TRUE(std::filesystem::exists(dir / "photo.pgw"));
  ASSERT_TRUE(std::filesystem::exists(dir / "photo.prj"));

  const geo::Orthophoto ortho(path, LocalFrame(kOrigin));
  EXPECT_EQ(ortho.crs_source().rfind("sidecar", 0), 0u) << ortho.crs_source();
  EXPECT_NE(ortho.crs_wkt().find("UTM zone 32N"), std::string::npos);
  ASSERT_EQ(ortho.width(), photo.grey.cols);
  ASSERT_EQ(ortho.height(), photo.grey.rows);
  EXPECT_EQ(cv::norm(ortho.image(), photo.grey, cv::NORM_INF), 0.0);  // PNG is lossless
  EXPECT_NEAR(ortho.ground_sample_distance_m(), 0.16, 0.001);
  // Pixel <-> ENU through GDAL and PROJ against the renderer's own map: well within a pixel.
  const double h_water = kOrigin.height_m;
  const double w = ortho.width() - 1, h = ortho.height() - 1;
  for (const Eigen::Vector2d& uv :
       {Eigen::Vector2d(0, 0), Eigen::Vector2d(w, 0), Eigen::Vector2d(0, h), Eigen::Vector2d(w, h),
        Eigen::Vector2d(0.5 * w, 0.3 * h)}) {
    const Eigen::Vector2d expected = photo.pixel_to_enu * uv.homogeneous();
    EXPECT_NEAR((ortho.PixelToEnu(uv.x(), uv.y(), h_water).head<2>() - expected).norm(), 0.0, 0.001)
        << uv.transpose();
    EXPECT_NEAR((ortho.EnuToPixel({expected.x(), expected.y(), 0.0}) - uv).norm(), 0.0, 0.01);
  }
  // Covering what was asked.
  EXPECT_TRUE(ortho.Covers({-19.9, -39.9, 0}));
  EXPECT_TRUE(ortho.Covers({79.9, 39.9, 0}));
}

}  // namespace
}  // namespace skerry::sim
