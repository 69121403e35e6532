#include "skerry/twin/twin_calibration.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <utility>

namespace skerry {

namespace {

TwinParameter Param(std::string name,
                    std::function<double&(sim::TwinModel&)> value,
                    std::vector<double> start,
                    double min,
                    double max,
                    std::function<double&(sim::TwinModel&)> companion = {},
                    std::vector<double> companion_start = {}) {
  TwinParameter p;
  p.name = std::move(name);
  p.value = std::move(value);
  p.start = std::move(start);
  p.min = min;
  p.max = max;
  p.companion = std::move(companion);
  p.companion_start = std::move(companion_start);
  return p;
}

}  // namespace

std::vector<TwinParameter> CalibratableParameters(const Dataset& real,
                                                  double reference_sigma_m,
                                                  bool solve_and_propagate) {
  const double r = reference_sigma_m > 0.0 ? reference_sigma_m : 0.5;
  std::vector<TwinParameter> p;
  p.push_back(Param(
      "gnss.white_sigma_horizontal_m",
      [](sim::TwinModel& m) -> double& { return m.gnss.white_sigma_horizontal_m; }, {0.5 * r, r},
      1e-3, 100.0));
  p.push_back(Param(
      "gnss.white_sigma_vertical_m",
      [](sim::TwinModel& m) -> double& { return m.gnss.white_sigma_vertical_m; }, {0.5 * r, r},
      1e-3, 100.0));
  auto tau = [](sim::TwinModel& m) -> double& { return m.gnss.drift_tau_s; };
  // A drift from a tenth of a second (a receiver's tracking loops) to minutes (the atmosphere).
  const std::vector<double> taus = {0.3, 3.0, 30.0, 300.0};
  p.push_back(Param(
      "gnss.drift_sigma_horizontal_m",
      [](sim::TwinModel& m) -> double& { return m.gnss.drift_sigma_horizontal_m; },
      {0.5 * r, r, 2.0 * r}, 0.0, 100.0, tau, taus));
  p.push_back(Param(
      "gnss.drift_tau_s", [](sim::TwinModel& m) -> double& { return m.gnss.drift_tau_s; },
      {30.0, 300.0}, 0.05, 1e5));
  p.push_back(Param(
      "gnss.drift_sigma_vertical_m",
      [](sim::TwinModel& m) -> double& { return m.gnss.drift_sigma_vertical_m; },
      {0.5 * r, r, 2.0 * r}, 0.0, 100.0, tau, taus));
  // Gross-error episodes: how often, and how far off.
  p.push_back(Param(
      "gnss.gross_rate_per_hour",
      [](sim::TwinModel& m) -> double& { return m.gnss.gross_rate_per_hour; }, {6.0, 60.0}, 0.0,
      3600.0, [](sim::TwinModel& m) -> double& { return m.gnss.gross_offset_horizontal_m; },
      {5.0 * r, 20.0 * r}));
  p.push_back(Param(
      "gnss.gross_offset_horizontal_m",
      [](sim::TwinModel& m) -> double& { return m.gnss.gross_offset_horizontal_m; },
      {5.0 * r, 20.0 * r}, 0.0, 1000.0));
  if (solve_and_propagate) {
    // A receiver that solves once a period and propagates between: the offset at each solution,
    // the propagation velocity error and its correlation time (sim/twin.h).
    p.push_back(Param(
        "gnss.solve_offset_sigma_m",
        [](sim::TwinModel& m) -> double& { return m.gnss.solve_offset_sigma_m; },
        {0.2 * r, 0.5 * r}, 0.0, 100.0));
    p.push_back(Param(
        "gnss.propagation_velocity_sigma_m_s",
        [](sim::TwinModel& m) -> double& { return m.gnss.propagation_velocity_sigma_m_s; },
        {r, 2.0 * r}, 0.0, 100.0));
    p.push_back(Param(
        "gnss.propagation_velocity_tau_s",
        [](sim::TwinModel& m) -> double& { return m.gnss.propagation_velocity_tau_s; }, {5.0}, 0.1,
        1e4));
  }
  if (real.has_imu) {
    p.push_back(Param(
        "imu.gyro_noise_density_rad_s_sqrt_hz",
        [](sim::TwinModel& m) -> double& { return m.imu.gyro_noise_density_rad_s_sqrt_hz; },
        {real.imu.noise.gyro_noise_density_rad_s_sqrt_hz}, 1e-9, 1.0));
    p.push_back(Param(
        "imu.accel_noise_density_m_s2_sqrt_hz",
        [](sim::TwinModel& m) -> double& { return m.imu.accel_noise_density_m_s2_sqrt_hz; },
        {real.imu.noise.accel_noise_density_m_s2_sqrt_hz}, 1e-9, 10.0));
    // Bias wander the batch's bias history does not hold (it smooths what it estimates).
    p.push_back(Param(
        "imu.gyro_bias_random_walk_rad_s2_sqrt_hz",
        [](sim::TwinModel& m) -> double& { return m.imu.gyro_bias_random_walk_rad_s2_sqrt_hz; },
        {real.imu.noise.gyro_bias_random_walk_rad_s2_sqrt_hz,
         10.0 * real.imu.noise.gyro_bias_random_walk_rad_s2_sqrt_hz},
        0.0, 1.0));
    p.push_back(Param(
        "imu.accel_bias_random_walk_m_s3_sqrt_hz",
        [](sim::TwinModel& m) -> double& { return m.imu.accel_bias_random_walk_m_s3_sqrt_hz; },
        {real.imu.noise.accel_bias_random_walk_m_s3_sqrt_hz,
         10.0 * real.imu.noise.accel_bias_random_walk_m_s3_sqrt_hz},
        0.0, 10.0));
  }
  bool heading = false;
  for (const GnssFix& f : real.gnss_fixes) heading = heading || f.has_heading;
  if (heading) {
    p.push_back(Param(
        "gnss.heading_sigma_deg",
        [](sim::TwinModel& m) -> double& { return m.gnss.heading_sigma_deg; }, {0.1, 0.5}, 1e-3,
        30.0));
  }
  return p;
}

TwinCalibration CalibrateTwin(const sim::TwinModel& start,
                              const std::vector<TwinParameter>& parameters,
                              const std::function<double(const sim::TwinModel&)>& objective,
                              const TwinCalibrationOptions& options) {
  if (parameters.empty()) throw std::invalid_argument("CalibrateTwin: no parameter to calibrate");
  if (options.rounds < 1) throw std::invalid_argument("CalibrateTwin: rounds must be >= 1");
  for (double f : options.factors) {
    if (!(f > 0.0) || !std::isfinite(f)) {
      throw std::invalid_argument("CalibrateTwin: step factors must be finite and > 0");
    }
  }
  TwinCalibration out;
  out.model = start;
  double best = objective(out.model);
  ++out.evaluations;
  out.objective_before = best;
  std::vector<double> factors = options.factors;
  for (int round = 0; round < options.rounds; ++round) {
    for (const TwinParameter& p : parameters) {
      sim::TwinModel trial = out.model;
      const double current = p.value(trial);
      const bool paired = current == 0.0 && p.companion && !p.companion_start.empty();
      const double companion_current = paired ? p.companion(trial) : 0.0;
      // (value, companion value) pairs; without a companion the second is unused.
      std::vector<std::pair<double, double>> candidates;
      if (current > 0.0) {
        for (double f : factors) candidates.emplace_back(current * f, 0.0);
        // In the first round, also the start values the steps cannot reach: an IMU's sheet
        // value twenty times below a density the residuals overstate (their truth misses the
        // fastest motion) is otherwise out of reach of a few halvings.
        const auto [lo, hi] = std::minmax_element(factors.begin(), factors.end());
        for (double v : round == 0 && !factors.empty() ? p.start : std::vector<double>()) {
          if (v > 0.0 && (v < current * *lo || v > current * *hi)) candidates.emplace_back(v, 0.0);
        }
      } else {
        for (double v : p.start) {
          if (!paired) candidates.emplace_back(v, 0.0);
          for (double c : paired ? p.companion_start : std::vector<double>()) {
            candidates.emplace_back(v, c);
          }
        }
      }
      std::pair<double, double> best_value(current, companion_current);
      int best_step = -1;
      for (auto [value, companion_value] : candidates) {
        value = std::clamp(value, p.min, p.max);
        if (value == current) continue;
        p.value(trial) = value;
        if (paired) p.companion(trial) = companion_value;
        const double v = objective(trial);
        ++out.evaluations;
        std::string name = p.name;
        if (paired) name += " (" + std::to_string(companion_value) + ")";
        out.steps.push_back({name, value, v, false});
        if (v < best * (1.0 - options.min_improvement)) {
          best = v;
          best_value = {value, companion_value};
          best_step = static_cast<int>(out.steps.size()) - 1;
        }
      }
      p.value(out.model) = best_value.first;
      if (paired) p.companion(out.model) = best_value.second;
      if (best_step >= 0) out.steps[static_cast<size_t>(best_step)].kept = true;
    }
    for (double& f : factors) f = std::sqrt(f);
  }
  out.objective_after = best;
  return out;
}

}  // namespace skerry
