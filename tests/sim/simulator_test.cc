// The simulated dataset: determinism, IMU and GNSS error statistics, jumps, outages, truth.

#include "skerry/sim/simulator.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>

#include "sim/sim_test_util.h"
#include "skerry/core/earth_model.h"
#include "skerry/core/geodesy.h"
#include "skerry/core/heading.h"
#include "skerry/sim/earth_motion.h"

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

/// The true motion of a scenario on its Earth (EarthMotion keeps a reference to the vessel).
struct TrueMotion {
  TrueMotion(const ScenarioConfig& c, std::uint64_t seed)
      : vessel(c.trajectory, c.waves, c.duration_s, seed),
        earth(vessel, c.origin, c.earth, c.duration_s) {}
  BodyKinematics At(double t_s) const { return earth.At(t_s).body; }
  VesselMotion vessel;
  EarthMotion earth;
};

/// An IMU error model with white noise and a constant turn-on bias only.
ImuErrorModel WhiteNoiseOnly(ImuGrade grade) {
  const ImuErrorModel preset = ImuGradePreset(grade);
  ImuErrorModel m;
  m.noise.gyro_noise_density_rad_s_sqrt_hz = preset.noise.gyro_noise_density_rad_s_sqrt_hz;
  m.noise.accel_noise_density_m_s2_sqrt_hz = preset.noise.accel_noise_density_m_s2_sqrt_hz;
  m.noise.gyro_bias_random_walk_rad_s2_sqrt_hz = 0.0;
  m.noise.accel_bias_random_walk_m_s3_sqrt_hz = 0.0;
  return m;
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
  // 2 Hz from 0.037 s (the receiver's epochs are off the 10 Hz keyframe grid) up to 600 s:
  // 1200 epochs, minus 240 in the 120 s outage.
  EXPECT_EQ(ds.gnss_fixes.size(), 1200u - 240u);
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
  c.imu.errors = WhiteNoiseOnly(ImuGrade::kConsumer);
  const Dataset ds = Simulate(c, 11);
  Eigen::Vector3d sum_g = Eigen::Vector3d::Zero(), sum_a = Eigen::Vector3d::Zero();
  for (const ImuSample& s : ds.imu_samples) {
    sum_g += s.gyro_rad_s;
    sum_a += s.accel_m_s2;
  }
  const double n = static_cast<double>(ds.imu_samples.size());
  const Eigen::Vector3d mean_g = sum_g / n, mean_a = sum_a / n;
  Eigen::Vector3d sum_g2 = Eigen::Vector3d::Zero(), sum_a2 = Eigen::Vector3d::Zero();
  for (const ImuSample& s : ds.imu_samples) {
    sum_g2 += (s.gyro_rad_s - mean_g).cwiseAbs2();
    sum_a2 += (s.accel_m_s2 - mean_a).cwiseAbs2();
  }
  // Normal gravity at 47.6 N, 440 m (Somigliana with the free-air term: 9.8072 m/s^2).
  EXPECT_NEAR(mean_a.norm(), 9.80722, 1e-3);
  const double sigma_g = c.imu.errors.noise.gyro_noise_density_rad_s_sqrt_hz * std::sqrt(200.0);
  const double sigma_a = c.imu.errors.noise.accel_noise_density_m_s2_sqrt_hz * std::sqrt(200.0);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(std::sqrt(sum_g2[i] / n), sigma_g, 0.02 * sigma_g);
    EXPECT_NEAR(std::sqrt(sum_a2[i] / n), sigma_a, 0.02 * sigma_a);
  }
}

// A perfect IMU at rest reads the Earth's rate and the local gravity, rotated into its frame:
// at 47.6 N, 10.1 deg/h along the local north and 11.1 deg/h up, whatever the heading.
TEST(Simulate, APerfectImuAtRestReadsTheEarthsRateAndGravity) {
  for (const double heading : {0.0, 60.0, 200.0}) {
    ScenarioConfig c = testing::Perfect(AtRest(10.0));
    c.trajectory.start_heading_deg = heading;
    const Dataset ds = Simulate(c, 3);
    const EarthModel earth = ds.Earth();
    for (std::size_t k = 0; k < ds.truth_states.size(); k += 50) {
      const NavState& x = ds.truth_states[k];
      const ImuSample& s = ds.imu_samples[4 * k];
      ASSERT_EQ(s.t_ns, x.t_ns);
      const Eigen::Quaterniond q_i_w = x.q_w_b.conjugate();  // identity mounting
      EXPECT_LT((s.gyro_rad_s - q_i_w * earth.omega_ie_w()).norm(), 1e-15);
      EXPECT_LT((s.accel_m_s2 + q_i_w * earth.Gravity(x.p_w_b)).norm(), 1e-9);
      const double deg_h = 180.0 / M_PI * 3600.0;
      EXPECT_NEAR(s.gyro_rad_s.norm() * deg_h, 15.041, 0.001);
    }
  }
}

TEST(Simulate, TruthStatesCarryTheBiasesInTheMeasurements) {
  ScenarioConfig c = AtRest(100.0);
  c.imu.errors = ImuGradePreset(ImuGrade::kConsumer);
  c.imu.errors.noise.gyro_noise_density_rad_s_sqrt_hz = 0.0;
  c.imu.errors.noise.accel_noise_density_m_s2_sqrt_hz = 0.0;
  c.imu.errors.gyro_scale_factor_ppm = c.imu.errors.accel_scale_factor_ppm = 0.0;
  c.imu.errors.gyro_misalignment_mrad = c.imu.errors.accel_misalignment_mrad = 0.0;
  const Dataset ds = Simulate(c, 4);
  const EarthModel earth = ds.Earth();
  // With identity mounting at rest: gyro = Earth rate + bg, accel = -g + ba (IMU frame).
  for (const NavState& x : ds.truth_states) {
    const ImuSample& s = ds.imu_samples[static_cast<std::size_t>(x.t_ns / 5'000'000)];
    ASSERT_EQ(s.t_ns, x.t_ns);
    const Eigen::Quaterniond q_i_w = x.q_w_b.conjugate();
    ASSERT_LT((s.gyro_rad_s - q_i_w * earth.omega_ie_w() - x.bg).norm(), 1e-15);
    ASSERT_LT((s.accel_m_s2 + q_i_w * earth.Gravity(x.p_w_b) - x.ba).norm(), 1e-9);
  }
  EXPECT_GT(ds.truth_states.front().bg.norm(), 0.0);
  EXPECT_NE(ds.truth_states.front().bg, ds.truth_states.back().bg);  // it wanders
}

// The in-run bias of a real unit is bounded, not a random walk: the simulator's Gauss-Markov
// wander keeps its stationary sigma over 30 correlation times and decorrelates with exp(-T/tau)
// (the estimator, told a random walk, expects it to grow as sqrt(T)).
TEST(Simulate, BiasWanderIsGaussMarkovWithTheConfiguredInstability) {
  ScenarioConfig c = testing::Perfect(AtRest(3000.0));
  c.imu.rate_hz = 20.0;
  c.imu.errors.gyro_bias_instability_rad_s = 1e-4;
  c.imu.errors.accel_bias_instability_m_s2 = 2e-3;
  c.imu.errors.bias_instability_tau_s = 100.0;
  const Dataset ds = Simulate(c, 17);
  double sum2 = 0.0, lag = 0.0;
  int n = 0, m = 0;
  const std::size_t lag_k = 2000;  // 100 s at 20 Hz: one correlation time
  for (std::size_t k = 0; k < ds.imu_samples.size(); ++k) {
    // The east axis of a vessel heading north: the Earth's rate has no part in it.
    const double x = ds.imu_samples[k].gyro_rad_s.x();
    sum2 += x * x;
    ++n;
    if (k >= lag_k) {
      lag += x * ds.imu_samples[k - lag_k].gyro_rad_s.x();
      ++m;
    }
  }
  EXPECT_NEAR(std::sqrt(sum2 / n), 1e-4, 0.25e-4);  // 30 correlation times: sample sigma +-20 %
  EXPECT_NEAR((lag / m) / (sum2 / n), std::exp(-1.0), 0.25);
}

// Scale factor and misalignment: a perfect unit with only these errors, turning at a steady
// rate, reads (I + S + M) times the true rate; the errors are drawn once per run.
TEST(Simulate, ScaleFactorAndMisalignmentAreDrawnOncePerRun) {
  ScenarioConfig c = testing::Perfect(Harbour(60.0));
  c.imu.errors.gyro_scale_factor_ppm = 1000.0;
  c.imu.errors.gyro_misalignment_mrad = 1.0;
  c.imu.q_b_i = Eigen::Quaterniond::Identity();
  c.imu.p_b_i.setZero();
  const Dataset a = Simulate(c, 5);
  ScenarioConfig ideal = c;
  ideal.imu.errors.gyro_scale_factor_ppm = 0.0;
  ideal.imu.errors.gyro_misalignment_mrad = 0.0;
  const Dataset b = Simulate(ideal, 5);
  // Fit the 3x3 matrix A with a.gyro = A b.gyro over the run (least squares).
  Eigen::Matrix3d BtB = Eigen::Matrix3d::Zero(), AtB = Eigen::Matrix3d::Zero();
  for (std::size_t k = 0; k < a.imu_samples.size(); ++k) {
    BtB += b.imu_samples[k].gyro_rad_s * b.imu_samples[k].gyro_rad_s.transpose();
    AtB += a.imu_samples[k].gyro_rad_s * b.imu_samples[k].gyro_rad_s.transpose();
  }
  const Eigen::Matrix3d A = AtB * BtB.inverse();
  const Eigen::Matrix3d E = A - Eigen::Matrix3d::Identity();
  EXPECT_GT(E.diagonal().cwiseAbs().maxCoeff(), 1e-4);  // of order 1e-3
  EXPECT_LT(E.diagonal().cwiseAbs().maxCoeff(), 5e-3);
  EXPECT_GT(std::abs(E(0, 1)) + std::abs(E(1, 2)) + std::abs(E(2, 0)), 1e-4);
  for (std::size_t k = 0; k < a.imu_samples.size(); k += 97) {
    EXPECT_LT((a.imu_samples[k].gyro_rad_s - A * b.imu_samples[k].gyro_rad_s).norm(), 1e-12);
  }
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
  const TrueMotion motion(c, 21);
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

// Pose fixes: on time (offset + k / rate, inside [start, end)), of the frame at T_b_s, with the
// configured sigmas along the local east, north and heading, the configured share of gross ones
// listed and at least min_m / heading_min_deg off; and they leave every other sensor's errors
// as they were.
TEST(Simulate, PoseFixesHaveTheConfiguredTimesNoiseAndOutliers) {
  ScenarioConfig c = AtRest(2000.0);
  c.imu.rate_hz = 10.0;
  c.waves.roll_deg = {{3.0, 7.0}};  // the mast swings: the truth must include the lever arm
  const Dataset without = Simulate(c, 22);
  c.pose_fixes.enabled = true;
  c.pose_fixes.rate_hz = 2.0;
  c.pose_fixes.time_offset_s = 0.37;
  c.pose_fixes.start_s = 100.0;
  c.pose_fixes.end_s = 1900.0;
  c.pose_fixes.kind = "enh";
  c.pose_fixes.sigma_horizontal_m = 0.5;
  c.pose_fixes.sigma_heading_deg = 1.0;
  c.pose_fixes.outlier_probability = 0.05;
  c.pose_fixes.outlier_min_m = 20.0;
  c.pose_fixes.outlier_heading_min_deg = 20.0;
  c.pose_fixes.mount.q_b_s =
      Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()));
  c.pose_fixes.mount.p_b_s = Eigen::Vector3d(0.5, 0.0, 4.0);
  const Dataset ds = Simulate(c, 22);
  EXPECT_TRUE(SameImu(ds.imu_samples, without.imu_samples));
  EXPECT_TRUE(SameGnss(ds.gnss_fixes, without.gnss_fixes));
  ASSERT_TRUE(ds.has_pose_fixes);
  ASSERT_EQ(ds.pose_fixes.size(), 3600u);  // 2 Hz over [100.37, 1900)
  EXPECT_EQ(ds.pose_fixes.front().t_ns, SecondsToNs(100.37));
  const TrueMotion motion(c, 22);
  const EarthModel earth(c.origin, c.earth);
  Eigen::Vector3d sum2 = Eigen::Vector3d::Zero();
  int inliers = 0;
  for (const PoseFix& f : ds.pose_fixes) {
    EXPECT_TRUE(f.has_heading && !f.has_up);
    const BodyKinematics k = motion.At(NsToSeconds(f.t_ns));
    const Eigen::Vector3d p_w_s = k.p_w_b + k.q_w_b * c.pose_fixes.mount.p_b_s;
    const Eigen::Matrix3d R_n_w = earth.LocalLevel(p_w_s).transpose();
    const Eigen::Vector3d e_n = R_n_w * (f.p_w - p_w_s);
    const Eigen::Vector3d x_n =
        R_n_w * (k.q_w_b * (c.pose_fixes.mount.q_b_s * Eigen::Vector3d::UnitX()));
    const double e_psi =
        std::remainder(f.heading_deg - std::atan2(x_n.x(), x_n.y()) * 180.0 / M_PI, 360.0);
    const bool outlier =
        std::binary_search(ds.pose_fix_outliers.begin(), ds.pose_fix_outliers.end(), f.t_ns);
    if (outlier) {
      EXPECT_GE(e_n.head<2>().norm(), 20.0 - 4.0 * 0.5);
      EXPECT_GE(std::abs(e_psi), 20.0 - 4.0);
      continue;
    }
    EXPECT_LT(e_n.head<2>().norm(), 5.0 * 0.5);
    sum2 += Eigen::Vector3d(e_n.x() * e_n.x(), e_n.y() * e_n.y(), e_psi * e_psi);
    ++inliers;
  }
  const int outliers = static_cast<int>(ds.pose_fix_outliers.size());
  EXPECT_NEAR(outliers, 0.05 * 3600, 4.0 * std::sqrt(0.05 * 0.95 * 3600));  // binomial, 4 sigma
  const Eigen::Vector3d sigma = (sum2 / inliers).cwiseSqrt();
  EXPECT_NEAR(sigma.x(), 0.5, 0.05);
  EXPECT_NEAR(sigma.y(), 0.5, 0.05);
  EXPECT_NEAR(sigma.z(), 1.0, 0.1);
  EXPECT_DOUBLE_EQ(ds.pose_fixes.front().covariance(0, 0), 0.25);
  EXPECT_NEAR(ds.pose_fixes.front().covariance(3, 3), std::pow(M_PI / 180.0, 2), 1e-15);
}

// The water surface: the vessel floats at its mean height, up to its zero-mean heave (not at its
// starting height, which holds the heave at t = 0: a bias the estimator would hold all run).
TEST(Simulate, TheVesselFloatsAtTheWaterSurfaceHeight) {
  ScenarioConfig c = Harbour(300.0);
  c.water_surface_enabled = true;
  c.water_surface_sigma_m = 0.3;
  const Dataset ds = Simulate(c, 23);
  ASSERT_TRUE(ds.water_surface.has_value());
  EXPECT_DOUBLE_EQ(ds.water_surface->sigma_m, 0.3);
  const LocalFrame frame(c.origin);
  double heave = 0.0;
  for (const WaveComponent& w : c.waves.heave_m) heave += w.amplitude;
  ASSERT_GT(heave, 0.1);
  double max_dev = 0.0, sum = 0.0;
  for (const StampedPose& p : ds.groundtruth) {
    const double dev = frame.ToGeodetic(p.p_w_b).z() - ds.water_surface->height_m;
    max_dev = std::max(max_dev, std::abs(dev));
    sum += dev;
  }
  const double mean = sum / static_cast<double>(ds.groundtruth.size());
  EXPECT_LE(max_dev, heave + 1e-6);                 // inside the heave's range about the surface
  EXPECT_GT(max_dev, 0.1 * heave);                  // and it does heave
  EXPECT_LT(std::abs(mean), 0.05 * heave) << mean;  // about the surface, not off it
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

// The jump's offset is along the local east, north and up at the antenna (the receiver's frame).
TEST(Simulate, JumpOffsetsExactlyTheFixesInsideItsWindow) {
  ScenarioConfig c = testing::Perfect(Harbour(300.0));
  c.gnss.time_offset_s = 0.0;
  const Dataset ds = Simulate(c, 1);
  const TrueMotion motion(c, 1);
  const EarthModel earth = ds.Earth();
  int inside = 0;
  for (const GnssFix& f : ds.gnss_fixes) {
    const double t = NsToSeconds(f.t_ns);
    const BodyKinematics k = motion.At(t);
    const Eigen::Vector3d p_w_g = k.p_w_b + k.q_w_b * c.gnss.p_b_g;
    const Eigen::Vector3d e = f.p_w - p_w_g;
    const bool in_jump = t >= 200.0 && t < 220.0;
    inside += in_jump;
    const Eigen::Vector3d expected =
        in_jump ? Eigen::Vector3d(earth.LocalLevel(p_w_g) * Eigen::Vector3d(14.5, 0, 0))
                : Eigen::Vector3d::Zero();
    ASSERT_LT((e - expected).norm(), 1e-9) << "t=" << t;
  }
  EXPECT_EQ(inside, 40);  // 20 s at 2 Hz, [200, 220)
}

// A receiver measuring at offset + k / rate, stamping each fix latency + N(0, jitter^2) later:
// the stamps are off the keyframe grid and late, and the position is the antenna's at the
// instant measured, not at the stamp.
TEST(Simulate, FixesAreStampedLateOffTheGridWithJitter) {
  ScenarioConfig c = testing::Perfect(Harbour(120.0));
  c.gnss.time_offset_s = 0.037;
  c.gnss.latency_s = 0.02;
  c.gnss.stamp_jitter_s = 0.003;
  const Dataset ds = Simulate(c, 2);
  const TrueMotion motion(c, 2);
  ASSERT_EQ(ds.gnss_fixes.size(), 240u);
  double sum = 0.0, sum2 = 0.0;
  for (std::size_t k = 0; k < ds.gnss_fixes.size(); ++k) {
    const GnssFix& f = ds.gnss_fixes[k];
    const double t_meas = 0.037 + 0.5 * static_cast<double>(k);
    const double delay = NsToSeconds(f.t_ns) - t_meas;
    ASSERT_GE(delay, 0.02 - 3 * 0.003 - 1e-9);
    ASSERT_LE(delay, 0.02 + 3 * 0.003 + 1e-9);
    sum += delay;
    sum2 += delay * delay;
    const BodyKinematics at_meas = motion.At(t_meas);
    EXPECT_LT((f.p_w - (at_meas.p_w_b + at_meas.q_w_b * c.gnss.p_b_g)).norm(), 1e-6);
  }
  const double n = static_cast<double>(ds.gnss_fixes.size());
  EXPECT_NEAR(sum / n, 0.02, 0.0005);
  EXPECT_NEAR(std::sqrt(sum2 / n - (sum / n) * (sum / n)), 0.003, 0.0005);
  // Off the 10 Hz grid: 37 ms + 20 ms after a keyframe, never on it.
  for (const GnssFix& f : ds.gnss_fixes) EXPECT_NE(f.t_ns % 100'000'000, 0);
}

// Multipath bursts and the second, slow process: bounded, zero-mean errors, the bursts only
// in their episodes. Over 10 hours of 1 Hz fixes at rest with only these two errors on.
TEST(Simulate, MultipathBurstsAndTheSlowProcess) {
  ScenarioConfig c = testing::Perfect(AtRest(36000.0));
  c.imu.rate_hz = 1.0;
  c.gnss.rate_hz = 1.0;
  c.gnss.multipath_rate_per_hour = 6.0;
  c.gnss.multipath_mean_duration_s = 20.0;
  c.gnss.multipath_sigma_horizontal_m = 1.0;
  c.gnss.multipath_sigma_vertical_m = 2.0;
  c.gnss.multipath_tau_s = 3.0;
  const Dataset ds = Simulate(c, 8);
  int affected = 0;
  double sum2 = 0.0;
  for (const GnssFix& f : ds.gnss_fixes) {
    if (f.p_w.head<2>().norm() > 1e-9) {
      ++affected;
      sum2 += f.p_w.x() * f.p_w.x();
    }
  }
  // Gaps of 600 s and bursts of 20 s on average: 20/620 of the time (+-20 % over 58 bursts).
  EXPECT_NEAR(affected / 36001.0, 20.0 / 620.0, 0.0065);
  EXPECT_NEAR(std::sqrt(sum2 / affected), 1.0, 0.15);
  ScenarioConfig slow = testing::Perfect(AtRest(36000.0));
  slow.imu.rate_hz = 1.0;
  slow.gnss.rate_hz = 1.0;
  slow.gnss.slow_drift_sigma_horizontal_m = 0.3;
  slow.gnss.slow_drift_sigma_vertical_m = 0.0;
  slow.gnss.slow_drift_tau_s = 1800.0;
  const Dataset d2 = Simulate(slow, 8);
  double s2 = 0.0, lag = 0.0, step2 = 0.0;
  for (std::size_t k = 0; k < d2.gnss_fixes.size(); ++k) {
    const double x = d2.gnss_fixes[k].p_w.x();
    s2 += x * x;
    if (k > 0) {
      const double x_prev = d2.gnss_fixes[k - 1].p_w.x();
      lag += x * x_prev;
      step2 += (x - x_prev) * (x - x_prev);
    }
  }
  const double n = static_cast<double>(d2.gnss_fixes.size());
  EXPECT_NEAR(std::sqrt(s2 / n), 0.3, 0.1);  // 20 correlation times
  EXPECT_NEAR(lag / s2, std::exp(-1.0 / 1800.0), 1e-3);
  // The correlation time itself: a first-order Gauss-Markov step over dt has the variance
  // 2 sigma^2 (1 - exp(-dt/tau)), 1.0e-4 m^2 here; estimated from 36,000 steps to ~1 %
  // (tau = 1500 s or 2200 s would be 20 % off).
  EXPECT_NEAR(step2 / (n - 1.0) / (2.0 * 0.09 * (1.0 - std::exp(-1.0 / 1800.0))), 1.0, 0.05);
}

// Stamps stay in order and inside the recording: a jitter that could swap two fixes is refused
// (also when the config is built in code, past the parser), and a fix whose latency stamps it
// after the end is not in the data.
TEST(Simulate, FixStampsStayInOrderAndInsideTheRecording) {
  ScenarioConfig c = Harbour(30.0);
  c.gnss.rate_hz = 2.0;
  c.gnss.stamp_jitter_s = 0.1;  // 6 sigma = 0.6 s > 0.5 s
  EXPECT_THROW(Simulate(c, 1), std::invalid_argument);
  c.gnss.stamp_jitter_s = 0.0;
  c.gnss.time_offset_s = 0.0;
  c.gnss.latency_s = 0.3;  // the fix measured at 29.5 s is stamped 29.8 s, at 30 s 30.3 s
  const Dataset d = Simulate(c, 1);
  ASSERT_FALSE(d.gnss_fixes.empty());
  EXPECT_LE(d.gnss_fixes.back().t_ns, SecondsToNs(30.0));
  EXPECT_EQ(d.gnss_fixes.back().t_ns, SecondsToNs(29.8));
  // Jitter with no offset or latency would stamp the first fix before the first IMU sample about
  // half the time: such a fix is not in the recording.
  c.gnss.latency_s = 0.0;
  c.gnss.stamp_jitter_s = 0.01;
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    const Dataset j = Simulate(c, seed);
    ASSERT_FALSE(j.gnss_fixes.empty());
    EXPECT_GE(j.gnss_fixes.front().t_ns, j.imu_samples.front().t_ns) << "seed " << seed;
  }
}

TEST(Simulate, NoFixesDuringOutagesAndOutagesDoNotChangeOtherFixes) {
  ScenarioConfig with = Harbour(600.0);
  with.gnss.time_offset_s = 0.0;  // epochs on whole seconds: the outage window's ends are epochs
  with.gnss.latency_s = 0.0;
  with.gnss.stamp_jitter_s = 0.0;
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

// The receiver's heading is from the local north at the vessel: w's north turned by the
// meridian convergence (0.19 deg 20 km east of the origin at 47 N).
TEST(Simulate, DualAntennaHeadingIsTheBaselineHeading) {
  ScenarioConfig c = testing::Perfect(Harbour(300.0));
  c.gnss.dual_antenna_enabled = true;
  c.gnss.time_offset_s = 0.0;
  c.trajectory.start_enu_m = Eigen::Vector3d(20000.0, 0.0, 0.0);
  const Dataset ds = Simulate(c, 1);
  const EarthModel earth = ds.Earth();
  double max_convergence = 0.0;
  for (const NavState& x : ds.truth_states) {
    for (const GnssFix& f : ds.gnss_fixes) {
      if (f.t_ns != x.t_ns) continue;
      ASSERT_TRUE(f.has_heading);
      const Eigen::Matrix3d R_w_n = earth.LocalLevel(x.p_w_b + x.q_w_b * c.gnss.p_b_g);
      const double local_heading =
          HeadingDeg(Eigen::Quaterniond(R_w_n.transpose() * x.q_w_b.toRotationMatrix()));
      max_convergence = std::max(
          max_convergence, std::abs(std::remainder(local_heading - HeadingDeg(x.q_w_b), 360.0)));
      const double d = std::remainder(f.heading_deg - local_heading, 360.0);
      ASSERT_NEAR(d, 0.0, 1e-9);
      ASSERT_GE(f.heading_deg, 0.0);
      ASSERT_LT(f.heading_deg, 360.0);
    }
  }
  EXPECT_NEAR(max_convergence, 0.19, 0.02);
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
