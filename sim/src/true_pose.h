#pragma once
// The true body pose at any time from the simulator's truth states (private to skerry_sim): the
// camera frames and the LiDAR sweeps are rendered from it.

#include <Eigen/Geometry>
#include <algorithm>
#include <vector>

#include "skerry/core/nav_state.h"

namespace skerry::sim {

/// T_w_b at t: the truth states interpolated (position linearly, rotation by slerp). The truth
/// is smooth and sampled at 50 Hz, so the interpolation error is far below a millimetre
/// (a * dt^2 / 8 = 1.3e-5 m at 0.26 m/s^2). False after the last truth state.
inline bool TruePose(const std::vector<NavState>& truth,
                     TimeNs t,
                     Eigen::Quaterniond* q,
                     Eigen::Vector3d* p) {
  const auto it = std::lower_bound(truth.begin(), truth.end(), t,
                                   [](const NavState& s, TimeNs v) { return s.t_ns < v; });
  if (it == truth.end()) return false;
  if (it == truth.begin() || it->t_ns == t) {
    *q = it->q_w_b;
    *p = it->p_w_b;
    return true;
  }
  const NavState& a = *(it - 1);
  const NavState& b = *it;
  const double f = static_cast<double>(t - a.t_ns) / static_cast<double>(b.t_ns - a.t_ns);
  *q = a.q_w_b.slerp(f, b.q_w_b);
  *p = (1 - f) * a.p_w_b + f * b.p_w_b;
  return true;
}

}  // namespace skerry::sim
