// The crucial simulator property: integrating the ideal (noise-free, bias-free) IMU reproduces the
// true trajectory. Every estimator test is validated against this, so a wrong lever-arm term, a
// frame mix-up or a gravity sign in the simulator shows up here first.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "sim/sim_test_util.h"
#include "skerry/core/so3.h"
#include "skerry/sim/simulator.h"
#include "skerry/sim/vessel_motion.h"

namespace skerry::sim {
namespace {

constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;

// State of the IMU point: attitude as quaternion coefficients (x, y, z, w), position, velocity.
struct ImuPointState {
  Eigen::Vector4d q;
  Eigen::Vector3d p;
  Eigen::Vector3d v;
};

ImuPointState Derivative(const ImuPointState& y, const ImuSample& s, const Eigen::Vector3d& g_w) {
  const Eigen::Quaterniond q(y.q[3], y.q[0], y.q[1], y.q[2]);
  // dq/dt = 1/2 q (x) (0, omega)
  const Eigen::Quaterniond omega(0.0, s.gyro_rad_s.x(), s.gyro_rad_s.y(), s.gyro_rad_s.z());
  Eigen::Quaterniond dq = q * omega;
  ImuPointState d;
  d.q = 0.5 * dq.coeffs();
  d.p = y.v;
  d.v = q.normalized() * s.accel_m_s2 + g_w;
  return d;
}

ImuPointState Add(const ImuPointState& y, const ImuPointState& d, double h) {
  return {y.q + h * d.q, y.p + h * d.p, y.v + h * d.v};
}

struct IntegrationErrors {
  double max_position_m = 0.0;
  double max_attitude_deg = 0.0;
  double max_velocity_m_s = 0.0;
  int compared = 0;
};

// Integrates the ideal IMU from t0_s for span_s with classic RK4 on steps of two IMU intervals
// (the middle sample is the RK4 midpoint) and compares with the dataset's ground truth.
IntegrationErrors IntegrateWindow(const ScenarioConfig& config, double t0_s, double span_s) {
  const std::uint64_t seed = 3;
  const Dataset ds = Simulate(config, seed);
  const VesselMotion motion(config.trajectory, config.waves, config.duration_s, seed);
  const Eigen::Quaterniond q_b_i = ds.imu.q_b_i;
  const Eigen::Vector3d p_b_i = ds.imu.p_b_i;
  const Eigen::Vector3d g_w(0.0, 0.0, -ds.imu.gravity_m_s2);

  const auto k0 = static_cast<std::size_t>(std::llround(t0_s * ds.imu.rate_hz));
  const auto steps = static_cast<std::size_t>(std::llround(span_s * ds.imu.rate_hz / 2.0));
  const double h = 2.0 / ds.imu.rate_hz;

  // Initial IMU-point state from the truth.
  const BodyKinematics kin0 = motion.At(NsToSeconds(ds.imu_samples[k0].t_ns));
  const Eigen::Quaterniond q_w_i0 = kin0.q_w_b * q_b_i;
  ImuPointState y{q_w_i0.coeffs(), kin0.p_w_b + kin0.q_w_b * p_b_i,
                  kin0.v_w + kin0.q_w_b * kin0.omega_b.cross(p_b_i)};

  IntegrationErrors err;
  std::size_t gt = 0;
  for (std::size_t n = 0; n < steps; ++n) {
    const std::size_t k = k0 + 2 * n;
    const ImuSample& s0 = ds.imu_samples[k];
    const ImuSample& s1 = ds.imu_samples[k + 1];
    const ImuSample& s2 = ds.imu_samples[k + 2];
    const ImuPointState d1 = Derivative(y, s0, g_w);
    const ImuPointState d2 = Derivative(Add(y, d1, h / 2), s1, g_w);
    const ImuPointState d3 = Derivative(Add(y, d2, h / 2), s1, g_w);
    const ImuPointState d4 = Derivative(Add(y, d3, h), s2, g_w);
    y.q += h / 6.0 * (d1.q + 2.0 * d2.q + 2.0 * d3.q + d4.q);
    y.p += h / 6.0 * (d1.p + 2.0 * d2.p + 2.0 * d3.p + d4.p);
    y.v += h / 6.0 * (d1.v + 2.0 * d2.v + 2.0 * d3.v + d4.v);
    y.q.normalize();

    // Compare with the ground truth sample at this time, if there is one.
    const TimeNs t_ns = s2.t_ns;
    while (gt < ds.groundtruth.size() && ds.groundtruth[gt].t_ns < t_ns) ++gt;
    if (gt == ds.groundtruth.size() || ds.groundtruth[gt].t_ns != t_ns) continue;
    const Eigen::Quaterniond q_w_i(y.q[3], y.q[0], y.q[1], y.q[2]);
    const Eigen::Quaterniond q_w_b = q_w_i * q_b_i.conjugate();
    const Eigen::Vector3d p_w_b = y.p - q_w_b * p_b_i;
    const StampedPose& truth = ds.groundtruth[gt];
    const Eigen::Vector3d omega_b = q_b_i * s2.gyro_rad_s;  // ideal gyro = true rate
    const Eigen::Vector3d v_w_b = y.v - q_w_b * omega_b.cross(p_b_i);
    err.max_position_m = std::max(err.max_position_m, (p_w_b - truth.p_w_b).norm());
    err.max_attitude_deg =
        std::max(err.max_attitude_deg,
                 LogQ(Eigen::Quaterniond(truth.q_w_b.conjugate() * q_w_b)).norm() * kRadToDeg);
    err.max_velocity_m_s = std::max(err.max_velocity_m_s, (v_w_b - ds.truth_states[gt].v_w).norm());
    ++err.compared;
  }
  return err;
}

ScenarioConfig ShortHarbour(double duration_s) {
  ScenarioConfig c = testing::Perfect(testing::SourceScenario("harbour"));
  c.duration_s = duration_s;
  return c;
}

TEST(ImuConsistency, IdealImuReproducesHarbourStartWithFirstTurn) {
  // 0..60 s: the straight start and the first 90 deg turn with its ramps, waves, heel, and the
  // harbour IMU's 90 deg mounting rotation and 1.3 m lever arm.
  const IntegrationErrors e = IntegrateWindow(ShortHarbour(61.0), 0.0, 60.0);
  std::printf("harbour 0-60 s: max position error %.3g m, attitude %.3g deg, velocity %.3g m/s\n",
              e.max_position_m, e.max_attitude_deg, e.max_velocity_m_s);
  EXPECT_EQ(e.compared, 3000);
  EXPECT_LT(e.max_position_m, 0.05);
  EXPECT_LT(e.max_attitude_deg, 0.01);
  // What the integrator really achieves, far inside the brief's bounds.
  EXPECT_LT(e.max_position_m, 1e-4);
  EXPECT_LT(e.max_attitude_deg, 1e-6);
}

TEST(ImuConsistency, IdealImuReproducesSpeedChangesAndTheU_Turn) {
  // 100..260 s: slow-down, turn to port, speed-up and the 180 deg turn.
  const IntegrationErrors e = IntegrateWindow(ShortHarbour(261.0), 100.0, 160.0);
  std::printf(
      "harbour 100-260 s: max position error %.3g m, attitude %.3g deg, velocity %.3g m/s\n",
      e.max_position_m, e.max_attitude_deg, e.max_velocity_m_s);
  EXPECT_LT(e.max_position_m, 0.05);
  EXPECT_LT(e.max_attitude_deg, 0.01);
  EXPECT_LT(e.max_velocity_m_s, 1e-3);
}

TEST(ImuConsistency, IdealImuReproducesOpenSeaWaves) {
  // Big waves (roll 3 deg at 8 s, heave 0.6 m) are the hardest case for lever-arm terms.
  ScenarioConfig c = testing::Perfect(testing::SourceScenario("open-sea"));
  c.duration_s = 61.0;
  c.imu.p_b_i = Eigen::Vector3d(2.0, -1.0, 1.5);
  c.imu.q_b_i = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()));
  const IntegrationErrors e = IntegrateWindow(c, 0.0, 60.0);
  std::printf("open-sea 0-60 s: max position error %.3g m, attitude %.3g deg, velocity %.3g m/s\n",
              e.max_position_m, e.max_attitude_deg, e.max_velocity_m_s);
  EXPECT_LT(e.max_position_m, 0.05);
  EXPECT_LT(e.max_attitude_deg, 0.01);
}

}  // namespace
}  // namespace skerry::sim
