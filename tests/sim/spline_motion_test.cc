// The twin's truth through estimated states (spline_motion.h): it passes through the states, its
// closed-form derivatives agree with finite differences of the curve itself, it stays close to
// the smooth motion the states were sampled from, and bad states are refused.

#include "skerry/sim/spline_motion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "sim/sim_test_util.h"
#include "skerry/core/so3.h"

namespace skerry::sim {
namespace {

// The states of the built-in harbour scenario's motion (turns, speed changes, waves) at `rate`.
std::vector<NavState> SampledStates(const VesselMotion& m, double duration_s, double rate_hz) {
  std::vector<NavState> states;
  for (int k = 0; k <= static_cast<int>(duration_s * rate_hz); ++k) {
    const BodyKinematics kin = m.At(k / rate_hz);
    NavState s;
    s.t_ns = SecondsToNs(k / rate_hz) + 1'400'000'000'000'000'000LL;  // EuRoC-sized stamps
    s.p_w_b = kin.p_w_b;
    s.q_w_b = kin.q_w_b;
    s.v_w = kin.v_w;
    s.bg = Eigen::Vector3d::Constant(1e-3 * k);
    states.push_back(s);
  }
  return states;
}

TEST(SplineMotion, PassesThroughTheStatesAndNearTheMotionBetweenThem) {
  const ScenarioConfig c = testing::SourceScenario("harbour");
  const VesselMotion m(c.trajectory, c.waves, 300.0, 5);
  const std::vector<NavState> states = SampledStates(m, 300.0, 10.0);
  const SplineMotion spline(states);
  EXPECT_NEAR(spline.knot_s(), 0.1, 1e-9);
  for (const NavState& s : states) {
    const BodyKinematics k = spline.At(s.t_ns);
    ASSERT_LT((k.p_w_b - s.p_w_b).norm(), 1e-9);
    ASSERT_LT(LogQ(Eigen::Quaterniond(k.q_w_b.conjugate() * s.q_w_b)).norm(), 1e-9);
  }
  // Between the states: within a millimetre and a hundredth of a degree of the motion they were
  // sampled from, velocity within 1 cm/s, angular rate within 0.1 deg/s (waves of 4-8 s).
  double worst_p = 0, worst_r = 0, worst_v = 0, worst_w = 0;
  for (double t = 0.5; t < 299.5; t += 0.0137) {
    const BodyKinematics truth = m.At(t);
    const BodyKinematics k = spline.At(states.front().t_ns + SecondsToNs(t));
    worst_p = std::max(worst_p, (k.p_w_b - truth.p_w_b).norm());
    worst_r = std::max(worst_r, LogQ(Eigen::Quaterniond(k.q_w_b.conjugate() * truth.q_w_b)).norm());
    worst_v = std::max(worst_v, (k.v_w - truth.v_w).norm());
    worst_w = std::max(worst_w, (k.omega_b - truth.omega_b).norm());
  }
  EXPECT_LT(worst_p, 1e-3);
  EXPECT_LT(worst_r, 1e-2 * M_PI / 180.0);
  EXPECT_LT(worst_v, 1e-2);
  EXPECT_LT(worst_w, 0.1 * M_PI / 180.0);
  // Biases are interpolated linearly.
  EXPECT_NEAR(spline.StateAt(states[10].t_ns + SecondsToNs(0.05)).bg.x(), 10.5e-3, 1e-12);
}

TEST(SplineMotion, DerivativesMatchCentralDifferencesOfTheCurve) {
  // Uneven state spacing (a keyframe policy's), knots every 0.2 s: the derivatives are the
  // curve's own everywhere, across knots included.
  const ScenarioConfig c = testing::SourceScenario("harbour");
  const VesselMotion m(c.trajectory, c.waves, 120.0, 2);
  std::vector<NavState> states = SampledStates(m, 120.0, 10.0);
  for (size_t i = 1; i + 1 < states.size(); i += 3) {
    states[i].t_ns += SecondsToNs(0.031);
    const BodyKinematics kin = m.At(NsToSeconds(states[i].t_ns - states.front().t_ns));
    states[i].p_w_b = kin.p_w_b;
    states[i].q_w_b = kin.q_w_b;
    states[i].v_w = kin.v_w;
  }
  const SplineMotion spline(states, 0.2);
  const TimeNs h = 10'000;  // 10 us
  const double hs = NsToSeconds(h);
  for (double t = 0.3; t < 119.7; t += 0.0911) {
    const TimeNs tn = states.front().t_ns + SecondsToNs(t);
    const BodyKinematics k = spline.At(tn);
    const BodyKinematics kp = spline.At(tn + h);
    const BodyKinematics km = spline.At(tn - h);
    const Eigen::Vector3d v_fd = (kp.p_w_b - km.p_w_b) / (2 * hs);
    const Eigen::Vector3d a_fd = (kp.v_w - km.v_w) / (2 * hs);
    const Eigen::Vector3d w_fd =
        LogQ(Eigen::Quaterniond(km.q_w_b.conjugate() * kp.q_w_b)) / (2 * hs);
    const Eigen::Vector3d alpha_fd = (kp.omega_b - km.omega_b) / (2 * hs);
    ASSERT_LT((v_fd - k.v_w).norm(), 1e-5 * (1 + k.v_w.norm())) << "t=" << t;
    ASSERT_LT((a_fd - k.a_w).norm(), 1e-4) << "t=" << t;
    ASSERT_LT((w_fd - k.omega_b).norm(), 1e-6) << "t=" << t;
    ASSERT_LT((alpha_fd - k.alpha_b).norm(), 1e-4) << "t=" << t;
  }
}

TEST(SplineMotion, RefusesStatesItCannotPassThrough) {
  NavState a, b;
  b.t_ns = 100'000'000;
  EXPECT_THROW(SplineMotion({a}), std::invalid_argument);
  EXPECT_THROW(SplineMotion({b, a}), std::invalid_argument);
  NavState nan = b;
  nan.p_w_b.x() = std::nan("");
  EXPECT_THROW(SplineMotion({a, nan}), std::invalid_argument);
  EXPECT_THROW(SplineMotion({a, b}, -1.0), std::invalid_argument);
  EXPECT_NO_THROW(SplineMotion({a, b}));
}

}  // namespace
}  // namespace skerry::sim
