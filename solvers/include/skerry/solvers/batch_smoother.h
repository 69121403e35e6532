#pragma once
/// \file
/// Whole-trajectory smoothing with the same factors as the window: one keyframe per window
/// keyframe, every IMU interval, every GNSS fix the window neither rejected nor dropped, a Ceres
/// solve over all of it, then a chi-square check of every GNSS residual at the solution (fixes
/// beyond the gate left out and the problem re-solved, up to three rounds), and the marginal
/// covariance of every state.

#include <string>
#include <vector>

#include "skerry/io/dataset.h"
#include "skerry/io/estimate_io.h"
#include "skerry/solvers/sliding_window_estimator.h"

namespace skerry {

struct BatchResult {
  std::vector<EstimateRecord> records;
  int iterations = 0;  ///< Ceres iterations that tried a step, over every solve
  double solve_s = 0.0;
  double covariance_s = 0.0;
  int gnss_used = 0;                  ///< position factors kept
  int headings_used = 0;              ///< dual-antenna heading factors
  int gnss_rejected_after_solve = 0;  ///< fixes left out at the final solution
  bool usable = false;
  std::string ceres_report;
};

/// The batch smoother over the data up to t_end_ns, started from nothing but `start` (a first
/// state and its covariance: the prior of the start rule) and the data: keyframes at the
/// window's rate, their values predicted through the IMU from the solution so far over spans that
/// double (10 s, 20 s, 40 s, ...) and re-solved, every fix it can tie to a keyframe with the
/// robust losses and, at each solution, the fixes beyond the gate dropped (up to three rounds).
/// Nothing of a window's estimates or decisions goes in, so its estimate at t_end_ns is a
/// reference for the window's: the best causal estimate (pipeline.h SmoothUntil).
BatchResult SmoothFrom(const Dataset& data,
                       const EstimatorConfig& config,
                       const EstimateRecord& start,
                       TimeNs t_end_ns);

/// `initial`: the window's keyframe estimates (their times become the batch keyframes, their
/// values the initial guess; the first record's covariance is the prior). `decisions`: the
/// window's decision per GNSS fix, decisions[k] about data.gnss_fixes[k] (positions it rejected
/// or dropped stay out, and headings it did not take); std::logic_error if they do not match.
BatchResult SmoothBatch(const Dataset& data,
                        const EstimatorConfig& config,
                        const std::vector<EstimateRecord>& initial,
                        const std::vector<FixRecord>& decisions);

}  // namespace skerry
