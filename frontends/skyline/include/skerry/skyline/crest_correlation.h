#pragma once
/// \file
/// How much of a skyline frame's error it shares with the previous frame of the same camera,
/// from how far the terrain points that make its skyline have moved.
///
/// A skyline's error is mostly the DEM's: its heights and their interpolation are wrong by a
/// field that is fixed on the ground and varies over some length L (a grid cell or more). Two
/// frames repeat each other's error for as long as the same ground makes their horizon, whatever
/// the time between them: a vessel holding its course towards ridges 30 km away sees the same
/// crests for minutes, one passing a headland 2 km off sees its silhouette slide across the
/// slope within seconds. So the correlation of frame k with frame k - 1 is measured on the
/// ground: for each sample, the terrain point X_i making its horizon from the camera's position
/// now, and the point X'_i making the horizon from the previous frame's camera position along
/// the azimuth towards X_i (the same ground when the silhouette stays put, another point of the
/// slope when it slid), and
///   rho = (1 / n) sum_i exp(-|X_i - X'_i|_h / L),
/// with n the samples that have a horizon now (those without one from the previous position
/// count 0: new ground). A horizon made by water (the map's nodes around its point level once the
/// Earth's curvature is taken out: a sea or a lake in the DEM) counts 0 as well: its errors are the
/// waves' and the air's, not the map's, and the grazing point slides over the water with the
/// vessel. The errors of the same ground are modelled as one exponentially correlated field
/// (the first-order Gauss-Markov process of Gelb 1974, "Applied Optimal Estimation", ch. 3, over
/// distance instead of time), so rho is the correlation of each sample's error with its
/// predecessor's, averaged over the frame.

#include <Eigen/Core>
#include <vector>

#include "skerry/skyline/horizon_predictor.h"

namespace skerry::skyline {

struct CrestMotion {
  double rho = 0.0;             ///< the frame's correlation with its predecessor, in [0, 1]
  int samples = 0;              ///< samples with a horizon from the camera now (n)
  int water = 0;                ///< of which are made by water (count 0)
  int compared = 0;             ///< of the others, those with a horizon from the previous position
  double median_shift_m = 0.0;  ///< median horizontal |X_i - X'_i| over the compared ones
};

/// Whether a horizon point lies on water: the map level around the node nearest it
/// (geo::EnuHeightGrid::LevelAround: its 3 x 3 nodes within 0.1 m once the curvature is taken
/// out). False where that node is off the map or any of those nodes is void.
bool HorizonOnWater(const HorizonPredictor& horizon, const Eigen::Vector3d& point_w);

/// `now_w`: per sample, X_i, the terrain point making its horizon from the camera now, NaN where
/// it has none (SkylineResidualModel::HorizonPoints, which keeps that trace for the residual);
/// `p_prev_w_c`: the previous frame's camera position; `length_m` (> 0): L.
CrestMotion MeasureCrestMotion(const HorizonPredictor& horizon,
                               const std::vector<Eigen::Vector3d>& now_w,
                               const Eigen::Vector3d& p_prev_w_c,
                               double length_m);

/// The same, tracing X_i itself: `rays_c` the frame's unit rays in the camera frame
/// (SkylineResidualModel::rays_c), seen from the camera pose (r_w_c, p_w_c). Truncated horizons
/// (the map ends there) are no horizon.
CrestMotion MeasureCrestMotion(const HorizonPredictor& horizon,
                               const std::vector<Eigen::Vector3d>& rays_c,
                               const Eigen::Matrix3d& r_w_c,
                               const Eigen::Vector3d& p_w_c,
                               const Eigen::Vector3d& p_prev_w_c,
                               double length_m);

}  // namespace skerry::skyline
