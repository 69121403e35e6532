#pragma once
/// \file
/// The error of a real DEM, for the simulator: the terrain the cameras see is the map the
/// estimator is given plus a height error that is fixed on the ground, so that the skyline a
/// frame shows differs from the map's by what SRTM's does in the world and not only by the
/// resampling of one grid onto another.
///
/// SRTM's heights are wrong by a field correlated over hundreds of metres to kilometres (Rodriguez
/// et al. 2006, "A global assessment of the SRTM performance", PE&RS 72(3): absolute height error
/// 90 % below 6-9 m by continent, with long-wavelength components), flat over water, where the
/// mission set lakes and the sea to one level. Modelled as a Gaussian random field with a Gaussian
/// covariance sigma^2 exp(-d^2 / length^2) (correlation 1/e at `length_m`): white noise on the grid
/// blurred by a Gaussian kernel of standard deviation length / 2, scaled to `sigma_m` over the
/// grid. Deliberately not the estimator's model (crest_correlation.h assumes an exponential
/// covariance): the simulator's world is not what the estimator believes.
///
/// Water is left level: a node whose 3 x 3 neighbourhood is level (geo::EnuHeightGrid::LevelAround:
/// spread below 0.1 m once the Earth's curvature is taken out) keeps its height.

#include <cstdint>

#include "skerry/geo/enu_height_grid.h"

namespace skerry::sim {

struct DemErrorSpec {
  double sigma_m = 0.0;      ///< standard deviation of the height error (0: none)
  double length_m = 1000.0;  ///< distance at which its correlation falls to 1/e
};

/// Adds the error to the land nodes of `grid` in place, the same for the same seed, grid and
/// spec. `earth_radius_m`: for the curvature taken out of the water test. std::invalid_argument
/// for sigma < 0 or a length <= 0; nothing happens for sigma 0.
void AddDemError(const DemErrorSpec& spec,
                 std::uint64_t seed,
                 double earth_radius_m,
                 geo::EnuHeightGrid* grid);

}  // namespace skerry::sim
