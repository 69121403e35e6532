#pragma once
/// \file
/// A DEM resampled onto a regular grid of the local ENU frame `w`: what the frontends look up
/// (many times per frame) instead of the raster and its CRS.

#include <Eigen/Core>
#include <optional>
#include <vector>

namespace skerry::geo {

/// The ENU *up* coordinate z_w (m) of the terrain surface at the nodes of a regular (x, y) grid
/// of the frame `w`. Node (col, row) sits at origin_w + (col, row) * spacing_m: columns go east,
/// rows go north (row 0 is the southern edge). Values are row-major, NaN where the DEM has no
/// data. z is the ENU coordinate, not a height: with Earth curvature a flat sea 30 km from the
/// origin lies about d^2 / 2R = 70 m below the origin's tangent plane.
struct EnuHeightGrid {
  Eigen::Vector2d origin_w = Eigen::Vector2d::Zero();  ///< (x, y) of node (0, 0), m
  double spacing_m = 0.0;
  int cols = 0;
  int rows = 0;
  std::vector<double> up_m;  ///< rows * cols values, index row * cols + col

  double at(int col, int row) const { return up_m[static_cast<size_t>(row) * cols + col]; }
  Eigen::Vector2d NodePosition(int col, int row) const {
    return origin_w + spacing_m * Eigen::Vector2d(col, row);
  }

  /// Bilinear z_w between the four nodes around (x, y); nullopt outside the grid or if any of
  /// the four is NaN.
  std::optional<double> UpAt(double x_m, double y_m) const;
};

}  // namespace skerry::geo
