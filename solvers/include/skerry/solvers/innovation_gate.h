#pragma once
/// \file
/// The chi-square gate of a measurement block on one keyframe, decided before the block enters
/// the graph: the innovation of the block's whitened residual r, with its tangent Jacobian J at
/// the keyframe's current estimate (the factor's own, so the gate and the factor cannot disagree)
/// and the keyframe's predicted covariance P, has covariance S = J P J^T + I; a consistent
/// estimator gives d2 = r^T S^-1 r ~ chi-square with dim(r) degrees of freedom (Bar-Shalom, Li
/// and Kirubarajan 2001, sec. 5.4.2; the validation gate of sec. 2.6 of Bar-Shalom and
/// Fortmann 1988). Robust losses are not applied here: they act once the block is in.
///
/// In the state space (GateSpace::kState) only the projection of r on the column space of J is
/// tested: y = Q^T r with Q = J V L^-1/2 orthonormal (J^T J = V L V^T, directions whose
/// information is below 1e-9 of the largest left out), Cov y = I + L^1/2 V^T P V L^1/2, and
/// d2 = y^T (Cov y)^-1 y ~ chi-square in rank(J) degrees of freedom. |y|^2 is what a Gauss-Newton
/// step on the state alone would remove from |r|^2: the block is equivalent to a measurement of
/// the state, delta = (J^T J)^-1 J^T r with information J^T J (measurement compression: Maybeck,
/// "Stochastic Models, Estimation and Control" vol. 1, sec. 5.9), and this is that measurement's
/// gate. What no change of the state explains (a registration's misfit at the truth: edges in one
/// source and not the other) is left out, and the cost is O(dim(r)) rather than O(dim(r)^3).

#include <ceres/cost_function.h>

#include <Eigen/Core>
#include <vector>

#include "skerry/solvers/nav_graph.h"
#include "skerry/solvers/sensor_block.h"

namespace skerry {

struct Innovation {
  int dim = 0;             ///< degrees of freedom (residual size; kState: rank of J)
  double d2 = 0.0;         ///< r^T S^-1 r
  double log_det_s = 0.0;  ///< log det S, S of the whitened residual
  Eigen::VectorXd r;       ///< the whitened residual tested (kState: its projection y)
  Eigen::MatrixXd S;       ///< its covariance
};

/// `slots`: the keyframe slot of each of the cost's parameter blocks; `P`: the keyframe's
/// covariance in the graph's 18-D order. False if the cost fails or S is not positive definite.
bool BlockInnovation(const ceres::CostFunction& cost,
                     const std::vector<Slot>& slots,
                     const Keyframe& kf,
                     const GraphCovariance& P,
                     Innovation* out);

/// The same for a cost whose parameter blocks are the keyframe's `slots` followed by blocks held
/// constant at `fixed` (a sensor's extrinsic: the gate is conditional on its estimate). False as
/// above; `*evaluated` (if given) says whether the cost could be evaluated at all. The residual
/// and its Jacobian are divided by `residual_scale` first (SensorMeasurement::gate_scale: a
/// down-weighted block is tested on its own noise). `fixed_variances` (empty, or one per fixed
/// block): a fixed block of size 1 that is itself uncertain (an estimated sensor parameter) with
/// its variance > 0 enters as one more column of J beside the keyframe's with that variance,
/// S = J P J^T + v j j^T + I (its cross-covariance with the keyframe left out): a camera whose
/// map's crest offset is still the prior's 10 m is not gated as if it were known.
bool BlockInnovation(const ceres::CostFunction& cost,
                     const std::vector<Slot>& slots,
                     const std::vector<const double*>& fixed,
                     const Keyframe& kf,
                     const GraphCovariance& P,
                     Innovation* out,
                     bool* evaluated = nullptr,
                     GateSpace space = GateSpace::kResidual,
                     double residual_scale = 1.0,
                     const std::vector<double>& fixed_variances = {});

/// The projection of a whitened residual on the column space of its Jacobian (above): y in the
/// eigenbasis of J^T J, and B = V L^1/2 (columns: the kept directions), so Cov y = I + B^T P B.
struct StateSpaceProjection {
  Eigen::VectorXd y;
  Eigen::MatrixXd B;
};
StateSpaceProjection ProjectOnState(const Eigen::VectorXd& r, const Eigen::MatrixXd& J);

}  // namespace skerry
