#include "skerry/factors/robust_loss.h"

#include <stdexcept>

namespace skerry {

LossType ParseLossType(const std::string& name) {
  if (name == "none") return LossType::kNone;
  if (name == "huber") return LossType::kHuber;
  if (name == "cauchy") return LossType::kCauchy;
  if (name == "tukey") return LossType::kTukey;
  throw std::invalid_argument("unknown loss '" + name + "' (expected none, huber, cauchy, tukey)");
}

std::string ToString(LossType type) {
  switch (type) {
    case LossType::kNone:
      return "none";
    case LossType::kHuber:
      return "huber";
    case LossType::kCauchy:
      return "cauchy";
    case LossType::kTukey:
      return "tukey";
  }
  return "none";
}

std::unique_ptr<ceres::LossFunction> MakeLoss(const RobustLoss& loss) {
  switch (loss.type) {
    case LossType::kNone:
      return nullptr;
    case LossType::kHuber:
      return std::make_unique<ceres::HuberLoss>(loss.scale);
    case LossType::kCauchy:
      return std::make_unique<ceres::CauchyLoss>(loss.scale);
    case LossType::kTukey:
      return std::make_unique<ceres::TukeyLoss>(loss.scale);
  }
  return nullptr;
}

}  // namespace skerry
