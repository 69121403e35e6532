#pragma once
/// \file
/// IMU bias random-walk factor between consecutive keyframes:
///   r = [ (bg_j - bg_i) / (sigma_bg_rw sqrt(dt)) ; (ba_j - ba_i) / (sigma_ba_rw sqrt(dt)) ]
/// with the continuous-time random-walk densities of ImuNoise (Forster eq. 48, discretised).
/// Parameter blocks: bg(i)[3], ba(i)[3], bg(j)[3], ba(j)[3].

#include <ceres/sized_cost_function.h>

#include <memory>

#include "skerry/core/sensor_config.h"

namespace skerry {

class BiasRandomWalkFactor : public ceres::SizedCostFunction<6, 3, 3, 3, 3> {
 public:
  BiasRandomWalkFactor(const ImuNoise& noise, double dt_s);
  bool Evaluate(double const* const* parameters,
                double* residuals,
                double** jacobians) const override;

 private:
  double sqrt_info_g_;
  double sqrt_info_a_;
};

}  // namespace skerry
