#pragma once
/// \file
/// The aerial photograph of the simulated harbour (harbour_world.h), written as an orthophoto the
/// geodata layer reads (geo/orthophoto.h): an 8-bit grey PNG, a world file (.pgw) and a CRS
/// sidecar (.prj), north up on the grid of the UTM zone of the scenario's origin (WGS84).
///
/// Model. A pinhole camera camera_height_m above the water, over `nadir_w`, looks straight down.
/// The photograph is rectified to the terrain (the IsTerrain boxes: quays and the land behind
/// them, piers, breakwaters, paint; the water elsewhere), as an orthophoto made with a terrain
/// model and not a surface model is: pixel (u, v) is the grid point g of the UTM grid, and it
/// shows what the camera sees along the ray from its centre C to g at the terrain's height.
/// Terrain lands where it is; what stands on it (buildings, boats, poles, cranes) leans away from
/// the nadir: a point h above the terrain whose image lies r from the nadir is displaced outward
/// by h r / H (relief displacement; Wolf, Dewitt and Wilkinson, Elements of Photogrammetry, 4th
/// ed., eq. 6-11), H the camera's height above that terrain, and its walls facing away from the
/// nadir show.
///
/// Each visible point is lit by the sun (Lambert, plus an ambient share of 0.35) unless a ray
/// towards the sun meets a box (a cast shadow); its grey is 255 x albedo x texture x light,
/// normalised so that a lit horizontal top shows its albedo. The texture is value noise on three
/// scales (0.4, 3, 15 m) in the surface's own coordinates, different for each box; the water is
/// dark (albedo 0.09) with ripples. Pixel noise of noise_grey grey levels is added. One ray per
/// pixel (no anti-aliasing). The world file's georeferencing is exact, up to the deliberate
/// offset image_offset_east_m / north_m (the image shows every object that far from where it is).
///
/// Not modelled: lens distortion, vignetting, colour, specular glints, atmospheric haze, the
/// Earth's curvature (the harbour is a plane tangent at the origin: 2.5 mm at 180 m).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <opencv2/core.hpp>
#include <string>

#include "skerry/core/geodesy.h"
#include "skerry/io/dataset.h"
#include "skerry/sim/harbour_world.h"
#include "skerry/sim/scenario.h"

namespace skerry::sim {

struct AerialPhoto {
  cv::Mat grey;  ///< CV_8UC1, rows towards UTM grid south, columns towards grid east
  double resolution_m = 0.0;
  int utm_zone = 0;
  bool north = true;  ///< northern hemisphere
  /// UTM easting and northing of the centre of pixel (0, 0) (the world file's last two lines).
  double top_left_east_m = 0.0;
  double top_left_north_m = 0.0;
  /// (east, north) in w of pixel (u, v) (centre of pixel (0, 0) at (0, 0)) at the water's
  /// height: pixel_to_enu * (u, v, 1), an affine fit to the exact UTM -> WGS84 -> ENU conversion
  /// (its error, below a millimetre over a harbour, is checked).
  Eigen::Matrix<double, 2, 3> pixel_to_enu = Eigen::Matrix<double, 2, 3>::Zero();
  Eigen::Vector3d camera_w = Eigen::Vector3d::Zero();  ///< the camera's centre in w

  /// Pixel (u, v) of an east/north point of w (the inverse of pixel_to_enu).
  Eigen::Vector2d EnuToPixel(const Eigen::Vector2d& p_w) const;
};

/// Renders the photograph of `world` covering at least `extent_w` (east/north in w; the grid is
/// snapped to whole multiples of the resolution in UTM), taken from camera_height_m above the
/// water over `nadir_w`. `origin` places w on the Earth. Texture and pixel noise from `seed`.
/// Throws std::invalid_argument when the origin has no UTM zone (beyond 84 N or 80 S) or the
/// extent is too large for one affine georeferencing (tens of kilometres). `progress` (0..1)
/// may be empty.
AerialPhoto RenderAerialPhoto(const HarbourWorld& world,
                              const GeoOrigin& origin,
                              const AerialImageSim& options,
                              const Eigen::AlignedBox2d& extent_w,
                              const Eigen::Vector2d& nadir_w,
                              std::uint64_t seed,
                              const std::function<void(double)>& progress = {});

/// Writes the photograph as `png_path` with its world file (same stem, .pgw) and CRS sidecar
/// (.prj: the UTM zone as WKT, from GDAL's EPSG database). Throws std::runtime_error when a file
/// cannot be written.
void WriteAerialPhoto(const AerialPhoto& photo, const std::string& png_path);

/// The scenario's photograph (config.harbour.aerial_image, when the harbour and its image are
/// enabled): the harbour's boxes and the dataset's track (truth_states) plus the margin, from
/// above the basin's centre, written as out_dir/orthophoto.png (.pgw, .prj) and named in the
/// dataset's maps.orthophoto.
void RenderAerialImage(const ScenarioConfig& config,
                       std::uint64_t seed,
                       Dataset* data,
                       const std::string& out_dir,
                       const std::function<void(double)>& progress = {});

}  // namespace skerry::sim
