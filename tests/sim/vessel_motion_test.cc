// The true motion: its closed-form derivatives agree with finite differences, manoeuvres turn by
// the configured angles, and waves have the configured amplitudes.

#include "skerry/sim/vessel_motion.h"

#include <gtest/gtest.h>

#include <cmath>

#include "sim/sim_test_util.h"
#include "skerry/core/heading.h"
#include "skerry/core/so3.h"

namespace skerry::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegToRad = kPi / 180.0;

TEST(VesselMotion, DerivativesMatchCentralDifferences) {
  const ScenarioConfig c = testing::SourceScenario("harbour");
  const VesselMotion m(c.trajectory, c.waves, c.duration_s, 5);
  const double h = 1e-4;
  // Times inside straights, ramps, steady turns, speed changes and at leg junctions.
  for (double t = 1.0; t < 599.0; t += 0.737) {
    const BodyKinematics k = m.At(t);
    const BodyKinematics kp = m.At(t + h);
    const BodyKinematics km = m.At(t - h);
    const Eigen::Vector3d v_fd = (kp.p_w_b - km.p_w_b) / (2 * h);
    const Eigen::Vector3d a_fd = (kp.v_w - km.v_w) / (2 * h);
    const Eigen::Vector3d w_fd =
        LogQ(Eigen::Quaterniond(km.q_w_b.conjugate() * kp.q_w_b)) / (2 * h);
    const Eigen::Vector3d alpha_fd = (kp.omega_b - km.omega_b) / (2 * h);
    ASSERT_LT((v_fd - k.v_w).norm(), 1e-6) << "t=" << t;
    ASSERT_LT((a_fd - k.a_w).norm(), 1e-6) << "t=" << t;
    ASSERT_LT((w_fd - k.omega_b).norm(), 1e-7) << "t=" << t;
    ASSERT_LT((alpha_fd - k.alpha_b).norm(), 1e-6) << "t=" << t;
  }
}

TEST(VesselMotion, TurnsByTheConfiguredAngles) {
  TrajectorySpec spec;
  spec.start_heading_deg = 10.0;
  spec.start_speed_m_s = 4.0;
  spec.turn_ramp_s = 3.0;
  Leg straight;
  straight.duration_s = 10.0;
  Leg turn;
  turn.type = Leg::Type::kTurn;
  turn.angle_deg = 180.0;
  turn.rate_deg_s = 3.0;
  Leg small_turn = turn;  // too short to reach the rate: ramps only
  small_turn.angle_deg = -5.0;
  Leg slow;
  slow.type = Leg::Type::kSpeedChange;
  slow.to_m_s = 2.0;
  slow.accel_m_s2 = 0.5;
  spec.legs = {straight, turn, straight, small_turn, slow};
  const VesselMotion m(spec, WaveSpec(), 200.0, 1);
  EXPECT_NEAR(HeadingDeg(m.At(0.0).q_w_b), 10.0, 1e-9);
  EXPECT_NEAR(HeadingDeg(m.At(9.9).q_w_b), 10.0, 1e-9);
  // 180 deg at 3 deg/s with 3 s ramps: 57 s of steady turn plus two ramps = 63 s.
  EXPECT_NEAR(m.At(10.0 + 3.0 + 28.5).omega_b.z(), -3.0 * kDegToRad, 1e-12);
  EXPECT_NEAR(HeadingDeg(m.At(73.0).q_w_b), 190.0, 1e-9);
  EXPECT_NEAR(m.At(73.0).omega_b.z(), 0.0, 1e-12);
  // The small turn: 5 deg in two 3 s ramps at 5/3 deg/s peak.
  EXPECT_NEAR(HeadingDeg(m.At(83.0 + 6.0).q_w_b), 185.0, 1e-9);
  // Speed change 4 -> 2 m/s at a mean 0.5 m/s^2 takes 4 s.
  EXPECT_NEAR(m.At(89.0 + 4.0).speed_m_s, 2.0, 1e-12);
  EXPECT_NEAR(m.At(89.0 + 2.0).a_w.norm(), 1.0, 1e-9);  // peak = twice the mean
  EXPECT_NEAR(m.At(150.0).v_w.norm(), 2.0, 1e-12);
}

TEST(VesselMotion, CurrentMakesCourseDifferFromHeading) {
  TrajectorySpec spec;
  spec.start_heading_deg = 0.0;  // north
  spec.start_speed_m_s = 3.0;
  spec.current_enu_m_s = Eigen::Vector2d(1.0, 0.0);
  const VesselMotion m(spec, WaveSpec(), 100.0, 1);
  const BodyKinematics k = m.At(50.0);
  EXPECT_NEAR(HeadingDeg(k.q_w_b), 0.0, 1e-9);
  EXPECT_NEAR(k.p_w_b.x(), 50.0, 1e-6);
  EXPECT_NEAR(k.p_w_b.y(), 150.0, 1e-6);
}

TEST(VesselMotion, SingleWaveHasTheConfiguredAmplitudeAndPeriod) {
  WaveSpec waves;
  waves.roll_deg = {{2.0, 7.0}};
  waves.pitch_deg = {{0.5, 3.0}};
  waves.heave_m = {{0.4, 5.0}};
  TrajectorySpec spec;
  const VesselMotion m(spec, waves, 700.0, 9);
  double max_roll = 0.0, max_pitch = 0.0, max_heave = 0.0;
  int roll_upcrossings = 0;
  double prev_roll = m.At(0.0).roll_rad;
  for (double t = 0.01; t < 700.0; t += 0.01) {
    const BodyKinematics k = m.At(t);
    max_roll = std::max(max_roll, std::abs(k.roll_rad));
    max_pitch = std::max(max_pitch, std::abs(k.pitch_rad));
    max_heave = std::max(max_heave, std::abs(k.p_w_b.z()));
    roll_upcrossings += (prev_roll < 0.0 && k.roll_rad >= 0.0);
    prev_roll = k.roll_rad;
  }
  EXPECT_NEAR(max_roll / kDegToRad, 2.0, 1e-3);
  EXPECT_NEAR(max_pitch / kDegToRad, 0.5, 1e-3);
  EXPECT_NEAR(max_heave, 0.4, 1e-4);
  EXPECT_NEAR(roll_upcrossings, 100, 1);  // 700 s / 7 s
}

TEST(VesselMotion, HarbourSeaStateStdMatchesTheSumOfSinusoids) {
  // A sum of sinusoids with amplitudes a_k has std sqrt(sum a_k^2 / 2) over a long window.
  const ScenarioConfig c = testing::SourceScenario("harbour");
  TrajectorySpec straight;  // no turns: no heel
  const VesselMotion m(straight, c.waves, 3600.0, 2);
  double sum_roll2 = 0.0, sum_pitch2 = 0.0;
  int n = 0;
  for (double t = 0.0; t < 3600.0; t += 0.05, ++n) {
    const BodyKinematics k = m.At(t);
    sum_roll2 += k.roll_rad * k.roll_rad;
    sum_pitch2 += k.pitch_rad * k.pitch_rad;
  }
  auto expected_std = [](const std::vector<WaveComponent>& w) {
    double s = 0.0;
    for (const WaveComponent& c : w) s += c.amplitude * c.amplitude / 2.0;
    return std::sqrt(s);
  };
  EXPECT_NEAR(std::sqrt(sum_roll2 / n) / kDegToRad, expected_std(c.waves.roll_deg),
              0.05 * expected_std(c.waves.roll_deg));
  EXPECT_NEAR(std::sqrt(sum_pitch2 / n) / kDegToRad, expected_std(c.waves.pitch_deg),
              0.05 * expected_std(c.waves.pitch_deg));
}

TEST(VesselMotion, HeelsOutwardInTurns) {
  TrajectorySpec spec;
  spec.start_speed_m_s = 5.0;
  spec.heel_deg_per_m_s2 = 2.0;
  Leg turn;
  turn.type = Leg::Type::kTurn;
  turn.angle_deg = -90.0;  // to port: left turn, centripetal acceleration to +y
  turn.rate_deg_s = 3.0;
  spec.legs = {turn};
  const VesselMotion m(spec, WaveSpec(), 100.0, 1);
  const BodyKinematics k = m.At(15.0);  // steady part
  const double a_centripetal = 5.0 * 3.0 * kDegToRad;
  EXPECT_NEAR(k.roll_rad, 2.0 * kDegToRad * a_centripetal, 1e-12);  // starboard down
  EXPECT_GT(k.roll_rad, 0.0);
}

}  // namespace
}  // namespace skerry::sim
