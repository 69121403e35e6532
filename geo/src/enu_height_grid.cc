#include "skerry/geo/enu_height_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace skerry::geo {

std::optional<double> EnuHeightGrid::UpAt(double x_m, double y_m) const {
  if (cols < 2 || rows < 2 || !(spacing_m > 0.0)) return std::nullopt;
  const double c = (x_m - origin_w.x()) / spacing_m;
  const double r = (y_m - origin_w.y()) / spacing_m;
  if (!(c >= 0.0 && c <= cols - 1 && r >= 0.0 && r <= rows - 1)) return std::nullopt;
  const int c0 = std::min(static_cast<int>(c), cols - 2);
  const int r0 = std::min(static_cast<int>(r), rows - 2);
  const double tc = c - c0;
  const double tr = r - r0;
  const double v = (1 - tr) * ((1 - tc) * at(c0, r0) + tc * at(c0 + 1, r0)) +
                   tr * ((1 - tc) * at(c0, r0 + 1) + tc * at(c0 + 1, r0 + 1));
  if (std::isnan(v)) return std::nullopt;
  return v;
}

bool EnuHeightGrid::LevelAround(int col, int row, double earth_radius_m, double spread_m) const {
  if (col < 0 || row < 0 || col >= cols || row >= rows) return false;
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (int r = std::max(0, row - 1); r <= std::min(rows - 1, row + 1); ++r) {
    for (int c = std::max(0, col - 1); c <= std::min(cols - 1, col + 1); ++c) {
      const double z = at(c, r);
      if (!std::isfinite(z)) return false;
      const double level = z + NodePosition(c, r).squaredNorm() / (2.0 * earth_radius_m);
      lo = std::min(lo, level);
      hi = std::max(hi, level);
    }
  }
  return hi - lo < spread_m;
}

EnuHeightGrid BlockMeans(const EnuHeightGrid& grid, int block) {
  if (block < 1) throw std::invalid_argument("BlockMeans: block must be >= 1");
  EnuHeightGrid out;
  out.spacing_m = grid.spacing_m * block;
  out.origin_w = grid.origin_w + Eigen::Vector2d::Constant(0.5 * (block - 1) * grid.spacing_m);
  out.cols = grid.cols / block;
  out.rows = grid.rows / block;
  out.up_m.assign(static_cast<size_t>(out.cols) * out.rows, 0.0);
  for (int row = 0; row < out.rows; ++row) {
    for (int col = 0; col < out.cols; ++col) {
      double sum = 0.0;
      for (int r = 0; r < block; ++r) {
        for (int c = 0; c < block; ++c) sum += grid.at(col * block + c, row * block + r);
      }
      out.up_m[static_cast<size_t>(row) * out.cols + col] = sum / (block * block);
    }
  }
  return out;
}

EnuHeightGrid Resampled(const EnuHeightGrid& grid,
                        const Eigen::Vector2d& origin_w,
                        double spacing_m,
                        int cols,
                        int rows) {
  EnuHeightGrid out;
  out.origin_w = origin_w;
  out.spacing_m = spacing_m;
  out.cols = std::max(0, cols);
  out.rows = std::max(0, rows);
  out.up_m.resize(static_cast<size_t>(out.cols) * out.rows);
  for (int row = 0; row < out.rows; ++row) {
    for (int col = 0; col < out.cols; ++col) {
      const Eigen::Vector2d p = out.NodePosition(col, row);
      out.up_m[static_cast<size_t>(row) * out.cols + col] =
          grid.UpAt(p.x(), p.y()).value_or(std::numeric_limits<double>::quiet_NaN());
    }
  }
  return out;
}

}  // namespace skerry::geo
