#pragma once
/// \file
/// The relief a DEM averaged away, given back to the simulator's world.
///
/// A raster's height is a mean over a footprint about a cell wide, so the terrain's crests stand
/// above the raster's (docs/skyline.md, *The map's crests*; measured on the real Engabreen lidar
/// DEM against its own block means by bench/skyline_crest_loss.cc). A world that is the raster's
/// surface shows the estimator a terrain exactly as low as its map. This gives the world relief
/// above its raster: with y the world resampled from the raster and h a Gaussian of
/// `footprint_cells` cells, three iterations of van Cittert's deconvolution
///   z_0 = y,   z_{n+1} = z_n + (y - h * z_n)                (van Cittert 1931; Jansson 1997,
///   eq. 3.12)
/// and the world y + gain (z_3 - y). With gain 1 and the default footprint (0.75 cells) the world's
/// crests stand above its raster as Engabreen's real terrain stands above its block means
/// (bench/skyline_crest_loss.cc: the mean height of the crests a horizon grazes within 0.3 m of
/// the real terrain's for a 30 m raster, 1.9 m below it for a 90 m one, where the raster itself
/// is 4.1 and 9.9 m low). Deliberately not what the estimator's map does
/// (geo::SharpenTerrain: one iteration with its own footprint): the world's relief is not the
/// estimator's belief about it. Water (level over 3 x 3 nodes) keeps its height and is kept out of
/// the footprint, and the change is tapered at shores (geo::ShoreTaper, as the map's sharpening
/// is); voids stay voids.

#include "skerry/geo/enu_height_grid.h"

namespace skerry::sim {

struct TerrainReliefSpec {
  double gain = 0.0;  ///< 0: the world is the raster's surface
  /// The footprint h's standard deviation, in the raster's cells.
  double footprint_cells = 0.75;
};

/// Gives `world` the relief in place. `cell_m`: the raster's cell (its finer axis). Throws
/// std::invalid_argument for a gain < 0 or not finite, or, with a gain > 0, a cell or a
/// footprint <= 0 or not finite.
void AddTerrainRelief(const TerrainReliefSpec& spec,
                      double cell_m,
                      double earth_radius_m,
                      geo::EnuHeightGrid* world);

}  // namespace skerry::sim
