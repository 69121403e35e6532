#include "skerry/geo/footprint_strip.h"

#include <algorithm>
#include <cmath>

namespace skerry::geo {

int FootprintHalfWidth(double sigma_nodes, int cols, int rows) {
  return static_cast<int>(
      std::clamp(std::ceil(4.0 * sigma_nodes), 1.0, 1.0 * std::max(cols, rows)));
}

FootprintStrip ReadFootprintStrip(const EnuHeightGrid& grid,
                                  int first_row,
                                  int last_row,
                                  double earth_radius_m) {
  FootprintStrip s;
  s.first_row = first_row;
  const int cols = grid.cols;
  for (size_t i = static_cast<size_t>(first_row) * cols; i < static_cast<size_t>(last_row) * cols;
       ++i) {
    if (std::isfinite(grid.up_m[i])) {
      s.ref_m = grid.up_m[i];
      s.has_data = true;
      break;
    }
  }
  if (!s.has_data) return s;
  const int n = last_row - first_row;
  s.up.create(n, cols, CV_32F);
  s.land.create(n, cols, CV_32F);
  s.data.create(n, cols, CV_32F);
  s.water.create(n, cols, CV_8U);
  for (int row = first_row; row < last_row; ++row) {
    for (int col = 0; col < cols; ++col) {
      const double v = grid.at(col, row);
      const bool ok = std::isfinite(v);
      const bool level = grid.LevelAround(col, row, earth_radius_m);
      s.up.at<float>(row - first_row, col) = ok ? static_cast<float>(v - s.ref_m) : 0.0f;
      s.land.at<float>(row - first_row, col) = ok && !level ? 1.0f : 0.0f;
      s.data.at<float>(row - first_row, col) = ok ? 1.0f : 0.0f;
      s.water.at<unsigned char>(row - first_row, col) = level;
    }
  }
  return s;
}

}  // namespace skerry::geo
