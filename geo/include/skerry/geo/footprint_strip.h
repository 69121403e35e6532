#pragma once
/// \file
/// A height grid read in strips of rows for a blur by a DEM's footprint (SharpenTerrain and the
/// simulator's sim::AddTerrainRelief): a map of 30 million nodes would need four more copies of
/// itself for a blur of the whole (1 GB in doubles); in strips a blur needs one float per node
/// for the change.

#include <opencv2/core.hpp>

#include "skerry/geo/enu_height_grid.h"

namespace skerry::geo {

/// Rows blurred at a time.
constexpr int kFootprintStripRows = 256;

/// Half the side of a Gaussian kernel of `sigma_nodes`, in nodes: four sigma, at least 1 and
/// never wider than a `cols` x `rows` grid (a wider kernel adds nothing and its size would
/// overflow).
int FootprintHalfWidth(double sigma_nodes, int cols, int rows);

/// Rows [first_row, first_row + up.rows) of a grid as CV_32F images. Heights are relative to
/// the strip's first one that holds data, so float keeps a tenth of a millimetre.
struct FootprintStrip {
  int first_row = 0;
  double ref_m = 0.0;  ///< the height `up` is relative to
  bool has_data = false;
  cv::Mat up;     ///< height - ref_m where the node holds data, else 0
  cv::Mat land;   ///< 1 where the node holds data and is not water, else 0
  cv::Mat data;   ///< 1 where the node holds data, else 0
  cv::Mat water;  ///< CV_8U, 1 where the node is level around (EnuHeightGrid::LevelAround)
};

/// Rows [first_row, last_row) of `grid`; `earth_radius_m` for LevelAround's curvature. A strip
/// with no data has has_data false and no images.
FootprintStrip ReadFootprintStrip(const EnuHeightGrid& grid,
                                  int first_row,
                                  int last_row,
                                  double earth_radius_m);

}  // namespace skerry::geo
