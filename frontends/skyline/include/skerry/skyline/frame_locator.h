#pragma once
/// \file
/// Where a camera is, from one frame's skyline and the DEM, with no prior closer than a few
/// hundred metres and no heading at all: the global search that starts the window without GNSS
/// and recovers it after a streak of rejected frames.
///
/// 1. Coarse: for every node of a square grid of positions around the prior (camera height held
///    at the prior's), the horizon profile (horizon_predictor.h) at every azimuth step the search
///    can look at: all 360 deg for an unknown heading, else the samples' span widened by the
///    heading window (a forward camera with a known heading need not trace the sea behind it);
///    the observed samples, levelled with the roll and pitch the IMU gives (their world azimuth
///    is then the heading plus a known offset), are slid over it at every heading step, scoring
///    a capped squared pixel error (truncated or missing horizon costs half the cap). The
///    profiles come from the map with every other node (coarse_decimation).
/// 2. Fine: the best few distinct (position, heading) candidates are refined by Levenberg-
///    Marquardt on the full 6-DOF camera pose with the frame's skyline residual
///    (skyline_residual.h) and priors on the tilt and the height; the lowest cost wins, and its
///    ratio to the next distinct minimum says how ambiguous the frame is.
/// 3. Its covariance is the inverse Gauss-Newton information of the winning solution (with the
///    map's error in the samples' noise when dem_sigma_m is set).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <string>
#include <vector>

#include "skerry/skyline/camera_model.h"
#include "skerry/skyline/horizon_predictor.h"
#include "skerry/skyline/skyline_residual.h"

namespace skerry::skyline {

struct FrameLocatorOptions {
  /// Half-width of the square searched around the prior position, m.
  double search_radius_m = 1000.0;
  /// Grid step of the coarse search, m (0: radius / 10).
  double grid_step_m = 0.0;
  /// Azimuth step of the coarse profiles and the heading sweep, deg.
  double azimuth_step_deg = 0.5;
  /// Heading searched: all of it, or prior_heading +- this (deg; >= 180: all).
  double heading_window_deg = 180.0;
  double prior_heading_deg = 0.0;
  /// Candidates refined.
  int refine_candidates = 6;
  /// Per-sample cap of the coarse score, px.
  double coarse_cap_px = 12.0;
  /// Trace the coarse profiles all round even when the heading window cannot reach most of
  /// them: the reference the restricted tracing is tested against (same result, slower).
  bool full_profiles = false;
  /// The coarse profiles are traced on the map with every n-th node in each direction (1: the
  /// map itself), a ray crossing n times fewer cells; the capped coarse score only ranks the
  /// candidates, and their refinement always uses the full map.
  int coarse_decimation = 2;
  /// Priors of the refinement: tilt from the IMU (rad), camera height (m), and the horizontal
  /// position (m; <= 0: none, the search is global inside the square).
  double tilt_sigma_rad = 0.5 * 3.14159265358979323846 / 180.0;
  double height_sigma_m = 1.0;
  double horizontal_sigma_m = 0.0;
  /// Only the horizontal position and heading are estimated (prior work's protocol: 2-DOF
  /// position plus heading); else the full 6-DOF pose with the priors above.
  bool planar = false;
  /// A frame needs this many samples with a horizon to be located, and its solution an RMS
  /// pixel error below max_rms_px.
  int min_samples = 20;
  double max_rms_px = 4.0;
  SkylineResidualOptions residual;
  /// The map's own height error in each sample's noise, as the window's blocks carry it
  /// (SkylineResidualModel::AddMapError, applied at each refinement's start pose): sigma, m
  /// (0: the map taken as exact), and its correlation length on the ground, m. With it the
  /// solution's covariance is that of the frames the window will weigh against it.
  double dem_sigma_m = 0.0;
  double map_correlation_m = 0.0;
};

struct FrameLocation {
  bool ok = false;
  std::string reason;  ///< why not, when !ok
  Eigen::Quaterniond q_w_c = Eigen::Quaterniond::Identity();
  Eigen::Vector3d p_w_c = Eigen::Vector3d::Zero();
  /// Covariance of (rotation vector in the world frame, position), rad and m.
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Identity();
  double cost = 0.0;    ///< final cost of the refinement (half the squared residuals)
  double rms_px = 0.0;  ///< RMS pixel error of the active samples at the solution
  int active_samples = 0;
  /// Final cost of the winner over that of the best distinct other minimum (< 1; near 1:
  /// ambiguous). 0 when only one minimum was found.
  double ambiguity = 0.0;
  int candidates_refined = 0;
  /// The coarse search: the lowest score over grid nodes and headings, the profile azimuths it
  /// traced (over all nodes) and its time, s. 0 for RefineFrame.
  double coarse_score = 0.0;
  long coarse_traces = 0;
  double coarse_seconds = 0.0;
  double seconds = 0.0;
};

/// Locates a camera. `r_level_c`: the camera's attitude up to heading (R_w_c = Rz(a) r_level_c
/// for an unknown a), from the IMU's roll and pitch and the mounting; `prior_p_w_c`: centre of
/// the search, its height taken as the camera's.
FrameLocation LocateFrame(std::shared_ptr<const HorizonPredictor> horizon,
                          const CameraModel& camera,
                          const std::vector<SkylineSample>& samples,
                          const Eigen::Matrix3d& r_level_c,
                          const Eigen::Vector3d& prior_p_w_c,
                          const FrameLocatorOptions& options);

/// Refines a pose by LM from a start (no search): what LocateFrame does to each candidate.
FrameLocation RefineFrame(std::shared_ptr<const HorizonPredictor> horizon,
                          const CameraModel& camera,
                          const std::vector<SkylineSample>& samples,
                          const Eigen::Quaterniond& q_w_c0,
                          const Eigen::Vector3d& p_w_c0,
                          const Eigen::Matrix3d& r_level_c,
                          const Eigen::Vector3d& prior_p_w_c,
                          const FrameLocatorOptions& options);

}  // namespace skerry::skyline
