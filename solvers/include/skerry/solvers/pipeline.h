#pragma once
/// \file
/// Runs the estimators over a dataset: the window processes the data in time order as a live
/// system would; the batch smoother refines the whole trajectory afterwards.

#include <functional>
#include <vector>

#include "skerry/core/dataset.h"
#include "skerry/solvers/batch_smoother.h"
#include "skerry/solvers/sliding_window_estimator.h"

namespace skerry {

struct WindowRun {
  std::vector<EstimateRecord> records;
  std::vector<UpdateStats> stats;
  GnssStats gnss;
  std::vector<std::pair<TimeNs, FixDecision>> decisions;
  double wall_s = 0.0;
  double data_s = 0.0;  ///< span of the IMU data
};

/// `progress(fraction)` is called now and then (may be empty).
/// `initial`: optional given first state (init.mode "given").
WindowRun RunWindow(const Dataset& data,
                    const EstimatorConfig& config,
                    const std::function<void(double)>& progress = {},
                    const EstimateRecord* initial = nullptr);

}  // namespace skerry
