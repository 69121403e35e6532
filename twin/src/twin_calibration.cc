#include "skerry/twin/twin_calibration.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace skerry {

std::vector<TwinParameter> CalibratableParameters(const Dataset& real, double reference_sigma_m) {
  const double r = reference_sigma_m > 0.0 ? reference_sigma_m : 0.5;
  std::vector<TwinParameter> p;
  p.push_back({"gnss.white_sigma_horizontal_m",
               [](sim::TwinModel& m) -> double& { return m.gnss.white_sigma_horizontal_m; },
               {0.5 * r, r},
               1e-3,
               100.0});
  p.push_back({"gnss.white_sigma_vertical_m",
               [](sim::TwinModel& m) -> double& { return m.gnss.white_sigma_vertical_m; },
               {0.5 * r, r},
               1e-3,
               100.0});
  p.push_back({"gnss.drift_sigma_horizontal_m",
               [](sim::TwinModel& m) -> double& { return m.gnss.drift_sigma_horizontal_m; },
               {0.5 * r, r, 2.0 * r},
               0.0,
               100.0});
  p.push_back({"gnss.drift_tau_s",
               [](sim::TwinModel& m) -> double& { return m.gnss.drift_tau_s; },
               {30.0, 300.0},
               1.0,
               1e5});
  p.push_back({"gnss.drift_sigma_vertical_m",
               [](sim::TwinModel& m) -> double& { return m.gnss.drift_sigma_vertical_m; },
               {0.5 * r, r, 2.0 * r},
               0.0,
               100.0});
  if (real.has_imu) {
    p.push_back(
        {"imu.gyro_noise_density_rad_s_sqrt_hz",
         [](sim::TwinModel& m) -> double& { return m.imu.gyro_noise_density_rad_s_sqrt_hz; },
         {real.imu.noise.gyro_noise_density_rad_s_sqrt_hz},
         1e-9,
         1.0});
    p.push_back(
        {"imu.accel_noise_density_m_s2_sqrt_hz",
         [](sim::TwinModel& m) -> double& { return m.imu.accel_noise_density_m_s2_sqrt_hz; },
         {real.imu.noise.accel_noise_density_m_s2_sqrt_hz},
         1e-9,
         10.0});
    // Bias wander the batch's bias history does not hold (it smooths what it estimates).
    p.push_back(
        {"imu.gyro_bias_random_walk_rad_s2_sqrt_hz",
         [](sim::TwinModel& m) -> double& { return m.imu.gyro_bias_random_walk_rad_s2_sqrt_hz; },
         {real.imu.noise.gyro_bias_random_walk_rad_s2_sqrt_hz,
          10.0 * real.imu.noise.gyro_bias_random_walk_rad_s2_sqrt_hz},
         0.0,
         1.0});
    p.push_back(
        {"imu.accel_bias_random_walk_m_s3_sqrt_hz",
         [](sim::TwinModel& m) -> double& { return m.imu.accel_bias_random_walk_m_s3_sqrt_hz; },
         {real.imu.noise.accel_bias_random_walk_m_s3_sqrt_hz,
          10.0 * real.imu.noise.accel_bias_random_walk_m_s3_sqrt_hz},
         0.0,
         10.0});
  }
  bool heading = false;
  for (const GnssFix& f : real.gnss_fixes) heading = heading || f.has_heading;
  if (heading) {
    p.push_back({"gnss.heading_sigma_deg",
                 [](sim::TwinModel& m) -> double& { return m.gnss.heading_sigma_deg; },
                 {0.1, 0.5},
                 1e-3,
                 30.0});
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
      std::vector<double> candidates;
      if (current > 0.0) {
        for (double f : factors) candidates.push_back(current * f);
      } else {
        candidates = p.start;
      }
      double best_value = current;
      for (double c : candidates) {
        c = std::clamp(c, p.min, p.max);
        if (c == current) continue;
        p.value(trial) = c;
        const double v = objective(trial);
        ++out.evaluations;
        const bool better = v < best * (1.0 - options.min_improvement);
        out.steps.push_back({p.name, c, v, false});
        if (better) {
          best = v;
          best_value = c;
        }
      }
      p.value(out.model) = best_value;
      if (best_value != current) {
        for (auto it = out.steps.rbegin(); it != out.steps.rend(); ++it) {
          if (it->parameter == p.name && it->value == best_value) {
            it->kept = true;
            break;
          }
        }
      }
    }
    for (double& f : factors) f = std::sqrt(f);
  }
  out.objective_after = best;
  return out;
}

}  // namespace skerry
