// The DEM's own error in the simulator's world (dem_error.h): its size and correlation length
// measured on a large grid against the spec, water left level, the same field for the same seed.

#include "skerry/sim/dem_error.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace skerry::sim {
namespace {

constexpr double kEarthRadiusM = 6371000.0;

// A grid on the round Earth centred on the origin: level water (the sphere's surface at height
// 0) where x < x_coast, a hill slope rising to the east beyond it.
geo::EnuHeightGrid Terrain(int n, double spacing_m, double x_coast_m) {
  geo::EnuHeightGrid g;
  g.spacing_m = spacing_m;
  g.cols = n;
  g.rows = n;
  g.origin_w = Eigen::Vector2d::Constant(-0.5 * (n - 1) * spacing_m);
  g.up_m.resize(static_cast<size_t>(n) * n);
  for (int row = 0; row < n; ++row) {
    for (int col = 0; col < n; ++col) {
      const Eigen::Vector2d p = g.NodePosition(col, row);
      const double height = p.x() < x_coast_m ? 0.0 : 5.0 + 0.05 * (p.x() - x_coast_m);
      g.up_m[static_cast<size_t>(row) * n + col] = height - p.squaredNorm() / (2 * kEarthRadiusM);
    }
  }
  return g;
}

// Correlation of the error between nodes `lag` columns apart, over the land nodes.
double Correlation(const geo::EnuHeightGrid& before,
                   const geo::EnuHeightGrid& after,
                   int lag,
                   int first_land_col) {
  double sxy = 0, sxx = 0, syy = 0;
  for (int row = 0; row < before.rows; ++row) {
    for (int col = first_land_col; col + lag < before.cols; ++col) {
      const double x = after.at(col, row) - before.at(col, row);
      const double y = after.at(col + lag, row) - before.at(col + lag, row);
      sxy += x * y;
      sxx += x * x;
      syy += y * y;
    }
  }
  return sxy / std::sqrt(sxx * syy);
}

TEST(DemError, HasItsSigmaAndCorrelationLengthOnLandAndLeavesWaterLevel) {
  // 60 km square at 100 m, the coast 10 km west of the middle; errors of 4 m over 1 km.
  const geo::EnuHeightGrid before = Terrain(600, 100.0, -10000.0);
  geo::EnuHeightGrid after = before;
  AddDemError({4.0, 1000.0}, 7, kEarthRadiusM, &after);
  int water = 0, land = 0, coast_col = -1;
  double sum2 = 0;
  for (int row = 0; row < before.rows; ++row) {
    for (int col = 0; col < before.cols; ++col) {
      const double d = after.at(col, row) - before.at(col, row);
      if (before.NodePosition(col, row).x() < -10000.0 - 150.0) {
        EXPECT_EQ(d, 0.0) << "water at " << col << ", " << row;
        ++water;
      } else if (before.NodePosition(col, row).x() > -10000.0 + 150.0) {
        if (coast_col < 0) coast_col = col;
        sum2 += d * d;
        ++land;
      }
    }
  }
  ASSERT_GT(water, 10000);
  ASSERT_GT(land, 100000);
  // The field is scaled to sigma over the whole grid; on land, 70 % of it, within sampling.
  EXPECT_NEAR(std::sqrt(sum2 / land), 4.0, 0.4);
  // Gaussian covariance: exp(-(d / L)^2) at 500 m (0.78), 1 km (0.37), 2 km (0.02).
  EXPECT_NEAR(Correlation(before, after, 5, coast_col), std::exp(-0.25), 0.06);
  EXPECT_NEAR(Correlation(before, after, 10, coast_col), std::exp(-1.0), 0.08);
  EXPECT_NEAR(Correlation(before, after, 20, coast_col), std::exp(-4.0), 0.08);
}

TEST(DemError, IsTheSameForTheSameSeedAndNothingAtSigmaZero) {
  const geo::EnuHeightGrid before = Terrain(80, 90.0, 0.0);
  geo::EnuHeightGrid a = before, b = before, c = before, none = before;
  AddDemError({4.0, 600.0}, 1, kEarthRadiusM, &a);
  AddDemError({4.0, 600.0}, 1, kEarthRadiusM, &b);
  AddDemError({4.0, 600.0}, 2, kEarthRadiusM, &c);
  AddDemError({0.0, 600.0}, 1, kEarthRadiusM, &none);
  EXPECT_EQ(a.up_m, b.up_m);
  EXPECT_NE(a.up_m, c.up_m);
  EXPECT_NE(a.up_m, before.up_m);
  EXPECT_EQ(none.up_m, before.up_m);
}

TEST(DemError, NoDataStaysNoDataAndBadSpecsThrow) {
  geo::EnuHeightGrid g = Terrain(40, 90.0, -2000.0);
  g.up_m[5 * 40 + 30] = std::nan("");
  AddDemError({4.0, 600.0}, 3, kEarthRadiusM, &g);
  EXPECT_TRUE(std::isnan(g.at(30, 5)));
  EXPECT_THROW(AddDemError({-1.0, 600.0}, 3, kEarthRadiusM, &g), std::invalid_argument);
  EXPECT_THROW(AddDemError({4.0, 0.0}, 3, kEarthRadiusM, &g), std::invalid_argument);
  EXPECT_THROW(AddDemError({std::nan(""), 600.0}, 3, kEarthRadiusM, &g), std::invalid_argument);
}

}  // namespace
}  // namespace skerry::sim
