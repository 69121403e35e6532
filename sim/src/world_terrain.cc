#include "skerry/sim/world_terrain.h"

namespace skerry::sim {

geo::EnuHeightGrid WorldTerrain(const geo::Dem& dem, const Eigen::AlignedBox2d& box_w) {
  const double spacing = 0.5 * dem.cell_size_m().minCoeff();
  Eigen::AlignedBox2d box = box_w;
  box.min() += Eigen::Vector2d::Constant(0.5 * spacing);
  return dem.ResampleToEnu(box, spacing);
}

}  // namespace skerry::sim
