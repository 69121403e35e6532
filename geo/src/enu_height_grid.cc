#include "skerry/geo/enu_height_grid.h"

#include <algorithm>
#include <cmath>

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

}  // namespace skerry::geo
