// The crucial simulator property: integrating the ideal (noise-free, bias-free) IMU reproduces the
// true trajectory. Every estimator test is validated against this, so a wrong lever-arm term, a
// frame mix-up or a gravity sign in the simulator shows up here first.
//
// The integration is the strapdown mechanisation in the Earth-fixed world frame w with the
// estimator's Earth model (core/earth_model.h: gravity from GeographicLib's normal potential in
// ECEF, the Earth's rate in w), while the simulator builds its IMU from the navigation-frame
// formulation (sim/earth_motion.h: latitude and longitude integrated, transport rate, normal
// gravity along the local vertical). Two formulations of one physics: agreement to micrometres
// checks both.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "sim/sim_test_util.h"
#include "skerry/core/earth_model.h"
#include "skerry/core/so3.h"
#include "skerry/sim/earth_motion.h"
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

// dR/dt = R [omega_ib]x - [W]x R,  dv/dt = R f + g(p) - 2 W x v,  dp/dt = v (earth_model.h).
ImuPointState Derivative(const ImuPointState& y, const ImuSample& s, const EarthModel& earth) {
  const Eigen::Quaterniond q(y.q[3], y.q[0], y.q[1], y.q[2]);
  const Eigen::Vector3d& W = earth.omega_ie_w();
  const Eigen::Quaterniond omega(0.0, s.gyro_rad_s.x(), s.gyro_rad_s.y(), s.gyro_rad_s.z());
  const Eigen::Quaterniond earth_rate(0.0, W.x(), W.y(), W.z());
  ImuPointState d;
  d.q = 0.5 * ((q * omega).coeffs() - (earth_rate * q).coeffs());
  d.p = y.v;
  d.v = q.normalized() * s.accel_m_s2 + earth.Gravity(y.p) - 2.0 * W.cross(y.v);
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
  const VesselMotion vessel(config.trajectory, config.waves, config.duration_s, seed);
  const EarthMotion motion(vessel, config.origin, config.earth, config.duration_s);
  const EarthModel earth = ds.Earth();
  const Eigen::Quaterniond q_b_i = ds.imu.q_b_i;
  const Eigen::Vector3d p_b_i = ds.imu.p_b_i;

  const auto k0 = static_cast<std::size_t>(std::llround(t0_s * ds.imu.rate_hz));
  const auto steps = static_cast<std::size_t>(std::llround(span_s * ds.imu.rate_hz / 2.0));
  const double h = 2.0 / ds.imu.rate_hz;

  // Initial IMU-point state from the truth.
  const BodyKinematics kin0 = motion.At(NsToSeconds(ds.imu_samples[k0].t_ns)).body;
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
    const ImuPointState d1 = Derivative(y, s0, earth);
    const ImuPointState d2 = Derivative(Add(y, d1, h / 2), s1, earth);
    const ImuPointState d3 = Derivative(Add(y, d2, h / 2), s1, earth);
    const ImuPointState d4 = Derivative(Add(y, d3, h), s2, earth);
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
    // The ideal gyro reads the rate relative to inertial space; the lever arm moves with the
    // rate relative to the Earth.
    const Eigen::Vector3d omega_b = q_b_i * s2.gyro_rad_s - q_w_b.conjugate() * earth.omega_ie_w();
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

// 25 km from the origin, where the vertical is tilted by 4 mrad and the surface lies 50 m below
// the tangent plane, on a course that changes latitude and longitude: the round-Earth terms of
// the simulator (transport rate, the vessel following the ellipsoid) against the Earth-fixed
// mechanisation with the estimator's gravity.
TEST(ImuConsistency, IdealImuReproducesAHarbourFarFromTheOrigin) {
  ScenarioConfig c = ShortHarbour(101.0);
  c.trajectory.start_enu_m = Eigen::Vector3d(-15000.0, 20000.0, 0.0);
  const IntegrationErrors e = IntegrateWindow(c, 0.0, 100.0);
  std::printf(
      "harbour 25 km out, 0-100 s: max position error %.3g m, attitude %.3g deg, "
      "velocity %.3g m/s\n",
      e.max_position_m, e.max_attitude_deg, e.max_velocity_m_s);
  EXPECT_LT(e.max_position_m, 1e-4);
  EXPECT_LT(e.max_attitude_deg, 1e-6);
  EXPECT_LT(e.max_velocity_m_s, 1e-5);
}

// The flat world is still there (earth: flat) and still consistent.
TEST(ImuConsistency, IdealImuReproducesTheFlatWorld) {
  ScenarioConfig c = ShortHarbour(61.0);
  c.earth.kind = EarthKind::kFlat;
  const IntegrationErrors e = IntegrateWindow(c, 0.0, 60.0);
  EXPECT_LT(e.max_position_m, 1e-4);
  EXPECT_LT(e.max_attitude_deg, 1e-6);
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
