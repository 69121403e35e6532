// Geoid: skerry's bilinear EGM96 lookup against PROJ's reading of the same grid, worldwide and
// across the antimeridian.

#include "skerry/geo/geoid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "geo/geo_test_util.h"
#include "skerry/core/input_error.h"

namespace skerry::geo {
namespace {

TEST(Geoid, AgreesWithProjWorldwideAndWrapsAroundTheAntimeridian) {
  const Geoid geoid;  // /usr/share/proj/egm96_15.gtx
  double worst = 0.0;
  for (double lat = -85.0; lat <= 85.0; lat += 8.5) {
    for (double lon :
         {-180.0, -179.9, -123.3, -60.1, -0.07, 0.0, 13.7, 77.77, 150.3, 179.8, 179.9, 180.0}) {
      const std::optional<double> n = geoid.Undulation(lat, lon);
      const std::optional<double> n_proj = testing::ProjUndulation(lat, lon);
      ASSERT_TRUE(n && n_proj) << lat << " " << lon;
      worst = std::max(worst, std::abs(*n - *n_proj));
    }
  }
  RecordProperty("max_diff_vs_proj_m", ::testing::PrintToString(worst));
  EXPECT_LT(worst, 1e-5);  // both bilinear on the same float grid: measured < 1e-6 m
  EXPECT_NEAR(*geoid.Undulation(10.0, 180.0), *geoid.Undulation(10.0, -180.0), 1e-9);
  EXPECT_NEAR(*geoid.Undulation(10.0, 540.0), *geoid.Undulation(10.0, 180.0), 1e-9);
}

TEST(Geoid, AMissingGridIsAnInputError) {
  testing::ExpectInputError([] { Geoid("/nonexistent/egm96_15.gtx"); }, "/nonexistent/egm96_15.gtx",
                            "geoid_path", {"proj-data"});
}

// A grid declaring 10^10 nodes is refused before anything is allocated (40 GB as float32).
TEST(Geoid, AGridDeclaringMoreNodesThanAnyGeoidIsAnInputError) {
  const std::string huge = testing::MakeSparseGeoTiff(testing::FreshDir("size") + "/huge.tif",
                                                      100000, 100000, 1, GDT_Float32);
  testing::ExpectInputError([&] { Geoid{huge}; }, huge, "geoid_path",
                            {"100000 x 100000 = 10000000000 cells", "37.3 GiB"});
}

}  // namespace
}  // namespace skerry::geo
