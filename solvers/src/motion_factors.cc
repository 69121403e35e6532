#include "skerry/solvers/motion_factors.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "skerry/factors/bias_random_walk_factor.h"
#include "skerry/factors/gnss_drift_factor.h"
#include "skerry/factors/imu_factor.h"
#include "skerry/factors/linear_prior_factor.h"

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
  std::vector<BlockRef> blocks = {{prev, Slot::kQ},  {prev, Slot::kP},  {prev, Slot::kV},
                                  {prev, Slot::kBg}, {prev, Slot::kBa}, {next, Slot::kQ},
                                  {next, Slot::kP},  {next, Slot::kV}};
  if (graph->has_imu_calibration()) {
    if (pim.gyro_calibration() == nullptr) {
      throw std::logic_error(
          "AddMotionFactors: the graph calibrates the gyro, the preintegration "
          "has no calibration Jacobians");
    }
    blocks.push_back(ImuCalibrationBlock());
    graph->AddFactor(FactorKind::kImu,
                     ImuFactor::CreateCalibrated(pim, imu, gyro_prev, gyro_next, earth), nullptr,
                     blocks);
  } else {
    graph->AddFactor(FactorKind::kImu, ImuFactor::Create(pim, imu, gyro_prev, gyro_next, earth),
                     nullptr, blocks);
  }
  graph->AddFactor(FactorKind::kBiasRandomWalk,
                   std::make_unique<BiasRandomWalkFactor>(imu.noise, dt_s), nullptr,
                   {{prev, Slot::kBg}, {prev, Slot::kBa}, {next, Slot::kBg}, {next, Slot::kBa}});
  if (!drift.enabled()) return -1;
  return graph->AddFactor(FactorKind::kGnssDrift, std::make_unique<GnssDriftFactor>(drift, dt_s),
                          nullptr, {{prev, Slot::kGb}, {next, Slot::kGb}});
}

void AddImuCalibration(NavGraph* graph,
                       const ImuConfig& imu,
                       const ImuCalibration* current,
                       const Eigen::Matrix<double, 9, 9>* covariance) {
  // A Gaussian prior r = L^-1 (e - e0), L L^T its covariance, as AddSensorExtrinsic's: what an
  // old graph learnt when its covariance is usable, else the datasheet's.
  using Vector9 = Eigen::Matrix<double, 9, 1>;
  std::unique_ptr<LinearPriorFactor> prior;
  Vector9 x0 = Vector9::Zero();
  if (current != nullptr && covariance != nullptr) {
    x0 = Eigen::Map<const Vector9>(current->value);
    prior = LinearPriorFactor::FromCovariance({9}, {Eigen::VectorXd(x0)}, *covariance);
  }
  if (prior == nullptr) {
    x0.setZero();
    Eigen::Matrix<double, 9, 9> C = Eigen::Matrix<double, 9, 9>::Zero();
    for (int k = 0; k < 9; ++k) {  // E(r, c) at 3 c + r: the diagonal holds the scale factors
      const double sigma = k % 3 == k / 3 ? imu.gyro_scale_factor_sigma_ppm * 1e-6
                                          : imu.gyro_misalignment_sigma_mrad * 1e-3;
      C(k, k) = std::pow(std::max(sigma, 1e-9), 2);
    }
    prior = LinearPriorFactor::FromCovariance({9}, {Eigen::VectorXd(x0)}, C);
  }
  graph->AddImuCalibration(x0);
  graph->AddFactor(FactorKind::kExtrinsicPrior, std::move(prior), nullptr, {ImuCalibrationBlock()});
}

}  // namespace skerry
