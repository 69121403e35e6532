// The digital twin's simulator (twin.h): along the truth of a noiseless simulated recording it
// reproduces that recording's IMU and GNSS (two independent paths: the closed-form vessel motion
// against the spline through its 50 Hz truth states); its noise, drift, latency and gross-error
// episodes are what the model says; it keeps the real stamps; it is deterministic in its seed.

#include "skerry/sim/twin.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>
#include <vector>

#include "sim/sim_test_util.h"
#include "skerry/sim/simulator.h"

namespace skerry::sim {
namespace {

Dataset NoiselessRecording(double duration_s) {
  ScenarioConfig c = testing::Perfect(testing::SourceScenario("harbour"));
  c.duration_s = duration_s;
  c.gnss.dual_antenna_enabled = true;
  c.gnss.rate_hz = 5.0;
  return Simulate(c, 3);
}

TEST(Twin, ANoiselessTwinReproducesTheRecordingItFollows) {
  const Dataset real = NoiselessRecording(180.0);
  const SplineMotion truth(real.truth_states);
  const Dataset twin = SimulateTwin(real, truth, TwinModel(), 1);
  ASSERT_EQ(twin.imu_samples.size(), real.imu_samples.size());
  ASSERT_EQ(twin.gnss_fixes.size(), real.gnss_fixes.size());
  double worst_g = 0, worst_a = 0;
  for (size_t i = 0; i < real.imu_samples.size(); ++i) {
    ASSERT_EQ(twin.imu_samples[i].t_ns, real.imu_samples[i].t_ns);
    // The spline's ends are clamped in velocity, not acceleration: two knots of transient.
    if (!truth.Covers(real.imu_samples[i].t_ns - SecondsToNs(0.05)) ||
        !truth.Covers(real.imu_samples[i].t_ns + SecondsToNs(0.05)))
      continue;
    worst_g = std::max(
        worst_g,
        (twin.imu_samples[i].gyro_rad_s - real.imu_samples[i].gyro_rad_s).cwiseAbs().maxCoeff());
    worst_a = std::max(
        worst_a,
        (twin.imu_samples[i].accel_m_s2 - real.imu_samples[i].accel_m_s2).cwiseAbs().maxCoeff());
  }
  // A consumer MEMS gyro's white noise at 200 Hz is ~1e-3 rad/s, its accelerometer's ~3e-2 m/s^2:
  // the twin's path differs from the simulator's by far less.
  EXPECT_LT(worst_g, 2e-5);
  EXPECT_LT(worst_a, 2e-3);
  double worst_p = 0, worst_h = 0;
  for (size_t i = 0; i < real.gnss_fixes.size(); ++i) {
    ASSERT_EQ(twin.gnss_fixes[i].t_ns, real.gnss_fixes[i].t_ns);
    worst_p = std::max(worst_p, (twin.gnss_fixes[i].p_w - real.gnss_fixes[i].p_w).norm());
    ASSERT_TRUE(twin.gnss_fixes[i].has_heading);
    double dh = twin.gnss_fixes[i].heading_deg - real.gnss_fixes[i].heading_deg;
    dh = std::remainder(dh, 360.0);
    worst_h = std::max(worst_h, std::abs(dh));
    EXPECT_EQ(twin.gnss_fixes[i].sigma_enu_m, real.gnss_fixes[i].sigma_enu_m);
  }
  EXPECT_LT(worst_p, 1e-3);
  EXPECT_LT(worst_h, 1e-3);
  EXPECT_FALSE(twin.truth_states.empty());
  EXPECT_EQ(twin.imu.noise.gyro_noise_density_rad_s_sqrt_hz,
            real.imu.noise.gyro_noise_density_rad_s_sqrt_hz);  // what the user tells skerry
}

// The GNSS errors of a twin against its own truth, over a long recording: white sigma, drift
// sigma and its lag-1 correlation, the latency's along-track offset, the gross-error episodes.
TEST(Twin, GnssErrorsFollowTheModel) {
  const Dataset real = NoiselessRecording(900.0);
  const SplineMotion truth(real.truth_states);
  TwinModel model;
  model.gnss.white_sigma_horizontal_m = 0.4;
  model.gnss.white_sigma_vertical_m = 0.8;
  // An episode every 30 s on average, 3 s long: 3 / 33 of the fixes are off, in ~27 runs.
  model.gnss.gross_rate_per_hour = 120.0;
  model.gnss.gross_mean_duration_s = 3.0;
  model.gnss.gross_offset_horizontal_m = 30.0;
  model.gnss.gross_offset_vertical_m = 10.0;
  model.gnss.latency_s = 0.3;
  const Dataset twin = SimulateTwin(real, truth, model, 7);
  std::vector<double> along, vertical;
  int gross = 0, runs = 0;
  bool in_run = false;
  Eigen::Vector3d run_offset = Eigen::Vector3d::Zero();
  for (const GnssFix& f : twin.gnss_fixes) {
    const BodyKinematics at = truth.At(f.t_ns - SecondsToNs(0.3));
    const Eigen::Vector3d e = f.p_w - (at.p_w_b + at.q_w_b * real.gnss.p_b_g);
    if (e.head<2>().norm() > 4.0) {
      // One offset per episode: the fixes of a run differ by their white noise only.
      if (in_run) {
        EXPECT_LT((e - run_offset).head<2>().norm(), 3.0);
      }
      if (!in_run) ++runs;
      in_run = true;
      run_offset = e;
      ++gross;
      continue;
    }
    in_run = false;
    vertical.push_back(e.z());
    // Against the truth at the stamp: the fix is behind by the latency.
    const BodyKinematics now = truth.At(f.t_ns);
    const Eigen::Vector3d e_now = f.p_w - (now.p_w_b + now.q_w_b * real.gnss.p_b_g);
    if (now.v_w.head<2>().norm() > 1.0)
      along.push_back(e_now.head<2>().dot(now.v_w.head<2>().normalized()));
  }
  const double n = static_cast<double>(twin.gnss_fixes.size());
  EXPECT_GT(gross / n, 0.045);
  EXPECT_LT(gross / n, 0.16);
  EXPECT_GT(runs, 12);  // Poisson(27): 12..45 but for 1e-3
  EXPECT_LT(runs, 45);
  const double mean_along = std::accumulate(along.begin(), along.end(), 0.0) / along.size();
  // The harbour vessel makes ~4-5 m/s: a fix 0.3 s late is ~1.3 m behind.
  EXPECT_LT(mean_along, -1.0);
  EXPECT_GT(mean_along, -1.8);
  double ss = 0;
  for (double v : vertical) ss += v * v;
  EXPECT_NEAR(std::sqrt(ss / vertical.size()), 0.8, 0.05);

  // Drift alone: its stationary sigma and its correlation over one fix interval, exp(-dt / tau).
  TwinModel drift;
  drift.gnss.drift_sigma_horizontal_m = 1.0;
  drift.gnss.drift_sigma_vertical_m = 1.0;
  drift.gnss.drift_tau_s = 10.0;
  const Dataset d = SimulateTwin(real, truth, drift, 8);
  std::vector<double> east;
  for (const GnssFix& f : d.gnss_fixes) {
    const BodyKinematics at = truth.At(f.t_ns);
    east.push_back((f.p_w - (at.p_w_b + at.q_w_b * real.gnss.p_b_g)).x());
  }
  double c0 = 0, c1 = 0;
  for (size_t i = 0; i + 1 < east.size(); ++i) {
    c0 += east[i] * east[i];
    c1 += east[i] * east[i + 1];
  }
  EXPECT_NEAR(std::sqrt(c0 / (east.size() - 1)), 1.0, 0.15);
  EXPECT_NEAR(c1 / c0, std::exp(-0.2 / 10.0), 0.01);
}

TEST(Twin, ImuNoiseHasTheModelsDensityAndSeedsAreReproducible) {
  const Dataset real = NoiselessRecording(60.0);
  const SplineMotion truth(real.truth_states);
  TwinModel model;
  model.imu.gyro_noise_density_rad_s_sqrt_hz = 1e-3;
  model.imu.accel_noise_density_m_s2_sqrt_hz = 2e-2;
  const Dataset clean = SimulateTwin(real, truth, TwinModel(), 1);
  const Dataset a = SimulateTwin(real, truth, model, 1);
  const Dataset b = SimulateTwin(real, truth, model, 1);
  const Dataset c = SimulateTwin(real, truth, model, 2);
  double sg = 0, sa = 0;
  for (size_t i = 0; i < a.imu_samples.size(); ++i) {
    sg += (a.imu_samples[i].gyro_rad_s - clean.imu_samples[i].gyro_rad_s).squaredNorm();
    sa += (a.imu_samples[i].accel_m_s2 - clean.imu_samples[i].accel_m_s2).squaredNorm();
    ASSERT_EQ(a.imu_samples[i].gyro_rad_s, b.imu_samples[i].gyro_rad_s);
  }
  const double n = 3.0 * a.imu_samples.size();
  const double rate = real.imu.rate_hz;
  EXPECT_NEAR(std::sqrt(sg / n) / std::sqrt(rate), 1e-3, 3e-5);
  EXPECT_NEAR(std::sqrt(sa / n) / std::sqrt(rate), 2e-2, 6e-4);
  EXPECT_NE(a.imu_samples[5].gyro_rad_s, c.imu_samples[5].gyro_rad_s);
}

TEST(Twin, RefusesAModelItCannotSimulate) {
  const Dataset real = NoiselessRecording(20.0);
  const SplineMotion truth(real.truth_states);
  TwinModel bad;
  bad.gnss.white_sigma_horizontal_m = -1.0;
  EXPECT_THROW(SimulateTwin(real, truth, bad, 1), std::invalid_argument);
  bad = TwinModel();
  bad.imu.gyro_noise_density_rad_s_sqrt_hz = std::nan("");
  EXPECT_THROW(SimulateTwin(real, truth, bad, 1), std::invalid_argument);
  bad = TwinModel();
  bad.gnss.gross_rate_per_hour = -1.0;
  EXPECT_THROW(SimulateTwin(real, truth, bad, 1), std::invalid_argument);
  bad = TwinModel();
  bad.gnss.drift_tau_s = 0.0;
  EXPECT_THROW(SimulateTwin(real, truth, bad, 1), std::invalid_argument);
  // A truth that does not overlap the recording.
  std::vector<NavState> later = real.truth_states;
  for (NavState& s : later) s.t_ns += SecondsToNs(1000.0);
  EXPECT_THROW(SimulateTwin(real, SplineMotion(later), TwinModel(), 1), std::invalid_argument);
}

}  // namespace
}  // namespace skerry::sim
