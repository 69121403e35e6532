// The digital twin's simulator (twin.h): along the truth of a noiseless simulated recording it
// reproduces that recording's IMU and GNSS (two independent paths: the closed-form vessel motion
// against the spline through its 50 Hz truth states); its noise, drift, latency and gross-error
// episodes are what the model says; it keeps the real stamps; it is deterministic in its seed.

#include "skerry/sim/twin.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
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

// Solve and propagate (twin.h): the error of a fix is its solution's offset plus the propagation
// velocity error times the time since that solution. Along the truth of a 10 Hz recording, with
// no other error: within each solution interval the error is exactly a line; the lines' slopes
// have the velocity error's sigma and its Gauss-Markov correlation exp(-period / tau) from one
// solution to the next, their values at the solution the offset's sigma; the fixes' first
// differences jump where the phase says; the errors' autocorrelation one period apart is
// rho sigma_v^2 E[s^2] / (sigma_o^2 + sigma_v^2 E[s^2]) (s: a fix's time since its solution).
TEST(Twin, SolveAndPropagateMakesTheModelsSawtooth) {
  ScenarioConfig c = testing::Perfect(testing::SourceScenario("harbour"));
  c.duration_s = 900.0;
  c.gnss.rate_hz = 10.0;
  const Dataset real = Simulate(c, 3);
  const SplineMotion truth(real.truth_states);
  TwinModel model;
  model.gnss.solve_period_s = 1.0;
  model.gnss.solve_phase_s = 0.28;
  model.gnss.solve_offset_sigma_m = 0.03;
  model.gnss.propagation_velocity_sigma_m_s = 0.35;
  model.gnss.propagation_velocity_tau_s = 5.0;
  const Dataset twin = SimulateTwin(real, truth, model, 5);
  ASSERT_GT(twin.gnss_fixes.size(), 7000u);  // an outage or two
  // Errors per solution interval k = floor(t - phase), s = t - phase - k.
  struct Interval {
    std::vector<double> s;
    std::vector<Eigen::Vector2d> e;
  };
  std::map<long, Interval> intervals;
  std::vector<Eigen::Vector2d> errors;
  std::vector<double> phases;
  for (const GnssFix& f : twin.gnss_fixes) {
    const BodyKinematics at = truth.At(f.t_ns);
    const Eigen::Vector2d e = (f.p_w - (at.p_w_b + at.q_w_b * real.gnss.p_b_g)).head<2>();
    const double t = NsToSeconds(f.t_ns) - 0.28;
    const long k = static_cast<long>(std::floor(t));
    intervals[k].s.push_back(t - k);
    intervals[k].e.push_back(e);
    errors.push_back(e);
    phases.push_back(t - k);
  }
  // A least-squares line per interval and axis: its slope and its value at the solution.
  std::vector<double> slopes, offsets, slope_products;
  double worst_off_line = 0.0;
  Eigen::Vector2d previous_slope = Eigen::Vector2d::Zero();
  long previous_k = -10;
  for (const auto& [k, iv] : intervals) {
    if (iv.s.size() < 5) continue;
    const double n = static_cast<double>(iv.s.size());
    const double s_mean = std::accumulate(iv.s.begin(), iv.s.end(), 0.0) / n;
    Eigen::Vector2d slope_k;
    for (int axis = 0; axis < 2; ++axis) {
      double e_mean = 0.0, sxx = 0.0, sxy = 0.0;
      for (const Eigen::Vector2d& e : iv.e) e_mean += e[axis] / n;
      for (size_t i = 0; i < iv.s.size(); ++i) {
        sxx += (iv.s[i] - s_mean) * (iv.s[i] - s_mean);
        sxy += (iv.s[i] - s_mean) * (iv.e[i][axis] - e_mean);
      }
      const double slope = sxy / sxx, offset = e_mean - slope * s_mean;
      for (size_t i = 0; i < iv.s.size(); ++i) {
        worst_off_line =
            std::max(worst_off_line, std::abs(iv.e[i][axis] - offset - slope * iv.s[i]));
      }
      slopes.push_back(slope);
      offsets.push_back(offset);
      if (previous_k == k - 1) slope_products.push_back(previous_slope[axis] * slope);
      slope_k[axis] = slope;
    }
    previous_slope = slope_k;
    previous_k = k;
  }
  auto rms = [](const std::vector<double>& v) {
    double ss = 0.0;
    for (double x : v) ss += x * x;
    return std::sqrt(ss / static_cast<double>(v.size()));
  };
  EXPECT_LT(worst_off_line, 1e-6);  // the truth is the recording's own path
  const double sigma_v = rms(slopes);
  // ~900 slopes per axis, correlated over tau = 5 s: ~100 independent ones per axis.
  EXPECT_NEAR(sigma_v, 0.35, 0.06);
  EXPECT_NEAR(rms(offsets), 0.03, 0.003);  // 1800 independent offsets
  const double rho = std::accumulate(slope_products.begin(), slope_products.end(), 0.0) /
                     static_cast<double>(slope_products.size()) / (sigma_v * sigma_v);
  EXPECT_NEAR(rho, std::exp(-1.0 / 5.0), 0.06);
  // The jump: first differences across a solution against those within an interval (there
  // sigma_v * 0.1 s per axis, across about sigma_v * 0.9 s).
  double ss_across = 0.0, ss_within = 0.0;
  int n_across = 0, n_within = 0;
  for (size_t i = 1; i < errors.size(); ++i) {
    const double d2 = (errors[i] - errors[i - 1]).squaredNorm();
    if (phases[i] < phases[i - 1]) {
      ss_across += d2;
      ++n_across;
    } else {
      ss_within += d2;
      ++n_within;
    }
  }
  ASSERT_GT(n_across, 700);
  EXPECT_GT(ss_across / n_across, 20.0 * ss_within / n_within);
  // The autocorrelation one period (10 fixes) apart, against the formula above.
  double s2 = 0.0;
  for (double s : phases) s2 += s * s / static_cast<double>(phases.size());
  const double expected = rho * sigma_v * sigma_v * s2 / (0.03 * 0.03 + sigma_v * sigma_v * s2);
  double c0 = 0.0, c10 = 0.0;
  for (size_t i = 0; i < errors.size(); ++i) {
    c0 += errors[i].squaredNorm();
    if (i + 10 < errors.size()) c10 += errors[i].dot(errors[i + 10]);
  }
  EXPECT_NEAR(c10 / c0, expected, 0.05);

  // Common random numbers. Off (period 0), the solve's other values change nothing: the twin
  // of the model without them, bit for bit. On, a twin with white noise differs from the same
  // seed's twin without the solve by exactly the sawtooth above.
  TwinModel white;
  white.gnss.white_sigma_horizontal_m = 0.1;
  TwinModel off = white;
  off.gnss.solve_phase_s = 0.3;
  off.gnss.solve_offset_sigma_m = 1.0;
  off.gnss.propagation_velocity_sigma_m_s = 1.0;
  TwinModel on = model;
  on.gnss.white_sigma_horizontal_m = 0.1;
  const Dataset a = SimulateTwin(real, truth, white, 5);
  const Dataset b = SimulateTwin(real, truth, off, 5);
  const Dataset d = SimulateTwin(real, truth, on, 5);
  ASSERT_EQ(a.gnss_fixes.size(), twin.gnss_fixes.size());
  double worst_saw = 0.0;
  for (size_t i = 0; i < a.gnss_fixes.size(); ++i) {
    ASSERT_EQ(a.gnss_fixes[i].p_w, b.gnss_fixes[i].p_w);
    const Eigen::Vector2d diff = (d.gnss_fixes[i].p_w - a.gnss_fixes[i].p_w).head<2>();
    worst_saw = std::max(worst_saw, (diff - errors[i]).norm());
  }
  EXPECT_LT(worst_saw, 1e-6);
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
  bad = TwinModel();
  bad.gnss.propagation_velocity_tau_s = 0.0;
  EXPECT_THROW(SimulateTwin(real, truth, bad, 1), std::invalid_argument);
  bad = TwinModel();
  bad.gnss.solve_period_s = 1e-6;
  EXPECT_THROW(SimulateTwin(real, truth, bad, 1), std::invalid_argument);
  // A truth that does not overlap the recording.
  std::vector<NavState> later = real.truth_states;
  for (NavState& s : later) s.t_ns += SecondsToNs(1000.0);
  EXPECT_THROW(SimulateTwin(real, SplineMotion(later), TwinModel(), 1), std::invalid_argument);
}

}  // namespace
}  // namespace skerry::sim
