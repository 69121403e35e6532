#pragma once
/// \file
/// Calibration of a twin (docs/twin.md): a search over the twin's model parameters (noise levels,
/// drift and its correlation time, bias wander) for the model whose twins' estimator outputs are
/// closest to the recording's, by the Hellinger distance, as prior work compared two tunings.
///
/// The search is a coordinate descent in the logarithm of each parameter: each in turn is tried
/// at the current value times each step factor (a parameter at 0, one the identification could
/// not see, is tried at its `start` values instead; in the first round a nonzero one is also tried
/// at the start values the steps do not reach, such as a sensor sheet's) and the best value kept;
/// the factors shrink towards 1 each round. The objective is evaluated with the same twin seeds
/// throughout (common random numbers: SimulateTwin draws the same numbers whatever the model), so
/// that two models are compared on the same noise and the search does not chase it.

#include <functional>
#include <string>
#include <vector>

#include "skerry/io/dataset.h"
#include "skerry/sim/twin.h"

namespace skerry {

struct TwinParameter {
  std::string name;  ///< the key of twin.yaml's model: section, e.g. gnss.white_sigma_horizontal_m
  std::function<double&(sim::TwinModel&)> value;
  std::vector<double> start;  ///< values tried when the parameter is 0
  double min = 0.0, max = 1e300;
  /// A parameter that only matters with another (a drift's sigma with its correlation time):
  /// when this one is 0, each start value is also tried with each of `companion_start` set in
  /// `companion`, so that the pair is switched on together.
  std::function<double&(sim::TwinModel&)> companion;
  std::vector<double> companion_start;
};

/// The parameters a recording's twin can be calibrated in: GNSS white noise, drift (sigma and
/// correlation time); IMU white noise and bias random walk when it has an IMU; the dual-antenna
/// heading noise when its fixes have a heading; with `solve_and_propagate` (a receiver's solve
/// period identified, solve_pattern.h) its offset, propagation velocity error and that error's
/// correlation time (period and phase stay as identified). `reference_sigma_m` scales the
/// drift's start values.
std::vector<TwinParameter> CalibratableParameters(const Dataset& real,
                                                  double reference_sigma_m,
                                                  bool solve_and_propagate = false);

struct TwinCalibrationOptions {
  int rounds = 2;
  std::vector<double> factors = {0.5, 0.7, 1.4, 2.0};  ///< first round; then square-rooted
  /// A new value is kept only when it lowers the objective by more than this (relative): the
  /// objective carries the noise of a few twins.
  double min_improvement = 0.005;
};

struct TwinCalibrationStep {
  std::string parameter;
  double value = 0.0;
  double objective = 0.0;
  bool kept = false;
};

struct TwinCalibration {
  sim::TwinModel model;
  double objective_before = 0.0;
  double objective_after = 0.0;
  int evaluations = 0;
  std::vector<TwinCalibrationStep> steps;  ///< every value tried, in order
  /// Set by the caller that checks the result on held-out twins (seeds the search never saw):
  /// the objective of the start model and of `model` there, and whether `model` stands.
  int validation_twins = 0;
  double validation_before = 0.0, validation_after = 0.0;
  bool validated = true;
};

/// Minimises `objective` over `parameters` from `start`. Throws std::invalid_argument on no
/// parameter, a factor <= 0 or rounds < 1.
TwinCalibration CalibrateTwin(const sim::TwinModel& start,
                              const std::vector<TwinParameter>& parameters,
                              const std::function<double(const sim::TwinModel&)>& objective,
                              const TwinCalibrationOptions& options = {});

}  // namespace skerry
