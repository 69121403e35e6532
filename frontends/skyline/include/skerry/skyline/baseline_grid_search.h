#pragma once
/// \file
/// Prior work's single-frame skyline localisation, reimplemented as a baseline to run beside
/// skerry on the same frames (bench/skyline_protocol.cc): a vessel's camera, a segmentation
/// mask and a DEM; the intended waypoint of its path (its position prior) and its true previous
/// position given; 2-DOF position with the heading implied by the path.
///
/// 1. The observed skyline: morphological opening and closing of the mask, then per column the
///    first sky -> not-sky transition (integer rows).
/// 2. The expected skyline at the waypoint, by ray tracing the DEM: per image column, a fixed-step
///    march along the column's azimuth for the highest elevation (Earth curvature and refraction
///    as skerry's, so that the methods, not the physics, differ); the terrain point found is kept
///    as the column's 3-D point and projected back into the image.
/// 3. "Hilltops" in both: local peaks of the skyline more than 5 px high and 25 px wide,
///    measured between the feet on either side.
/// 4. A 1-D sum-of-absolute-differences match of a window of the expected skyline around each
///    expected hilltop against the observed skyline over a range of horizontal shifts (windows
///    made zero-mean); a match is kept when an observed hilltop lies near the shifted peak.
/// 5. An adaptive grid search over (x, y): 5 x 5 candidates at half-width 32 m around the
///    waypoint, heading from the true previous position to each candidate, scored by the mean
///    reprojection error of the matched 3-D points against the observed hilltops; recentred on
///    the best and halved down to 0.5 m.
/// A frame with fewer than two matches is a failed match (the estimate stays at the waypoint).

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "skerry/geo/enu_height_grid.h"
#include "skerry/skyline/camera_model.h"

namespace skerry::skyline::baseline {

struct BaselineOptions {
  int morphology_px = 5;
  double min_hilltop_height_px = 5.0;
  double min_hilltop_width_px = 25.0;
  int sad_half_window_px = 40;
  int sad_max_shift_px = 200;
  double sad_max_mean_px = 6.0;     ///< a match's mean absolute difference must stay below
  double peak_tolerance_px = 12.0;  ///< observed hilltop within this of the shifted peak
  int min_matches = 2;
  double start_half_width_m = 32.0;
  double stop_half_width_m = 0.5;
  int grid_points = 5;  ///< per axis
  double march_step_m = 45.0;
  double min_range_m = 30.0;
  double max_range_m = 60000.0;
  double refraction_k = 0.13;
};

struct BaselineInput {
  Eigen::Vector2d intended_xy = Eigen::Vector2d::Zero();  ///< the waypoint (the prior)
  Eigen::Vector2d previous_xy = Eigen::Vector2d::Zero();  ///< the true previous position
  double camera_z = 0.0;                                  ///< ENU up of the camera
  /// The camera's attitude up to heading (R_w_c = Rz(-heading) r_level_c), from the IMU.
  Eigen::Matrix3d r_level_c = Eigen::Matrix3d::Identity();
};

struct BaselineResult {
  bool ok = false;
  std::string reason;
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();
  double heading_rad = 0.0;  ///< implied by the path to xy
  double reprojection_px = 0.0;
  int matches = 0;
  int hilltops_expected = 0, hilltops_observed = 0;
  double seconds = 0.0;
};

/// The observed skyline of a mask by morphology (integer rows, -1 where none).
std::vector<int> MorphologicalSkyline(const cv::Mat& mask, int morphology_px);

/// Hilltops of a skyline (rows per column, < 0 = none): the columns of their peaks.
std::vector<int> Hilltops(const std::vector<double>& rows,
                          double min_height_px,
                          double min_width_px);

/// The shift d minimising the mean absolute difference between the zero-mean window of
/// `expected` around `centre` and `observed` shifted by d; *mean_abs gets that mean.
int SadShift(const std::vector<double>& expected,
             const std::vector<double>& observed,
             int centre,
             int half_window,
             int max_shift,
             double* mean_abs);

BaselineResult LocateFrameBaseline(const geo::EnuHeightGrid& grid,
                                   const CameraModel& camera,
                                   const cv::Mat& mask,
                                   const BaselineInput& input,
                                   const BaselineOptions& options = {});

}  // namespace skerry::skyline::baseline
