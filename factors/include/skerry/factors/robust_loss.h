#pragma once
/// \file
/// Configurable robust loss for measurement factors.

#include <ceres/loss_function.h>

#include <memory>
#include <string>

namespace skerry {

enum class LossType { kNone, kHuber, kCauchy, kTukey };

struct RobustLoss {
  LossType type = LossType::kHuber;
  /// Scale in whitened units (sigmas): residuals beyond it are down-weighted.
  double scale = 3.0;
};

/// "none", "huber", "cauchy", "tukey" -> LossType; throws std::invalid_argument otherwise.
LossType ParseLossType(const std::string& name);
std::string ToString(LossType type);

/// nullptr for kNone. The caller owns the loss.
std::unique_ptr<ceres::LossFunction> MakeLoss(const RobustLoss& loss);

}  // namespace skerry
