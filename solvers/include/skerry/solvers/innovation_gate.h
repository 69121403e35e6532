#pragma once
/// \file
/// The chi-square gate of a measurement block on one keyframe, decided before the block enters
/// the graph: the innovation of the block's whitened residual r, with its tangent Jacobian J at
/// the keyframe's current estimate (the factor's own, so the gate and the factor cannot disagree)
/// and the keyframe's predicted covariance P, has covariance S = J P J^T + I; a consistent
/// estimator gives d2 = r^T S^-1 r ~ chi-square with dim(r) degrees of freedom (Bar-Shalom, Li
/// and Kirubarajan 2001, sec. 5.4.2; the validation gate of sec. 2.6 of Bar-Shalom and
/// Fortmann 1988). Robust losses are not applied here: they act once the block is in.

#include <ceres/cost_function.h>

#include <vector>

#include "skerry/solvers/nav_graph.h"

namespace skerry {

struct Innovation {
  int dim = 0;             ///< degrees of freedom (residual size)
  double d2 = 0.0;         ///< r^T S^-1 r
  double log_det_s = 0.0;  ///< log det S, S of the whitened residual
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
/// above; `*evaluated` (if given) says whether the cost could be evaluated at all.
bool BlockInnovation(const ceres::CostFunction& cost,
                     const std::vector<Slot>& slots,
                     const std::vector<const double*>& fixed,
                     const Keyframe& kf,
                     const GraphCovariance& P,
                     Innovation* out,
                     bool* evaluated = nullptr);

}  // namespace skerry
