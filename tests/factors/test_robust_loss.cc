// robust_loss: name parsing and the down-weighting each loss applies.

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "skerry/factors/robust_loss.h"

namespace skerry {
namespace {

TEST(RobustLossTest, ParseRoundTrip) {
  for (LossType type : {LossType::kNone, LossType::kHuber, LossType::kCauchy, LossType::kTukey}) {
    EXPECT_EQ(ParseLossType(ToString(type)), type);
  }
  EXPECT_EQ(ToString(LossType::kHuber), "huber");
  EXPECT_EQ(ParseLossType("cauchy"), LossType::kCauchy);
}

TEST(RobustLossTest, BadNamesThrow) {
  for (const char* name : {"", "Huber", "HUBER", "huber ", "l1", "cauchy2", "none\n"}) {
    EXPECT_THROW(ParseLossType(name), std::invalid_argument) << "'" << name << "'";
  }
}

TEST(RobustLossTest, MakeLossTypes) {
  RobustLoss cfg;
  cfg.type = LossType::kNone;
  EXPECT_EQ(MakeLoss(cfg), nullptr);
  cfg.type = LossType::kHuber;
  EXPECT_NE(dynamic_cast<ceres::HuberLoss*>(MakeLoss(cfg).get()), nullptr);
  cfg.type = LossType::kCauchy;
  EXPECT_NE(dynamic_cast<ceres::CauchyLoss*>(MakeLoss(cfg).get()), nullptr);
  cfg.type = LossType::kTukey;
  EXPECT_NE(dynamic_cast<ceres::TukeyLoss*>(MakeLoss(cfg).get()), nullptr);
}

// Weight rho'(s) of a whitened residual of n sigmas (s = n^2). Scale is in sigmas: a residual
// inside the scale is (nearly) untouched, a 15-sigma outlier is strongly down-weighted.
double Weight(LossType type, double n_sigma, double scale = 3.0) {
  RobustLoss cfg;
  cfg.type = type;
  cfg.scale = scale;
  const auto loss = MakeLoss(cfg);
  if (loss == nullptr) return 1.0;
  double rho[3];
  loss->Evaluate(n_sigma * n_sigma, rho);
  return rho[1];
}

TEST(RobustLossTest, OutlierWeights) {
  const double w_none = Weight(LossType::kNone, 15.0);
  EXPECT_EQ(w_none, 1.0);
  // Closed forms with scale a = 3, s = 225: Huber a/sqrt(s) = 0.2, Cauchy 1/(1 + s/a^2) = 1/26,
  // Tukey 0 beyond a.
  EXPECT_NEAR(Weight(LossType::kHuber, 15.0), 0.2, 1e-12);
  EXPECT_NEAR(Weight(LossType::kCauchy, 15.0), 1.0 / 26.0, 1e-12);
  EXPECT_EQ(Weight(LossType::kTukey, 15.0), 0.0);
  EXPECT_LT(Weight(LossType::kCauchy, 15.0), 0.05 * w_none);
  EXPECT_LT(Weight(LossType::kTukey, 15.0), 0.05 * w_none);
  // Inliers (1 sigma) keep most of their weight under every loss.
  EXPECT_EQ(Weight(LossType::kHuber, 1.0), 1.0);
  EXPECT_GT(Weight(LossType::kCauchy, 1.0), 0.85);
  EXPECT_GT(Weight(LossType::kTukey, 1.0), 0.75);
  // The scale is honoured: a larger scale down-weights the same residual less.
  EXPECT_GT(Weight(LossType::kCauchy, 15.0, 10.0), Weight(LossType::kCauchy, 15.0, 3.0));
}

}  // namespace
}  // namespace skerry
