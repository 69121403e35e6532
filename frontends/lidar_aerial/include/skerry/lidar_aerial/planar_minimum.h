#pragma once
/// \file
/// Where one scan's block fits the map best near a state, over the planar pose only: heading
/// about the world's vertical, east and north; roll, pitch, height and velocity held. What the
/// window's blocks trim their points at (lidar_aerial.window_trim_sigmas): the scan's own fit, not
/// the prediction, so that points off an edge only because the prediction is off are kept.

#include <ceres/cost_function.h>

#include "skerry/core/nav_state.h"

namespace skerry::lidar_aerial {

/// Levenberg-Marquardt (Marquardt 1963, "An algorithm for least-squares estimation of nonlinear
/// parameters": damping on the diagonal of J^T J, tenfold up on a failed step and down on a good
/// one) on the 3 planar parameters of `cost`, a block on (q_w_b, p_w_b, v_w) such as
/// DeskewedMapAlignmentCost, from `at`. The heading turns the body about the world's z at its
/// origin: q = Exp(psi e_z) q_at, whose derivative at psi = 0 is (psi / 2 e_z) q. Returns `at`
/// with its heading and horizontal position at the minimum found (at itself when the cost cannot
/// be evaluated there).
NavState PlanarMinimum(const ceres::CostFunction& cost,
                       const NavState& at,
                       int max_iterations = 20);

}  // namespace skerry::lidar_aerial
