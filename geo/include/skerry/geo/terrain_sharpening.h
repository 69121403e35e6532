#pragma once
/// \file
/// A DEM's relief, restored to first order where its footprint averaged it away.
///
/// A raster's height is not the terrain at the cell's centre but a mean over a footprint about a
/// cell wide (SRTM3: the 1" radar heights, themselves a ~30 m footprint, averaged 3 x 3; a lidar
/// DEM's cells are block means too). Averaging never raises a maximum: every crest is lower in the
/// raster than on the ground, and a skyline traced over it sinks (docs/skyline.md, *The map's
/// crests*). With the raster y = h * z (z the terrain, h the footprint), the first iteration of
/// van Cittert's deconvolution (van Cittert 1931, Z. Physik 69; Jansson 1997, "Deconvolution of
/// images and spectra", ch. 3, eq. 3.12 with z0 = y) gives
///   z1 = y + g (y - h * y)
/// with h a Gaussian of standard deviation `footprint_sigma_m` and g the relaxation (1: one full
/// iteration). It adds the raster's own high-pass back: crests rise, valleys sink, the mean over an
/// area is kept. Water (a node whose 3 x 3 neighbourhood is level, EnuHeightGrid::LevelAround) is
/// left as it is and kept out of the blur: a DEM's lakes and sea are set flat by hand, and with
/// them in the mean every shore would rise into a wall (a lake's skyline is mostly its shores).
/// Voids stay voids, and the blur sees only the land nodes that hold data (normalised
/// convolution). A footprint reaching over water sees only part of the land around a node, and
/// on a slope its mean leans uphill (a straight shore's bank would sink by the slope times 0.8
/// footprints): the change is tapered by ShoreTaper of the share of the footprint's weight on
/// data that is land, 0 up to 1.3 footprints from a straight shore, full from 2.3 on. A void or
/// the map's edge does not taper (a DEM's edge is no shore, and a small DEM's ridges run to it).

#include "skerry/geo/enu_height_grid.h"

namespace skerry::geo {

struct TerrainSharpening {
  double gain = 0.0;               ///< g (0: nothing happens)
  double footprint_sigma_m = 0.0;  ///< the footprint's standard deviation, m
};

/// max(0, min(1, (share - 0.9) / 0.1)): the share of the footprint's weight on land (1 inland,
/// 1/2 at a straight shore) to the part of the change kept. On a bank of 1 in 5 sharpened with
/// gain 2 the lean left is below 0.4 m.
double ShoreTaper(double land_share);

/// Sharpens `grid` in place. std::invalid_argument for a gain < 0, a footprint <= 0 with a gain
/// > 0, or either not finite. `earth_radius_m`: for the curvature taken out of the water test.
void SharpenTerrain(const TerrainSharpening& sharpening,
                    double earth_radius_m,
                    EnuHeightGrid* grid);

}  // namespace skerry::geo
