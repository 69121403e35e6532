// AerialMap: the orthophoto resampled onto an ENU grid (checked against the image itself on the
// real Autzen photo, whose Lambert grid is rotated against ENU), its edges and the distance to
// them (checked on a synthetic square of known size), and bad requests.

#include "skerry/lidar_aerial/aerial_map.h"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>

#include "lidar_aerial/synthetic_scene.h"

namespace skerry::lidar_aerial {
namespace {

using geo::testing::FreshDir;
using geo::testing::kData;

TEST(AerialMap, ASquaresEdgesAreWhereItIsAndDistancesGrowInsideIt) {
  testing::Scene scene;
  scene.boxes = {{{100.0, 100.0}, {6.0, 6.0}, 0.0, 2.0, 200, 50}};
  const geo::Orthophoto ortho = testing::LoadScene(testing::WriteAerialImage(scene, FreshDir("s")));
  const Eigen::Vector2d centre = testing::GridToEnu(scene, ortho, {100.0, 100.0});
  const Eigen::AlignedBox2d box(centre - Eigen::Vector2d(20, 20), centre + Eigen::Vector2d(20, 20));
  AerialMapOptions o;
  o.resolution_m = 0.25;
  o.blur_m = 0.3;
  const AerialMap map(ortho, box, o);
  EXPECT_NEAR(map.cols(), 161, 1);
  EXPECT_NEAR(map.rows(), 161, 1);
  const auto distance = [&](const Eigen::Vector2d& xy) {
    const Eigen::Vector2d g = map.ToGrid(xy);
    return map.distance().at<float>(static_cast<int>(std::lround(g.y())),
                                    static_cast<int>(std::lround(g.x())));
  };
  // On each side's midpoint: an edge within a cell; at the centre: 3 m from every side.
  for (const Eigen::Vector2d& side : {Eigen::Vector2d(103, 100), Eigen::Vector2d(97, 100),
                                      Eigen::Vector2d(100, 103), Eigen::Vector2d(100, 97)}) {
    EXPECT_LE(distance(testing::GridToEnu(scene, ortho, side)), 0.3) << side.transpose();
  }
  EXPECT_NEAR(distance(centre), 3.0, 0.3);
  // Far from the square, the clip.
  EXPECT_FLOAT_EQ(distance(centre + Eigen::Vector2d(15, 15)), o.max_distance_m);
  // Every edge lies on the square's outline (within a cell and a half).
  int edges = 0;
  for (int r = 0; r < map.rows(); ++r) {
    for (int c = 0; c < map.cols(); ++c) {
      if (map.edges().at<std::uint8_t>(r, c) == 0) continue;
      ++edges;
      const Eigen::Vector2d d = (map.ToEnu({c, r}) - centre).cwiseAbs();
      EXPECT_NEAR(d.maxCoeff(), 3.0, 0.4) << c << "," << r;
    }
  }
  EXPECT_GT(edges, 4 * 6 / 0.25 * 0.8);
}

TEST(AerialMap, GridAndEnuConvertBothWaysAndCoverageFollowsTheImage) {
  testing::Scene scene;
  scene.width_m = 50;
  scene.height_m = 40;
  const geo::Orthophoto ortho = testing::LoadScene(testing::WriteAerialImage(scene, FreshDir("s")));
  // Asked for more than the image: the map is clipped to it.
  const Eigen::AlignedBox2d box(Eigen::Vector2d(-100, -100), Eigen::Vector2d(100, 100));
  const AerialMap map(ortho, box);
  EXPECT_NEAR(map.cols() * map.resolution_m(), 50.0, 1.0);
  EXPECT_NEAR(map.rows() * map.resolution_m(), 40.0, 1.0);
  const Eigen::Vector2d xy(3.21, -4.56);
  EXPECT_LT((map.ToEnu(map.ToGrid(xy)) - xy).norm(), 1e-12);
  EXPECT_TRUE(map.Covers({0.0, 0.0}));
  EXPECT_FALSE(map.Covers({30.0, 0.0}));
  EXPECT_FALSE(map.Covers({0.0, -25.0}));
}

// A grey orthophoto's pixels are shared with the map's source: building a map coarser than the
// image (which blurs the source first) must leave the orthophoto as it was.
TEST(AerialMap, BuildingAMapLeavesTheOrthophotoUntouched) {
  testing::Scene scene;
  scene.width_m = 60;
  scene.height_m = 40;
  scene.boxes = {{{30.0, 20.0}, {6.0, 6.0}, 0.3, 2.0, 200, 50}};
  const geo::Orthophoto ortho = testing::LoadScene(testing::WriteAerialImage(scene, FreshDir("s")));
  ASSERT_EQ(ortho.image().channels(), 1);
  const cv::Mat before = ortho.image().clone();
  AerialMapOptions o;
  o.resolution_m = 0.5;  // five image pixels per cell
  const AerialMap map(ortho, ortho.footprint_box_enu(), o);
  EXPECT_EQ(cv::norm(before, ortho.image(), cv::NORM_INF), 0.0);
}

// Pixels without data (here the west of the scene, 0 and declared no-data, as a clipped mosaic's
// corner) are off the map: no edge along the step from them to the photo, distances at the clip,
// and no coverage. Without the declaration the same step is an edge the length of the image.
TEST(AerialMap, PixelsWithoutDataAreOffTheMapAndTheirBorderIsNoEdge) {
  testing::Scene scene;
  scene.width_m = 60;
  scene.height_m = 40;
  scene.boxes = {{{12.5, 20.0}, {25.0, 60.0}, 0.0, 0.0, 0, 20},  // the part without data
                 {{45.0, 20.0}, {6.0, 6.0}, 0.0, 2.0, 200, 50}};
  const std::string dir = FreshDir("s");
  const std::string png = testing::WriteAerialImage(scene, dir);
  const std::string tif = dir + "/masked.tif";
  ASSERT_TRUE(geo::testing::GdalTranslate(png, tif, {"-of", "GTiff", "-a_nodata", "0"}));
  const geo::Orthophoto masked = testing::LoadScene(tif);
  const geo::Orthophoto plain = testing::LoadScene(png);
  ASSERT_FALSE(masked.valid_mask().empty());
  EXPECT_NEAR(masked.valid_share(), 35.0 / 60.0, 0.01);
  ASSERT_TRUE(plain.valid_mask().empty());

  AerialMapOptions o;
  o.resolution_m = 0.25;
  // Edges within 1 m of the border x = 25 m, and everywhere.
  const auto count_edges = [&](const AerialMap& map, int& near_border) {
    int all = 0;
    near_border = 0;
    for (int r = 0; r < map.rows(); ++r) {
      for (int c = 0; c < map.cols(); ++c) {
        if (map.edges().at<std::uint8_t>(r, c) == 0) continue;
        ++all;
        const Eigen::Vector2d enu = map.ToEnu({c, r});
        const Eigen::Vector2d on_border = testing::GridToEnu(scene, masked, {25.0, 20.0});
        near_border += std::abs(enu.x() - on_border.x()) < 1.0;
      }
    }
    return all;
  };
  const AerialMap with_mask(masked, masked.footprint_box_enu(), o);
  const AerialMap without(plain, plain.footprint_box_enu(), o);
  int near_masked = 0;
  int near_plain = 0;
  const int all_masked = count_edges(with_mask, near_masked);
  count_edges(without, near_plain);
  EXPECT_EQ(near_masked, 0);
  EXPECT_GT(near_plain, 0.8 * 40.0 / o.resolution_m);  // the step, along the image's height
  EXPECT_GT(all_masked, 4 * 6 / 0.25 * 0.8);           // the square's outline is still found

  const Eigen::Vector2d west = testing::GridToEnu(scene, masked, {10.0, 20.0});
  const Eigen::Vector2d east = testing::GridToEnu(scene, masked, {35.0, 20.0});
  EXPECT_FALSE(with_mask.Covers(west));
  EXPECT_TRUE(with_mask.Covers(east));
  EXPECT_TRUE(without.Covers(west));
  const Eigen::Vector2d g = with_mask.ToGrid(west);
  EXPECT_FLOAT_EQ(with_mask.distance().at<float>(static_cast<int>(std::lround(g.y())),
                                                 static_cast<int>(std::lround(g.x()))),
                  o.max_distance_m);
}

TEST(AerialMap, AnAreaOffTheImageIsAnInputErrorNamingIt) {
  testing::Scene scene;
  scene.width_m = 50;
  scene.height_m = 40;
  const std::string path = testing::WriteAerialImage(scene, FreshDir("s"));
  const geo::Orthophoto ortho = testing::LoadScene(path);
  geo::testing::ExpectInputError(
      [&] {
        AerialMap(ortho, Eigen::AlignedBox2d(Eigen::Vector2d(500, 500), Eigen::Vector2d(600, 600)));
      },
      path, "coverage", {"does not overlap"});
  AerialMapOptions bad;
  bad.resolution_m = 0.0;
  geo::testing::ExpectInputError(
      [&] {
        AerialMap(ortho, Eigen::AlignedBox2d(Eigen::Vector2d(-5, -5), Eigen::Vector2d(5, 5)), bad);
      },
      path, "resolution_m");
}

// The resampling, on the real photo: the map's grey at a cell is the image's at that cell's
// ENU point (bilinear), through a CRS rotated by 1.8 degrees against ENU.
TEST(AerialMap, OnAutzenEachCellHoldsTheImagesGreyAtItsEnuPoint) {
  const std::string jpg = kData + "/autzen/autzen.jpg";
  SKERRY_SKIP_WITHOUT(jpg);
  const geo::Orthophoto rough(jpg, LocalFrame({44.05, -123.07, 100.0}));
  const Eigen::Vector3d llh = rough.frame().ToGeodetic(
      rough.PixelToEnu(0.5 * (rough.width() - 1), 0.5 * (rough.height() - 1), 100.0));
  const geo::Orthophoto ortho(jpg, LocalFrame({llh.x(), llh.y(), 100.0}));
  AerialMapOptions o;
  o.resolution_m = 0.25;  // finer than the image (0.30 m): no anti-aliasing blur
  const AerialMap map(
      ortho, Eigen::AlignedBox2d(Eigen::Vector2d(-200, -150), Eigen::Vector2d(200, 150)), o);
  EXPECT_LT(map.lattice_error_px(), 1e-3);
  cv::Mat grey;
  cv::cvtColor(ortho.image(), grey, cv::COLOR_BGR2GRAY);
  std::mt19937 rng(3);
  std::uniform_int_distribution<int> col(2, map.cols() - 3), row(2, map.rows() - 3);
  int close = 0;
  const int n = 2000;
  for (int k = 0; k < n; ++k) {
    const int c = col(rng), r = row(rng);
    const Eigen::Vector2d xy = map.ToEnu({c, r});
    const Eigen::Vector2d uv = ortho.EnuToPixel(Eigen::Vector3d(xy.x(), xy.y(), 0.0));
    cv::Mat patch;
    cv::getRectSubPix(grey, cv::Size(1, 1),
                      cv::Point2f(static_cast<float>(uv.x()), static_cast<float>(uv.y())), patch);
    close += std::abs(static_cast<int>(patch.at<std::uint8_t>(0, 0)) -
                      static_cast<int>(map.grey().at<std::uint8_t>(r, c))) <= 2;
  }
  EXPECT_GE(close, 0.99 * n);
}

// A cell's grey is the image's at its ENU point whatever the map's extent: a map over a small box
// is, cell for cell, the map over a larger one where they overlap, also along the small box's
// border, where the image is read only up to the small map's window (the window's margin keeps
// the anti-aliasing blur the whole image's). The boxes share their lattice of CRS lookups.
TEST(AerialMap, ACellsGreyDoesNotDependOnTheMapsExtent) {
  const std::string jpg = kData + "/autzen/autzen.jpg";
  SKERRY_SKIP_WITHOUT(jpg);
  const geo::Orthophoto ortho(jpg, LocalFrame({44.0567, -123.0696, 100.0}));
  const Eigen::Vector2d centre =
      ortho.PixelToEnu(0.5 * ortho.width(), 0.5 * ortho.height()).head<2>().array().round();
  for (const double resolution : {0.25, 0.5, 1.0}) {  // finer than the image, and coarser (blur)
    SCOPED_TRACE(resolution);
    AerialMapOptions o;
    o.resolution_m = resolution;
    const double step = 16 * resolution;  // the lattice
    const Eigen::AlignedBox2d big(centre - Eigen::Vector2d(10, 8) * step,
                                  centre + Eigen::Vector2d(10, 8) * step);
    const Eigen::AlignedBox2d small(centre - Eigen::Vector2d(3, 2) * step,
                                    centre + Eigen::Vector2d(4, 3) * step);
    const AerialMap a(ortho, big, o);
    const AerialMap b(ortho, small, o);
    const Eigen::Vector2d offset = a.ToGrid(b.ToEnu({0.0, 0.0}));
    ASSERT_LT((offset - offset.array().round().matrix()).norm(), 1e-9);
    const cv::Rect in_a(static_cast<int>(std::lround(offset.x())),
                        static_cast<int>(std::lround(offset.y())), b.cols(), b.rows());
    ASSERT_EQ(in_a & cv::Rect(0, 0, a.cols(), a.rows()), in_a);
    EXPECT_EQ(cv::norm(a.grey()(in_a), b.grey(), cv::NORM_INF), 0.0);
  }
}

// A map reads only the orthophoto's pixels under its cells: made from an orthophoto whose pixels
// stay on disk (each window read from the file), it is the map made from the image in memory, cell
// for cell (grey, coverage, edges, distances), on the real photo through its rotated Lambert grid,
// at a grid finer than the image and at one coarser (anti-aliasing blur), and on a scene with a
// part that holds no data. The disk's limit then bounds the window, not the image.
TEST(AerialMap, AMapFromAnOrthophotoOnDiskIsTheMapFromMemory) {
  const std::string jpg = kData + "/autzen/autzen.jpg";
  SKERRY_SKIP_WITHOUT(jpg);
  const LocalFrame frame({44.0567, -123.0696, 100.0});
  geo::OrthophotoOptions disk_options;
  disk_options.on_disk = true;
  const auto expect_same = [](const AerialMap& a, const AerialMap& b) {
    ASSERT_EQ(a.cols(), b.cols());
    ASSERT_EQ(a.rows(), b.rows());
    EXPECT_EQ(cv::norm(a.grey(), b.grey(), cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(a.valid(), b.valid(), cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(a.edges(), b.edges(), cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(a.distance(), b.distance(), cv::NORM_INF), 0.0);
    EXPECT_GT(cv::countNonZero(a.edges()), 100);
  };
  {
    const geo::Orthophoto memory(jpg, frame);
    const Eigen::Vector2d centre =
        memory.PixelToEnu(0.5 * memory.width(), 0.5 * memory.height()).head<2>();
    const Eigen::AlignedBox2d box(centre - Eigen::Vector2d(150, 100),
                                  centre + Eigen::Vector2d(150, 100));
    // A window of the box's pixels (300 x 200 m at 0.30 m: about 1000 x 670, rotated) fits, the
    // whole photo does not.
    disk_options.max_pixels = 900000;
    ASSERT_GT(static_cast<double>(memory.width()) * memory.height(), disk_options.max_pixels);
    const geo::Orthophoto disk(jpg, frame, disk_options);
    for (const double resolution : {0.25, 0.6}) {
      SCOPED_TRACE(resolution);
      AerialMapOptions o;
      o.resolution_m = resolution;
      expect_same(AerialMap(memory, box, o), AerialMap(disk, box, o));
    }
  }
  testing::Scene scene;
  scene.width_m = 60;
  scene.height_m = 40;
  scene.boxes = {{{12.5, 20.0}, {25.0, 60.0}, 0.0, 0.0, 0, 20},
                 {{45.0, 20.0}, {6.0, 6.0}, 0.0, 2.0, 200, 50}};
  const std::string dir = FreshDir("s");
  const std::string tif = dir + "/masked.tif";
  ASSERT_TRUE(geo::testing::GdalTranslate(testing::WriteAerialImage(scene, dir), tif,
                                          {"-of", "GTiff", "-a_nodata", "0"}));
  const geo::Orthophoto memory = testing::LoadScene(tif);
  disk_options.crs = "EPSG:32632";  // as LoadScene's
  const geo::Orthophoto disk(tif, memory.frame(), disk_options);
  AerialMapOptions o;
  o.resolution_m = 0.25;
  expect_same(AerialMap(memory, memory.footprint_box_enu(), o),
              AerialMap(disk, disk.footprint_box_enu(), o));
}

// A photo far finer than the cells (a drone's mosaic) is read as block means, and the map is the
// one the photo gives at its own resolution: a crop of the real Autzen photo, and the same crop
// upsampled 4 times (each pixel a block of 4 x 4), mapped at 2.2 pixels of the crop per cell.
// The fine photo (8.8 of its pixels per cell) is read in blocks of 4, which are the crop's pixels,
// so its map is the crop's up to the rounding of their lookups: this fails when a block mean is
// placed at its block's corner instead of its centre (a shift of 1.5 fine pixels), when the blur
// is not rescaled to the blocks, or when blocks do not sit on the image's lattice of 4. With its
// pixels on disk and a limit below the window at full resolution, the fine photo's map is the same
// to the bit.
TEST(AerialMap, APhotoFarFinerThanTheCellsIsReadAsBlockMeans) {
  const std::string jpg = kData + "/autzen/autzen.jpg";
  SKERRY_SKIP_WITHOUT(jpg);
  const cv::Mat autzen = cv::imread(jpg, cv::IMREAD_COLOR);
  ASSERT_FALSE(autzen.empty());
  const std::string dir = FreshDir("fine");
  const auto write = [&](const std::string& name, const cv::Mat& image, double gsd) {
    const std::string path = dir + "/" + name + ".png";
    cv::imwrite(path, image);
    const double e0 = 500000.0, n0 = 5000000.0;  // UTM 32N, the top-left corner
    geo::testing::WriteText(dir + "/" + name + ".pgw", std::to_string(gsd) + "\n0\n0\n" +
                                                           std::to_string(-gsd) + "\n" +
                                                           std::to_string(e0 + 0.5 * gsd) + "\n" +
                                                           std::to_string(n0 - 0.5 * gsd) + "\n");
    return path;
  };
  const cv::Mat crop = autzen(cv::Rect(1400, 1900, 480, 400)).clone();
  cv::Mat upsampled;
  cv::resize(crop, upsampled, cv::Size(), 4.0, 4.0, cv::INTER_NEAREST);
  const geo::Orthophoto coarse = testing::LoadScene(write("coarse", crop, 0.3));
  geo::OrthophotoOptions crs;
  crs.crs = "EPSG:32632";  // as LoadScene's
  const geo::Orthophoto fine(write("fine", upsampled, 0.075), coarse.frame(), crs);
  AerialMapOptions o;
  o.resolution_m = 2.2 * coarse.ground_sample_distance_m();
  const Eigen::AlignedBox2d box(Eigen::Vector2d(-55, -45), Eigen::Vector2d(55, 45));
  const AerialMap a(coarse, box, o);
  const AerialMap b(fine, box, o);
  ASSERT_EQ(a.cols(), b.cols());
  ASSERT_EQ(a.rows(), b.rows());
  EXPECT_EQ(cv::norm(a.valid(), b.valid(), cv::NORM_INF), 0.0);
  cv::Mat diff;
  cv::absdiff(a.grey(), b.grey(), diff);
  const int cells = a.cols() * a.rows();
  EXPECT_LE(cv::countNonZero(diff > 1), cells / 1000);
  EXPECT_LE(cv::norm(diff, cv::NORM_INF), 8.0);
  const int edges = cv::countNonZero(a.edges());
  EXPECT_GT(edges, cells / 20);
  EXPECT_LE(cv::countNonZero(a.edges() != b.edges()), edges / 50);

  geo::OrthophotoOptions disk = crs;
  disk.on_disk = true;
  disk.max_pixels = upsampled.cols * upsampled.rows / 8;
  const geo::Orthophoto fine_disk(fine.path(), coarse.frame(), disk);
  const AerialMap c(fine_disk, box, o);
  EXPECT_EQ(cv::norm(b.grey(), c.grey(), cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(b.edges(), c.edges(), cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(b.distance(), c.distance(), cv::NORM_INF), 0.0);
}

}  // namespace
}  // namespace skerry::lidar_aerial
