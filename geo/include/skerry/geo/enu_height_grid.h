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

  /// Whether the terrain around node (col, row) is level: its 3 x 3 nodes (clipped at the grid's
  /// border) within `spread_m` of each other once the Earth's curvature is taken out (z_w falls
  /// as |p|^2 / 2R away from the origin). A DEM's sea or lake is flat to the millimetre; land
  /// falls by metres to the next node, even along a crest (a maximum across its ridge, so a slope
  /// at the node alone would not tell it from water). False when (col, row) is off the grid or
  /// any of those nodes is void.
  bool LevelAround(int col, int row, double earth_radius_m, double spread_m = 0.1) const;
};

/// Means of `block` x `block` nodes of `grid` (a block holding a NaN is NaN), each at its
/// block's centre: the raster a sensor whose footprint is the block would give of the terrain in
/// `grid` (bench/skyline_crest_loss.cc). std::invalid_argument for a block < 1.
EnuHeightGrid BlockMeans(const EnuHeightGrid& grid, int block);

/// `grid`'s bilinear surface (UpAt) on `cols` x `rows` nodes every `spacing_m` from `origin_w`;
/// NaN off the grid.
EnuHeightGrid Resampled(const EnuHeightGrid& grid,
                        const Eigen::Vector2d& origin_w,
                        double spacing_m,
                        int cols,
                        int rows);

}  // namespace skerry::geo
