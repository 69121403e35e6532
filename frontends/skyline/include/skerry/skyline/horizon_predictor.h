#pragma once
/// \file
/// The terrain horizon seen from a point: per azimuth, the highest apparent elevation angle of
/// the DEM and the terrain point that makes it, with Earth curvature and refraction, fast enough
/// to re-predict at every solver iteration.
///
/// Everything is in the local ENU frame `w`. An azimuth a (rad, clockwise from the frame's
/// north) names the vertical half-plane of directions (sin a, cos a, tan e): the skyline a camera
/// sees along any ray of that half-plane is the maximum over distance s of
///   e(s) = atan2(z_t(p + s d) - z_c, s) + k s / (2 R)
/// with z_t the terrain's ENU up coordinate (geo::EnuHeightGrid: Earth curvature is in it, as
/// the ground falls below the origin's tangent plane) and the last term the refraction of a ray
/// bent on a circle of radius R/k (Hirt et al. 2010, "Modelling of the terrestrial refraction",
/// eq. 2, k ~ 0.13 over land by day).
///
/// Speed: a max pyramid over the grid's cells (each level the maximum of 2x2 blocks of the level
/// below) lets a ray skip every block whose highest terrain cannot beat the best elevation found
/// so far; only cells that could hold the horizon are sampled (at their edges and centres,
/// bilinear). A full 1920-column profile from 40 km of SRTM3 costs about a millisecond.
///
/// Derivatives are those of the maximum itself, which slides along the ridge as the camera moves
/// (no DEM point is frozen as a landmark): along the ray the grazed point stays put (a tangent
/// point, or a kink of the bilinear surface where the ray crosses a grid line, where most maxima
/// on a DEM sit), so d e / d s = -dz / (s^2 + dz^2) + k / (2 R); the skyline's slope d e / d a is
/// the difference of the maxima re-found next to the point on rays a +- da; and a camera moved by
/// c across the ray sees at azimuth a what it saw at a + c / s. The terrain's own gradient is
/// never used: at a kink it is undefined, and averaged across the crest it is not the slope the
/// ray grazes (tests/skyline/horizon_predictor_test.cc, on the Côte d'Azur DEM).

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "skerry/geo/enu_height_grid.h"

namespace skerry::skyline {

struct HorizonOptions {
  /// Coefficient of terrestrial refraction (0: straight rays).
  double refraction_k = 0.13;
  /// Earth radius for the refraction term, m.
  double earth_radius_m = 6371000.0;
  /// Terrain nearer than this (horizontally) is ignored: the ground under a mast or a hull.
  double min_range_m = 30.0;
  double max_range_m = 100000.0;
  /// A horizon is truncated when terrain at the map's edge (the grid's border, a void, or the
  /// end of max_range) comes within this angle of it: the terrain beyond may be higher.
  double edge_tolerance_rad = 0.05 * 3.14159265358979323846 / 180.0;
};

/// The horizon along one azimuth.
struct HorizonSample {
  /// Terrain was found along the azimuth within range.
  bool valid = false;
  /// The map ends (border, void or max_range) where its terrain is within edge_tolerance of the
  /// horizon: the true horizon may lie beyond the map, never use it as a measurement.
  bool truncated = false;
  double elevation_rad = 0.0;  ///< apparent elevation of the horizon (refraction included)
  double distance_m = 0.0;     ///< horizontal distance to the terrain point making it
  Eigen::Vector3d point_w = Eigen::Vector3d::Zero();  ///< that terrain point
  /// d elevation / d camera position (the grazed point fixed along the ray, the skyline's slope
  /// across it).
  Eigen::Vector3d d_elevation_d_p = Eigen::Vector3d::Zero();
  /// d elevation / d azimuth: the skyline's slope, from the maxima re-found on rays a quarter of a
  /// node spacing to either side at the point's distance.
  double d_elevation_d_azimuth = 0.0;
  /// d elevation / d refraction coefficient k: s* / (2 R) (envelope theorem).
  double d_elevation_d_refraction = 0.0;
};

class HorizonPredictor {
 public:
  /// Builds the pyramid over `grid` (NaN nodes are the map's holes). std::invalid_argument for a
  /// grid smaller than 2x2 or a spacing <= 0.
  HorizonPredictor(geo::EnuHeightGrid grid, const HorizonOptions& options = {});

  /// The horizon seen from p_w along azimuth a (rad, clockwise from north).
  HorizonSample Trace(const Eigen::Vector3d& p_w, double azimuth_rad) const {
    return Trace(p_w, azimuth_rad, options_.refraction_k);
  }
  /// The same with the refraction coefficient `refraction_k` in place of the options' (an
  /// estimator that estimates k traces at its current estimate). `derivatives` false leaves the
  /// position and azimuth derivatives at zero and saves the two maxima re-found for the skyline's
  /// slope (a search that only scores elevations).
  HorizonSample Trace(const Eigen::Vector3d& p_w,
                      double azimuth_rad,
                      double refraction_k,
                      bool derivatives = true) const;

  /// The horizon at n azimuths a0 + i * step.
  std::vector<HorizonSample> Profile(const Eigen::Vector3d& p_w,
                                     double azimuth0_rad,
                                     double step_rad,
                                     int n) const;

  /// The terrain's ENU up coordinate (bilinear); false outside the map or on a hole.
  bool Terrain(double x, double y, double* z) const;

  /// Whether (x, y) lies inside the grid with data under it.
  bool Covers(double x, double y) const;

  const geo::EnuHeightGrid& grid() const { return grid_; }
  const HorizonOptions& options() const { return options_; }

  /// The map's detail: per node, what one sharpening of gain 1 would add to its height
  /// (geo::SharpenTerrain; 0 on water), for a sharpening gain estimated with the states rather
  /// than applied (SkylineResidualModel). `detail` must have the grid's geometry, else
  /// std::invalid_argument. Not safe while the predictor is used elsewhere: attach before
  /// sharing it.
  void AttachDetail(geo::EnuHeightGrid detail);
  /// The detail (bilinear) at (x, y); 0 without one, off the grid or on a hole.
  double DetailAt(double x, double y) const;
  bool has_detail() const { return !detail_.up_m.empty(); }

 private:
  geo::EnuHeightGrid grid_;
  geo::EnuHeightGrid detail_;
  HorizonOptions options_;
  /// levels_[L]: max over blocks of 2^L x 2^L cells (a cell: the square between four nodes);
  /// +inf where a block holds a hole (never skipped, so the march sees the map's edge).
  struct Level {
    int cols = 0, rows = 0;
    std::vector<float> max;
  };
  std::vector<Level> levels_;
};

}  // namespace skerry::skyline
