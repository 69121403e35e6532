#pragma once
/// \file
/// Prior work's whole pipeline on a dataset, as a baseline: its planar EKF (baseline_planar_ekf.h)
/// predicted with the gyro's yaw rate, corrected by every GNSS fix (at the body origin through
/// the lever arm at the filter's heading) and by prior work's matcher (baseline_pso_matcher.h) on
/// every scan of the dataset's first LiDAR: the returns put in the body frame by T_b_l without
/// levelling (prior work projected them top-down with the heading alone), those lower than
/// `min_height_m` above the body origin and inside the hull box dropped, the match's prior the
/// filter's pose at the scan's stamp (no deskewing). It starts at the ground truth's first pose
/// with `start_sigma_m` and `start_sigma_deg` (given, as prior work's runs started known).

#include <Eigen/Geometry>
#include <vector>

#include "skerry/io/dataset.h"
#include "skerry/lidar_aerial/aerial_map.h"
#include "skerry/lidar_aerial/baseline_planar_ekf.h"
#include "skerry/lidar_aerial/baseline_pso_matcher.h"

namespace skerry::lidar_aerial::baseline {

struct BaselineRunOptions {
  PlanarEkfOptions ekf;
  BaselineOptions matcher;
  double min_height_m = 0.3;
  Eigen::AlignedBox3d hull_b;  ///< empty: none
  double start_sigma_m = 1.0;
  double start_sigma_deg = 2.0;
  /// Match every this many scans (1: all); the others are skipped. Prior work matched at 1 Hz.
  int match_every = 1;
};

struct BaselineRun {
  std::vector<PlanarEstimate> estimates;  ///< after every GNSS fix and every match
  int scans = 0;
  int matches = 0;  ///< matcher runs
  int accepted = 0;
  int gated = 0;
  int invalid = 0;
  double match_s = 0.0;  ///< total matcher time
};

/// `map` at the matcher's resolution (options.matcher.cell_m). Throws std::invalid_argument when
/// the dataset has no ground truth or no LiDAR, InputError for a scan that cannot be read.
BaselineRun RunBaseline(const Dataset& data,
                        const AerialMap& map,
                        const BaselineRunOptions& options = {});

}  // namespace skerry::lidar_aerial::baseline
