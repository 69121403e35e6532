#include "skerry/solvers/gnss_fix_model.h"

#include "skerry/core/so3.h"
#include "skerry/factors/gnss_heading_factor.h"
#include "skerry/factors/gnss_position_factor.h"

namespace skerry {

namespace {
constexpr double kDegToRad = M_PI / 180.0;
// Heading sigmas below this are taken as this (a receiver that claims 0 must not give an
// infinite weight).
constexpr double kMinHeadingSigmaDeg = 1e-3;
}  // namespace

TiedFix TieFix(const GnssFix& fix,
               const Keyframe& kf,
               const GnssConfig& gnss,
               const ImuConfig& imu,
               const EarthModel& earth,
               double sigma_scale) {
  TiedFix t;
  t.dt_s = NsToSeconds(fix.t_ns - kf.t_ns);
  const NavState s = kf.state();
  const Eigen::Vector3d omega_b =
      imu.q_b_i * (kf.gyro_rad_s - s.bg) - s.q_w_b.conjugate() * earth.omega_ie_w();
  const Eigen::Quaterniond turn = ExpQ(Eigen::Vector3d(omega_b * t.dt_s));
  t.lever_arm_b = turn * gnss.p_b_g;
  t.baseline_b = turn * gnss.baseline_b;
  t.R_n_w = earth.LocalLevel(fix.p_w).transpose();
  t.sigma_enu_m = fix.sigma_enu_m * sigma_scale;
  return t;
}

std::unique_ptr<ceres::CostFunction> GnssPositionCost(const GnssFix& fix, const TiedFix& tied) {
  return GnssPositionFactor::Create(fix.p_w, tied.sigma_enu_m, tied.lever_arm_b, tied.dt_s,
                                    tied.R_n_w);
}

std::vector<BlockRef> GnssPositionBlocks(KeyframeId id) {
  return {{id, Slot::kQ}, {id, Slot::kP}, {id, Slot::kV}, {id, Slot::kGb}};
}

FactorId AddGnssPositionFactor(NavGraph* graph,
                               const GnssFix& fix,
                               const TiedFix& tied,
                               KeyframeId id,
                               const EstimatorConfig& config) {
  return graph->AddFactor(FactorKind::kGnssPosition, GnssPositionCost(fix, tied),
                          MakeLoss(config.gnss_loss), GnssPositionBlocks(id));
}

FactorId AddGnssHeadingFactor(NavGraph* graph,
                              const GnssFix& fix,
                              const TiedFix& tied,
                              KeyframeId id,
                              const EstimatorConfig& config) {
  return graph->AddFactor(FactorKind::kGnssHeading, GnssHeadingCost(fix, tied),
                          MakeLoss(config.heading_loss), {{id, Slot::kQ}});
}

std::unique_ptr<ceres::CostFunction> GnssHeadingCost(const GnssFix& fix, const TiedFix& tied) {
  return GnssHeadingFactor::Create(fix.heading_deg * kDegToRad,
                                   std::max(fix.sigma_heading_deg, kMinHeadingSigmaDeg) * kDegToRad,
                                   tied.baseline_b, tied.R_n_w);
}

}  // namespace skerry
