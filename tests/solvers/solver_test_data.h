#pragma once
/// \file
/// Data for the solver tests. Tests of the estimator's correctness (accuracy at what the data
/// allow, consistency of its covariance, the gate's decisions) run in the world of its own model:
/// the built-in scenario with every error the model lacks switched off and the GNSS drift it
/// assumes (sim::MatchedToEstimator). Tests of robustness run on the scenario as it is, with a
/// real receiver's and IMU's errors (docs/simulator.md).

#include <string>

#include "skerry/io/dataset.h"
#include "skerry/io/trajectory.h"
#include "skerry/sim/scenario.h"
#include "skerry/sim/simulator.h"
#include "skerry/solvers/estimator_config.h"

namespace skerry::test {

inline sim::DriftModel DriftOf(const EstimatorConfig& config) {
  return {config.gnss_drift.sigma_horizontal_m, config.gnss_drift.sigma_vertical_m,
          config.gnss_drift.tau_s};
}

/// A built-in scenario matched to an estimator configuration (default: the `default` preset).
inline sim::ScenarioConfig MatchedScenario(const std::string& name,
                                           const EstimatorConfig& config = LoadPreset("default")) {
  return sim::MatchedToEstimator(sim::LoadScenario(name), DriftOf(config));
}

inline Dataset MatchedHarbour(std::uint64_t seed) {
  return sim::Simulate(MatchedScenario("harbour"), seed);
}

/// The true state at any time, interpolated from truth_states (linear in p, v and the biases,
/// slerp in q): the fixes and keyframes of a dataset are not on its 50 Hz truth grid.
inline bool TruthStateAt(const Dataset& data, TimeNs t_ns, NavState* out) {
  const std::vector<NavState>& s = data.truth_states;
  auto it = std::lower_bound(s.begin(), s.end(), t_ns,
                             [](const NavState& x, TimeNs t) { return x.t_ns < t; });
  if (it == s.end()) return false;
  if (it->t_ns == t_ns) {
    *out = *it;
    return true;
  }
  if (it == s.begin()) return false;
  const NavState& a = *std::prev(it);
  const NavState& b = *it;
  const double f = static_cast<double>(t_ns - a.t_ns) / static_cast<double>(b.t_ns - a.t_ns);
  out->t_ns = t_ns;
  out->q_w_b = a.q_w_b.slerp(f, b.q_w_b);
  out->p_w_b = a.p_w_b + f * (b.p_w_b - a.p_w_b);
  out->v_w = a.v_w + f * (b.v_w - a.v_w);
  out->bg = a.bg + f * (b.bg - a.bg);
  out->ba = a.ba + f * (b.ba - a.ba);
  return true;
}

}  // namespace skerry::test
