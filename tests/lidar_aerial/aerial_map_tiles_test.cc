// AerialMapTiles on the real Autzen photo (its pixels read from the file by window): which tile a
// position takes and what that tile holds, the cache (a tile kept while a block holds it, made
// again once nobody does), a tile against one map of the whole area (the same grey to the last
// bit; edges from the tile's own thresholds), and positions off the photo.

#include "skerry/lidar_aerial/aerial_map_tiles.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "geo/geo_test_util.h"

namespace skerry::lidar_aerial {
namespace {

using geo::testing::kData;

const std::string kAutzenJpg = kData + "/autzen/autzen.jpg";

struct Autzen {
  std::shared_ptr<const geo::Orthophoto> ortho;
  Eigen::Vector2d corner;  ///< a corner of the tiles' lattice (64 m) near the photo's centre
};

Autzen Load() {
  geo::OrthophotoOptions o;
  o.on_disk = true;
  Autzen a;
  a.ortho = std::make_shared<const geo::Orthophoto>(kAutzenJpg,
                                                    LocalFrame({44.0567, -123.0696, 100.0}), o);
  const Eigen::Vector2d centre =
      a.ortho->PixelToEnu(0.5 * a.ortho->width(), 0.5 * a.ortho->height()).head<2>();
  a.corner = (centre / 64.0).array().floor() * 64.0;
  return a;
}

AerialMapTilesOptions Tiles64(int cache = 4) {
  AerialMapTilesOptions t;
  t.tile_m = 64.0;
  t.margin_m = 32.0;
  t.cache_tiles = cache;
  return t;
}

// A position takes the tile of its square: the square grown by the margin, which holds all a
// scan there reaches; positions in one square share one tile, the next square has its own.
TEST(AerialMapTiles, APositionTakesTheTileOfItsSquare) {
  SKERRY_SKIP_WITHOUT(kAutzenJpg);
  const Autzen a = Load();
  const AerialMapTiles tiles(a.ortho, a.ortho->footprint_box_enu(), AerialMapOptions{}, Tiles64());
  EXPECT_TRUE(tiles.tiled());
  const Eigen::Vector2d p = a.corner + Eigen::Vector2d(10, 20);
  const auto here = tiles.At(p);
  ASSERT_TRUE(here);
  EXPECT_EQ(tiles.At(a.corner + Eigen::Vector2d(63.9, 0.1)), here);
  const auto east = tiles.At(a.corner + Eigen::Vector2d(64.1, 20));
  ASSERT_TRUE(east);
  EXPECT_NE(east, here);
  EXPECT_EQ(tiles.made(), 2);
  const Eigen::AlignedBox2d box = tiles.TileBox(p);
  EXPECT_LT((box.min() - (a.corner - Eigen::Vector2d(32, 32))).norm(), 1e-9);
  EXPECT_LT((box.max() - (a.corner + Eigen::Vector2d(96, 96))).norm(), 1e-9);
  // The tile's map spans its box: 128 m at 0.25 m.
  EXPECT_EQ(here->map->cols(), 513);
  EXPECT_EQ(here->map->rows(), 513);
  for (const Eigen::Vector2d& reach :
       {Eigen::Vector2d(-31.9, -31.9), Eigen::Vector2d(95.9, 95.9), Eigen::Vector2d(95.9, -31.9)}) {
    EXPECT_TRUE(here->map->Covers(a.corner + reach)) << reach.transpose();
  }
  EXPECT_FALSE(here->map->Covers(a.corner + Eigen::Vector2d(97, 10)));
  // The field shares the tile.
  const std::shared_ptr<const EdgeDistanceField> field = FieldOf(here);
  EXPECT_EQ(field.get(), &here->field);
  EXPECT_EQ(field.use_count(), here.use_count());
}

// The cache keeps the last cache_tiles tiles used; a tile a block holds (through its field) is
// found again rather than made twice, and a tile nobody holds any more is made again.
TEST(AerialMapTiles, ATileABlockHoldsIsFoundAgainAndOneNobodyHoldsIsMadeAgain) {
  SKERRY_SKIP_WITHOUT(kAutzenJpg);
  const Autzen a = Load();
  const AerialMapTiles tiles(a.ortho, a.ortho->footprint_box_enu(), AerialMapOptions{},
                             Tiles64(/*cache=*/1));
  const Eigen::Vector2d pa = a.corner + Eigen::Vector2d(10, 10);
  const Eigen::Vector2d pb = pa + Eigen::Vector2d(64, 0);
  const Eigen::Vector2d pc = pa + Eigen::Vector2d(0, 64);
  std::shared_ptr<const EdgeDistanceField> held = FieldOf(tiles.At(pa));  // a block's cost
  EXPECT_EQ(tiles.made(), 1);
  tiles.At(pb);  // the cache now holds b only
  EXPECT_EQ(tiles.made(), 2);
  EXPECT_EQ(&tiles.At(pa)->field, held.get());  // a is held: found, not made
  EXPECT_EQ(tiles.made(), 2);
  held.reset();
  tiles.At(pc);  // the cache holds c only; a and b are held by nobody
  EXPECT_EQ(tiles.made(), 3);
  tiles.At(pb);
  EXPECT_EQ(tiles.made(), 4);
  tiles.At(pb);
  EXPECT_EQ(tiles.made(), 4);
  EXPECT_GT(tiles.make_s(), 0.0);
}

// A tile is the map of its box: where it overlaps one map of a larger area (on the same lattice of
// cells), the grey is the same to the last bit. Its edges come from its own quantile thresholds:
// over its square, the distances mostly agree with the larger map's, and differ where a faint
// texture edge is above one threshold and below the other.
TEST(AerialMapTiles, ATileIsTheMapOfItsBox) {
  SKERRY_SKIP_WITHOUT(kAutzenJpg);
  const Autzen a = Load();
  const AerialMapOptions mo;  // 0.25 m
  const AerialMapTiles tiles(a.ortho, a.ortho->footprint_box_enu(), mo, Tiles64());
  const auto tile = tiles.At(a.corner + Eigen::Vector2d(32, 32));
  ASSERT_TRUE(tile);
  const AerialMap whole(*a.ortho,
                        Eigen::AlignedBox2d(a.corner - Eigen::Vector2d(128, 128),
                                            a.corner + Eigen::Vector2d(192, 192)),
                        mo);
  const Eigen::Vector2d offset = whole.ToGrid(tile->map->ToEnu({0.0, 0.0}));
  ASSERT_LT((offset - offset.array().round().matrix()).norm(), 1e-9);
  const cv::Rect in_whole(static_cast<int>(std::lround(offset.x())),
                          static_cast<int>(std::lround(offset.y())), tile->map->cols(),
                          tile->map->rows());
  ASSERT_EQ(in_whole & cv::Rect(0, 0, whole.cols(), whole.rows()), in_whole);
  EXPECT_EQ(cv::norm(whole.grey()(in_whole), tile->map->grey(), cv::NORM_INF), 0.0);
  // Over the tile's square (its middle 64 m), the share of cells whose distance agrees to 0.1 m.
  const cv::Rect square(128, 128, 257, 257);
  const cv::Mat d_tile = tile->map->distance()(square);
  const cv::Mat d_whole = whole.distance()(in_whole)(square);
  cv::Mat diff;
  cv::absdiff(d_tile, d_whole, diff);
  const double agree = cv::countNonZero(diff <= 0.1) / static_cast<double>(diff.total());
  EXPECT_GT(agree, 0.7);  // 76 % here: a 128 m tile against a 320 m map on a textured land scene
  std::printf("distances within 0.1 m of the larger map's over the tile's square: %.1f %%\n",
              100.0 * agree);
}

// Off the photo, out of the bounds or at a non-finite position there is no tile (the scan is off
// the map), and nothing is made.
TEST(AerialMapTiles, OffThePhotoOrOutOfBoundsThereIsNoTile) {
  SKERRY_SKIP_WITHOUT(kAutzenJpg);
  const Autzen a = Load();
  const Eigen::AlignedBox2d bounds(a.corner - Eigen::Vector2d(200, 200),
                                   a.corner + Eigen::Vector2d(200, 200));
  const AerialMapTiles tiles(a.ortho, bounds, AerialMapOptions{}, Tiles64());
  EXPECT_FALSE(tiles.At(a.corner + Eigen::Vector2d(1e5, 0)));
  EXPECT_FALSE(tiles.At(a.corner + Eigen::Vector2d(0, 400)));  // its box misses the bounds
  EXPECT_FALSE(tiles.At({std::numeric_limits<double>::quiet_NaN(), 0.0}));
  EXPECT_FALSE(tiles.At({std::numeric_limits<double>::infinity(), 0.0}));
  EXPECT_EQ(tiles.made(), 0);
  // At the bounds' edge, a tile clipped to them.
  const auto edge = tiles.At(a.corner + Eigen::Vector2d(190, 10));
  ASSERT_TRUE(edge);
  EXPECT_LE(edge->map->ToEnu({edge->map->cols() - 1.0, 0.0}).x(), bounds.max().x() + 1e-9);
  AerialMapTilesOptions bad = Tiles64();
  bad.tile_m = 0.0;
  EXPECT_THROW(AerialMapTiles(a.ortho, bounds, AerialMapOptions{}, bad), std::invalid_argument);
  bad = Tiles64(/*cache=*/0);
  EXPECT_THROW(AerialMapTiles(a.ortho, bounds, AerialMapOptions{}, bad), std::invalid_argument);
}

}  // namespace
}  // namespace skerry::lidar_aerial
