#pragma once
/// \file
/// Estimator outputs on disk.
///
/// `states.csv`: header
///   t,px,py,pz,qx,qy,qz,qw,vx,vy,vz,bgx,bgy,bgz,bax,bay,baz,sigma_px,sigma_py,sigma_pz,
///   sigma_heading_deg
/// (s, m, unit quaternion T_w_b in local ENU, m/s, rad/s, m/s^2, 1-sigma m, 1-sigma deg; sigma
/// columns are empty when no covariance was computed for that state).
///
/// `covariances.csv`: header `t,c00,c01,...,c0_14,c11,...,c14_14`: the upper triangle, row by
/// row, of the 15x15 state covariance in the tangent order of nav_state.h
/// ([rot(world), pos, vel, bg, ba]); one row per state that has a covariance.

#include <string>
#include <vector>

#include "skerry/core/nav_state.h"
#include "skerry/io/atomic_file.h"
#include "skerry/io/trajectory.h"

namespace skerry {

struct EstimateRecord {
  NavState state;
  bool has_covariance = false;
  StateCovariance covariance = StateCovariance::Zero();
};

/// 1-sigma heading (deg) from a 15x15 covariance: the world-z (up) rotation variance.
double HeadingSigmaDeg(const StateCovariance& covariance);
/// Horizontal 1-sigma (m) from a 15x15 covariance: sqrt(var_east + var_north), the RMS
/// horizontal error a consistent estimator makes.
double HorizontalSigmaM(const StateCovariance& covariance);

/// The estimate files of a run in `out_dir` (which must exist): trajectory.tum, states.csv and
/// covariances.csv (docs/outputs.md), written as the records come (a day-long run keeps none in
/// memory); each appears complete under its name at Commit() and never before (AtomicFile).
class EstimateFilesWriter {
 public:
  explicit EstimateFilesWriter(const std::string& out_dir);
  /// Records in time order, after those appended before.
  void Append(const std::vector<EstimateRecord>& records);
  void Commit();
  size_t count() const { return count_; }

 private:
  AtomicFile tum_;
  AtomicFile states_;
  AtomicFile covariances_;
  size_t count_ = 0;
};

/// The three files at once (`out_dir` created if need be).
void WriteEstimateFiles(const std::string& out_dir, const std::vector<EstimateRecord>& records);

/// Reads states.csv and, if `covariances_path` is non-empty and exists, attaches covariances by
/// matching time stamps. Throws InputError naming file, line and field on bad input.
std::vector<EstimateRecord> ReadEstimate(const std::string& states_path,
                                         const std::string& covariances_path = "");

std::vector<StampedPose> ToPoses(const std::vector<EstimateRecord>& records);

}  // namespace skerry
