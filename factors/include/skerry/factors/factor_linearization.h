#pragma once
/// \file
/// Linearisation of a (robustified) residual block in skerry's tangent convention: quaternion
/// blocks (size 4, Eigen [x,y,z,w]) are perturbed on the left by a full-angle world-frame rotation
/// vector, q(theta) = Exp(theta) * q; every other block is Euclidean. This is the convention of
/// the 15-D state covariance (nav_state.h) and of LinearPriorFactor.
///
/// Robust losses are folded in with the first-order (Triggs) correction: r <- sqrt(rho') r,
/// J <- sqrt(rho') J (Triggs et al., "Bundle Adjustment - A Modern Synthesis", 2000, sec. 4.3),
/// as used for marginalisation by OKVIS and VINS-Mono.

#include <ceres/cost_function.h>
#include <ceres/loss_function.h>

#include <Eigen/Core>
#include <vector>

namespace skerry {

/// d(Exp(theta) * q)/d theta at theta = 0, ambient rows [x,y,z,w] (4x3).
Eigen::Matrix<double, 4, 3> QuaternionLeftPlusJacobian(const double* q_xyzw);

/// Tangent size of a block of ambient size `size` (4 -> 3, else size).
inline int TangentSize(int size) { return size == 4 ? 3 : size; }

struct LinearizedResidual {
  Eigen::VectorXd residual;                ///< whitened and robustified
  std::vector<Eigen::MatrixXd> jacobians;  ///< one per block, tangent columns
};

/// Evaluates `cost` with Jacobians at `jacobian_values` and the residual at `residual_values`
/// (pass the same pointers for an ordinary linearisation; different ones for first-estimate
/// Jacobians). Returns false if the cost function fails.
bool LinearizeResidual(const ceres::CostFunction& cost,
                       const ceres::LossFunction* loss,
                       const std::vector<const double*>& residual_values,
                       const std::vector<const double*>& jacobian_values,
                       LinearizedResidual* out);

}  // namespace skerry
