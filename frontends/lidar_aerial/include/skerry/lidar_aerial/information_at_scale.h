#pragma once
/// \file
/// A scan block's information along its weakest horizontal direction, as the cost itself has it
/// over a metre rather than as its local curvature says, and the block that keeps only that much.
///
/// A block's Gauss-Newton information J^T J adds up the distance field's gradient at each point.
/// Along a straight breakwater or a row of parallel quays, the points' gradients along the quay
/// come from texture finer than the map's edges are sharp (the photo's blur, rock, fenders): the
/// local curvature claims decimetres where the cost, walked a metre either way, barely rises. On
/// the simulated harbour's runs the cost's rise over +-1 m is 0.6 of the local curvature in the
/// median but under 0.05 of it for the scans along the breakwater (bench/harbour_scan_fixes.cc,
/// columns secant_*). A window that believes the curvature holds a wrong position along the
/// quay as though it knew it (docs/results.md, "Information at the map's scale").
///
/// The remedy is Zhang, Kaess and Singh's (2016, "On degeneracy of optimization-based state
/// estimation problems", ICRA: in directions the problem does not constrain, do not let the
/// measurement move the solution), with the direction's share measured on the cost: the block
/// sees the position along the weak direction shrunk towards its own minimum, so its information
/// there is the share `keep` of its local curvature and elsewhere unchanged.

#include <ceres/cost_function.h>

#include <Eigen/Core>
#include <memory>
#include <optional>

#include "skerry/core/nav_state.h"

namespace skerry::lidar_aerial {

/// The weakest horizontal direction of a block on (q_w_b, p_w_b, v_w) at a state.
struct WeakDirection {
  Eigen::Vector2d direction = Eigen::Vector2d::UnitX();  ///< ENU, unit
  /// w^T J_p^T J_p w: the local (Gauss-Newton) information along it, f(s) - f(0) ~ local s^2
  /// for the cost f = |r|^2 moved by s along it.
  double local = 0.0;
  /// The same from the cost over +-scale: (f(s) + f(-s) - 2 f(0)) / (2 s^2).
  double at_scale = 0.0;
  /// at_scale / local clamped to [0, 1]: the share of the local information the cost bears out.
  double keep = 1.0;
  /// Smallest over largest eigenvalue of the horizontal information, the smallest one taken as
  /// local * keep.
  double constraint_ratio = 0.0;
};

/// Measures `cost`'s weakest horizontal direction at `at` (normally the block's own minimum,
/// PlanarMinimum) over +-scale_m. nullopt when the cost cannot be evaluated there or has no
/// horizontal information.
std::optional<WeakDirection> MeasureWeakDirection(const ceres::CostFunction& cost,
                                                  const NavState& at,
                                                  double scale_m);

/// `cost` with its information along the horizontal unit direction `w` scaled by `keep` in
/// [0, 1]: it is evaluated at p0 + P (p - p0), P = I - (1 - sqrt(keep)) w w^T, so its
/// information on p is P J^T J P: keep times the local one along w, unchanged across it. Its
/// Jacobians on q, v and any blocks after them (a calibrated mounting's) are the inner ones at
/// the remapped position. keep >= 1 returns `cost`.
std::shared_ptr<ceres::CostFunction> KeepAlong(std::shared_ptr<ceres::CostFunction> cost,
                                               const Eigen::Vector3d& p0,
                                               const Eigen::Vector2d& w,
                                               double keep);

}  // namespace skerry::lidar_aerial
