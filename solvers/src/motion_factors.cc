#include "skerry/solvers/motion_factors.h"

#include "skerry/factors/bias_random_walk_factor.h"
#include "skerry/factors/gnss_drift_factor.h"
#include "skerry/factors/imu_factor.h"

namespace skerry {

FactorId AddMotionFactors(NavGraph* graph,
                          KeyframeId prev,
                          KeyframeId next,
                          const ImuPreintegration& pim,
                          const ImuConfig& imu,
                          const Eigen::Vector3d& gyro_prev,
                          const Eigen::Vector3d& gyro_next,
                          const ImuEarthTerms& earth,
                          const GnssDriftParams& drift) {
  const double dt_s = pim.deltas().dt_s;
  graph->AddFactor(FactorKind::kImu, ImuFactor::Create(pim, imu, gyro_prev, gyro_next, earth),
                   nullptr,
                   {{prev, Slot::kQ},
                    {prev, Slot::kP},
                    {prev, Slot::kV},
                    {prev, Slot::kBg},
                    {prev, Slot::kBa},
                    {next, Slot::kQ},
                    {next, Slot::kP},
                    {next, Slot::kV}});
  graph->AddFactor(FactorKind::kBiasRandomWalk,
                   std::make_unique<BiasRandomWalkFactor>(imu.noise, dt_s), nullptr,
                   {{prev, Slot::kBg}, {prev, Slot::kBa}, {next, Slot::kBg}, {next, Slot::kBa}});
  if (!drift.enabled()) return -1;
  return graph->AddFactor(FactorKind::kGnssDrift, std::make_unique<GnssDriftFactor>(drift, dt_s),
                          nullptr, {{prev, Slot::kGb}, {next, Slot::kGb}});
}

}  // namespace skerry
