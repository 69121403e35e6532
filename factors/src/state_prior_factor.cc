#include "skerry/factors/state_prior_factor.h"

#include <Eigen/Cholesky>

namespace skerry {

StatePriorFactor::StatePriorFactor(const NavState& prior, const StateCovariance& covariance)
    : prior_(prior) {
  const Eigen::LLT<StateCovariance> llt(covariance);
  sqrt_info_ = llt.matrixL().solve(StateCovariance::Identity());
}

std::unique_ptr<ceres::CostFunction> StatePriorFactor::Create(const NavState& prior,
                                                              const StateCovariance& covariance) {
  return std::make_unique<ceres::AutoDiffCostFunction<StatePriorFactor, 15, 4, 3, 3, 3, 3>>(
      new StatePriorFactor(prior, covariance));
}

}  // namespace skerry
