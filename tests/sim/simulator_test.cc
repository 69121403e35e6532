// The simulated dataset: determinism, IMU and GNSS error statistics, jumps, outages, truth.

#include "skerry/sim/simulator.h"

#include <gtest/gtest.h>

#include <cmath>

#include "sim/sim_test_util.h"
#include "skerry/core/geodesy.h"
#include "skerry/core/heading.h"

namespace skerry::sim {
namespace {

bool SameImu(const std::vector<ImuSample>& a, const std::vector<ImuSample>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].t_ns != b[i].t_ns || a[i].gyro_rad_s != b[i].gyro_rad_s ||
        a[i].accel_m_s2 != b[i].accel_m_s2) {
      return false;
    }
  }
  return true;
}

bool SameGnss(const std::vector<GnssFix>& a, const std::vector<GnssFix>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a[i].t_ns != b[i].t_ns || a[i].lat_deg != b[i].lat_deg || a[i].lon_deg != b[i].lon_deg ||
        a[i].height_m != b[i].height_m || a[i].p_w != b[i].p_w) {
      return false;
    }
  }
  return true;
}

ScenarioConfig Harbour(double duration_s) {
  ScenarioConfig c = testing::SourceScenario("harbour");
  c.duration_s = duration_s;
  return c;
}

/// A vessel at rest on flat water: the IMU senses only gravity and its errors.
ScenarioConfig AtRest(double duration_s) {
  ScenarioConfig c;
  c.name = "rest";
  c.duration_s = duration_s;
  c.trajectory.start_speed_m_s = 0.0;
  return c;
}

TEST(Simulate, SameSeedGivesIdenticalDatasetOtherSeedDiffers) {
  const ScenarioConfig c = Harbour(30.0);
  const Dataset a = Simulate(c, 7);
  const Dataset b = Simulate(c, 7);
  const Dataset d = Simulate(c, 8);
  EXPECT_TRUE(SameImu(a.imu_samples, b.imu_samples));
  EXPECT_TRUE(SameGnss(a.gnss_fixes, b.gnss_fixes));
  ASSERT_EQ(a.truth_states.size(), b.truth_states.size());
  for (std::size_t i = 0; i < a.truth_states.size(); ++i) {
    EXPECT_EQ(a.truth_states[i].p_w_b, b.truth_states[i].p_w_b);
    EXPECT_EQ(a.truth_states[i].bg, b.truth_states[i].bg);
  }
  EXPECT_FALSE(SameImu(a.imu_samples, d.imu_samples));
  EXPECT_FALSE(SameGnss(a.gnss_fixes, d.gnss_fixes));
}

TEST(Simulate, FillsTheDataset) {
  const ScenarioConfig c = Harbour(600.0);
  const Dataset ds = Simulate(c, c.seed);
  EXPECT_EQ(ds.name, "harbour");
  EXPECT_TRUE(ds.has_gnss);
  EXPECT_EQ(ds.imu_samples.size(), 120001u);
  EXPECT_EQ(ds.imu_samples[1].t_ns, 5'000'000);
  EXPECT_EQ(ds.groundtruth.size(), 30001u);
  EXPECT_EQ(ds.truth_states.size(), ds.groundtruth.size());
  EXPECT_EQ(ds.imu.rate_hz, 200.0);
  EXPECT_EQ(ds.imu.noise.gyro_noise_density_rad_s_sqrt_hz,
            c.imu.errors.noise.gyro_noise_density_rad_s_sqrt_hz);
  EXPECT_TRUE(ds.imu.p_b_i.isApprox(Eigen::Vector3d(1.2, -0.3, 0.5)));
  EXPECT_TRUE(ds.gnss.p_b_g.isApprox(Eigen::Vector3d(-1.5, 0.0, 2.8)));
  // 2 Hz over 600 s = 1201 epochs, minus 240 in the 120 s outage.
  EXPECT_EQ(ds.gnss_fixes.size(), 1201u - 240u);
  ASSERT_EQ(ds.events.size(), 2u);
  EXPECT_EQ(ds.events[0].type, "jump");
  EXPECT_EQ(ds.events[0].t_start_ns, 200'000'000'000);
  EXPECT_EQ(ds.events[0].t_end_ns, 220'000'000'000);
  EXPECT_EQ(ds.events[0].offset_enu_m, Eigen::Vector3d(14.5, 0, 0));
  EXPECT_EQ(ds.events[1].type, "outage");
  EXPECT_EQ(ds.events[1].t_start_ns, 360'000'000'000);
  EXPECT_EQ(ds.events[1].t_end_ns, 480'000'000'000);
  // The vessel is moving from the start and goes straight for at least 5 s.
  EXPECT_NEAR(ds.truth_states.front().v_w.head<2>().norm(), 5.0, 1e-9);  // plus heave
  for (std::size_t i = 0; i <= 250; ++i) {
    EXPECT_NEAR(HeadingDeg(ds.truth_states[i].q_w_b), 60.0, 1.0);  // waves only
  }
  // Geodetic fixes agree with their local ENU position.
  const LocalFrame frame(ds.origin);
  for (const GnssFix& f : ds.gnss_fixes) {
    ASSERT_LT((frame.ToEnu(f.lat_deg, f.lon_deg, f.height_m) - f.p_w).norm(), 1e-6);
    EXPECT_EQ(f.sigma_enu_m, Eigen::Vector3d(0.35, 0.35, 0.6));
  }
}

TEST(Simulate, ImuAtRestSensesGravityPlusConfiguredWhiteNoise) {
  ScenarioConfig c = AtRest(500.0);
  c.imu.errors = ImuGradePreset(ImuGrade::kConsumer);
  c.imu.errors.gyro_bias_initial_sigma_rad_s = 0.0;
  c.imu.errors.accel_bias_initial_sigma_m_s2 = 0.0;
  c.imu.errors.noise.gyro_bias_random_walk_rad_s2_sqrt_hz = 0.0;
  c.imu.errors.noise.accel_bias_random_walk_m_s3_sqrt_hz = 0.0;
  const Dataset ds = Simulate(c, 11);
  Eigen::Vector3d sum_g2 = Eigen::Vector3d::Zero(), sum_a = Eigen::Vector3d::Zero(),
                  sum_a2 = Eigen::Vector3d::Zero();
  for (const ImuSample& s : ds.imu_samples) {
    sum_g2 += s.gyro_rad_s.cwiseAbs2();
    sum_a += s.accel_m_s2;
  }
  const double n = static_cast<double>(ds.imu_samples.size());
  const Eigen::Vector3d mean_a = sum_a / n;
  for (const ImuSample& s : ds.imu_samples) sum_a2 += (s.accel_m_s2 - mean_a).cwiseAbs2();
  EXPECT_NEAR(mean_a.z(), 9.80665, 1e-3);
  const double sigma_g = c.imu.errors.noise.gyro_noise_density_rad_s_sqrt_hz * std::sqrt(200.0);
  const double sigma_a = c.imu.errors.noise.accel_noise_density_m_s2_sqrt_hz * std::sqrt(200.0);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(std::sqrt(sum_g2[i] / n), sigma_g, 0.02 * sigma_g);
    EXPECT_NEAR(std::sqrt(sum_a2[i] / n), sigma_a, 0.02 * sigma_a);
  }
}

TEST(Simulate, TruthStatesCarryTheBiasesInTheMeasurements) {
  ScenarioConfig c = AtRest(100.0);
  c.imu.errors = ImuGradePreset(ImuGrade::kConsumer);
  c.imu.errors.noise.gyro_noise_density_rad_s_sqrt_hz = 0.0;
  c.imu.errors.noise.accel_noise_density_m_s2_sqrt_hz = 0.0;
  const Dataset ds = Simulate(c, 4);
  // With identity mounting at rest: gyro = bg, accel = (0, 0, g) + ba, for every truth state.
  for (const NavState& x : ds.truth_states) {
    const ImuSample& s = ds.imu_samples[static_cast<std::size_t>(x.t_ns / 5'000'000)];
    ASSERT_EQ(s.t_ns, x.t_ns);
    ASSERT_LT((s.gyro_rad_s - x.bg).norm(), 1e-15);
    ASSERT_LT((s.accel_m_s2 - Eigen::Vector3d(0, 0, 9.80665) - x.ba).norm(), 1e-12);
  }
  EXPECT_GT(ds.truth_states.front().bg.norm(), 0.0);
  EXPECT_NE(ds.truth_states.front().bg, ds.truth_states.back().bg);  // random walk
}

TEST(Simulate, GnssWhiteNoiseHasTheConfiguredSigma) {
  ScenarioConfig c = AtRest(2000.0);
  c.imu.rate_hz = 10.0;  // the IMU does not matter here
  c.gnss.rate_hz = 10.0;
  c.gnss.noise_sigma_horizontal_m = 0.3;
  c.gnss.noise_sigma_vertical_m = 0.5;
  c.gnss.p_b_g = Eigen::Vector3d(0.5, 0.2, 3.0);
  c.waves.roll_deg = {{3.0, 7.0}};  // antenna swings: the truth must include the lever arm
  const Dataset ds = Simulate(c, 21);
  const VesselMotion motion(c.trajectory, c.waves, c.duration_s, 21);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero(), sum2 = Eigen::Vector3d::Zero();
  for (const GnssFix& f : ds.gnss_fixes) {
    const BodyKinematics k = motion.At(NsToSeconds(f.t_ns));
    const Eigen::Vector3d e = f.p_w - (k.p_w_b + k.q_w_b * c.gnss.p_b_g);
    sum += e;
    sum2 += e.cwiseAbs2();
  }
  const double n = static_cast<double>(ds.gnss_fixes.size());
  EXPECT_EQ(n, 20001.0);
  const Eigen::Vector3d sigma = (sum2 / n - (sum / n).cwiseAbs2()).cwiseSqrt();
  EXPECT_NEAR(sigma.x(), 0.3, 0.03);
  EXPECT_NEAR(sigma.y(), 0.3, 0.03);
  EXPECT_NEAR(sigma.z(), 0.5, 0.05);
  EXPECT_LT((sum / n).head<2>().norm(), 0.02);
}

TEST(Simulate, GnssDriftIsSlowAndHasTheConfiguredSigma) {
  ScenarioConfig c = testing::Perfect(AtRest(20000.0));
  c.imu.rate_hz = 1.0;
  c.gnss.rate_hz = 1.0;
  c.gnss.drift_sigma_horizontal_m = 0.8;
  c.gnss.drift_sigma_vertical_m = 0.0;
  c.gnss.drift_tau_s = 100.0;
  const Dataset ds = Simulate(c, 5);
  double sum2 = 0.0, lag1 = 0.0;
  for (std::size_t i = 0; i < ds.gnss_fixes.size(); ++i) {
    const double e = ds.gnss_fixes[i].p_w.x();
    sum2 += e * e;
    if (i > 0) lag1 += e * ds.gnss_fixes[i - 1].p_w.x();
  }
  const double n = static_cast<double>(ds.gnss_fixes.size());
  // 200 correlation times: the sample std is within about 10 % of sigma.
  EXPECT_NEAR(std::sqrt(sum2 / n), 0.8, 0.1);
  EXPECT_NEAR(lag1 / sum2, std::exp(-1.0 / 100.0), 0.01);  // correlation over one step
  for (const GnssFix& f : ds.gnss_fixes) ASSERT_NEAR(f.p_w.z(), 0.0, 1e-9);
}

TEST(Simulate, JumpOffsetsExactlyTheFixesInsideItsWindow) {
  const ScenarioConfig c = testing::Perfect(Harbour(300.0));
  const Dataset ds = Simulate(c, 1);
  const VesselMotion motion(c.trajectory, c.waves, c.duration_s, 1);
  int inside = 0;
  for (const GnssFix& f : ds.gnss_fixes) {
    const double t = NsToSeconds(f.t_ns);
    const BodyKinematics k = motion.At(t);
    const Eigen::Vector3d e = f.p_w - (k.p_w_b + k.q_w_b * c.gnss.p_b_g);
    const bool in_jump = t >= 200.0 && t < 220.0;
    inside += in_jump;
    const Eigen::Vector3d expected =
        in_jump ? Eigen::Vector3d(14.5, 0, 0) : Eigen::Vector3d::Zero();
    ASSERT_LT((e - expected).norm(), 1e-9) << "t=" << t;
  }
  EXPECT_EQ(inside, 40);  // 20 s at 2 Hz, [200, 220)
}

TEST(Simulate, NoFixesDuringOutagesAndOutagesDoNotChangeOtherFixes) {
  const ScenarioConfig with = Harbour(600.0);
  ScenarioConfig without = with;
  without.gnss.outages.clear();
  const Dataset a = Simulate(with, 9);
  const Dataset b = Simulate(without, 9);
  for (const GnssFix& f : a.gnss_fixes) {
    const double t = NsToSeconds(f.t_ns);
    ASSERT_FALSE(t >= 360.0 && t < 480.0) << "fix at " << t;
  }
  EXPECT_EQ(b.gnss_fixes.size(), a.gnss_fixes.size() + 240);
  // Fixes outside the outage are identical with and without it (independent random streams).
  std::size_t j = 0;
  for (const GnssFix& f : a.gnss_fixes) {
    while (b.gnss_fixes[j].t_ns < f.t_ns) ++j;
    ASSERT_EQ(f.p_w, b.gnss_fixes[j].p_w);
  }
  EXPECT_EQ(a.gnss_fixes.front().t_ns, 0);
  // The first fix after the outage is at its end (half-open window).
  bool found = false;
  for (const GnssFix& f : a.gnss_fixes) found |= f.t_ns == 480'000'000'000;
  EXPECT_TRUE(found);
}

TEST(Simulate, DualAntennaHeadingIsTheBaselineHeading) {
  ScenarioConfig c = testing::Perfect(Harbour(300.0));
  c.gnss.dual_antenna_enabled = true;
  const Dataset ds = Simulate(c, 1);
  for (const NavState& x : ds.truth_states) {
    for (const GnssFix& f : ds.gnss_fixes) {
      if (f.t_ns != x.t_ns) continue;
      ASSERT_TRUE(f.has_heading);
      const double d = std::remainder(f.heading_deg - HeadingDeg(x.q_w_b), 360.0);
      ASSERT_NEAR(d, 0.0, 1e-9);
      ASSERT_GE(f.heading_deg, 0.0);
      ASSERT_LT(f.heading_deg, 360.0);
    }
  }
}

TEST(Simulate, RejectsNonPositiveRates) {
  ScenarioConfig c = AtRest(10.0);
  c.gnss.rate_hz = 0.0;
  EXPECT_THROW(Simulate(c, 1), std::invalid_argument);
}

}  // namespace
}  // namespace skerry::sim

namespace skerry::sim {
namespace {

TEST(Simulate, WrittenDatasetLoadsBack) {
  // The simulator's output must pass the dataset loader's checks (increasing time, unit
  // quaternions, finite numbers, optional heading columns).
  ScenarioConfig c = testing::SourceScenario("open-sea");
  c.duration_s = 60.0;
  const Dataset ds = Simulate(c, 2);
  const std::string dir = std::string(SKERRY_TEST_TMP_DIR) + "/sim_open_sea_60s";
  WriteDataset(ds, dir);
  const Dataset back = LoadDataset(dir);
  EXPECT_EQ(back.name, "open-sea");
  ASSERT_EQ(back.imu_samples.size(), ds.imu_samples.size());
  ASSERT_EQ(back.gnss_fixes.size(), ds.gnss_fixes.size());
  ASSERT_EQ(back.groundtruth.size(), ds.groundtruth.size());
  ASSERT_EQ(back.truth_states.size(), ds.truth_states.size());
  EXPECT_EQ(back.imu_samples.back().t_ns, ds.imu_samples.back().t_ns);
  EXPECT_LT((back.imu_samples[100].accel_m_s2 - ds.imu_samples[100].accel_m_s2).norm(), 1e-9);
  EXPECT_LT((back.gnss_fixes[10].p_w - ds.gnss_fixes[10].p_w).norm(), 1e-3);
  EXPECT_TRUE(back.gnss_fixes[10].has_heading);
  EXPECT_LT((back.truth_states[500].bg - ds.truth_states[500].bg).norm(), 1e-12);
  EXPECT_TRUE(back.imu.p_b_i.isApprox(ds.imu.p_b_i));
  EXPECT_EQ(back.imu.noise.gyro_noise_density_rad_s_sqrt_hz,
            ds.imu.noise.gyro_noise_density_rad_s_sqrt_hz);
}

}  // namespace
}  // namespace skerry::sim
