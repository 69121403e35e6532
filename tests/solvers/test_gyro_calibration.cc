// The gyro's scale factors and misalignment estimated with the states (estimate_gyro_calibration,
// GyroCalibrationJacobians) on the harbour scenario: its IMU matched to the estimator's model but
// for a gyro matrix I + E drawn with sigmas of 2000 ppm and 2 mrad (a consumer part's errors,
// twice over and more, so that three minutes of turns reveal them). The
// truth is the simulator's own draw (sim::SimulatedGyroMatrix). Checked against numbers: the
// estimate of vec(E) against the truth with its covariance (NEES), what the turns teach (the z
// column: the yaw rate's scale and its leak into roll and pitch) against the prior, and the window
// against the best causal estimate (the batch over the same data, SmoothUntil).

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <cmath>

#include "skerry/sim/scenario.h"
#include "skerry/sim/simulator.h"
#include "skerry/solvers/pipeline.h"
#include "solvers/solver_test_data.h"

namespace skerry {
namespace {

constexpr double kScalePpm = 2000.0, kMisalignmentMrad = 2.0;
constexpr double kChi2Nine999 = 27.88;  // chi-square quantile, 9 dof, 0.999

struct Truth {
  Dataset data;
  Eigen::Matrix3d E;
};

// The harbour run up to `until_s`: to 185 s its first two turns, 90 deg at 3 deg/s and -60 at 2.5,
// before the receiver's jump at 200 s and the outage at 360 s.
Truth HarbourWithGyroErrors(std::uint64_t seed, double until_s) {
  sim::ScenarioConfig scenario = test::MatchedScenario("harbour");
  scenario.imu.errors.gyro_scale_factor_ppm = kScalePpm;
  scenario.imu.errors.gyro_misalignment_mrad = kMisalignmentMrad;
  Truth t{DatasetUntil(sim::Simulate(scenario, seed), SecondsToNs(until_s)),
          sim::SimulatedGyroMatrix(scenario.imu.errors, seed) - Eigen::Matrix3d::Identity()};
  return t;
}

// The estimate against the truth: NEES of vec(E) inside its 0.999 bound, and the yaw rate's leak
// into the x and y gyros (k = 6, 7: E_xz, E_yz) learnt, its sigma well below the prior's: a turn
// tilts the attitude by E_xz and E_yz times its angle, which gravity shows. The yaw rate's own
// scale (E_zz) moves only the heading, 0.2 deg per 90 deg turn here, which the GNSS track barely
// resolves in these three minutes: it must not be worse than the prior.
void ExpectConsistentAndLearnt(const GyroCalibrationEstimate& x, const Eigen::Matrix3d& E_true) {
  ASSERT_TRUE(x.estimated);
  ASSERT_TRUE(x.has_covariance);
  const Eigen::Map<const Eigen::Matrix<double, 9, 1>> e(x.E.data()), e_true(E_true.data());
  const Eigen::Matrix<double, 9, 1> d = e - e_true;
  EXPECT_LT(d.dot(x.covariance.ldlt().solve(d)), kChi2Nine999) << "estimate\n"
                                                               << x.E << "\ntruth\n"
                                                               << E_true;
  for (int k = 6; k < 8; ++k) {
    EXPECT_LT(std::sqrt(x.covariance(k, k)), 0.3 * kMisalignmentMrad * 1e-3) << "entry " << k;
  }
  EXPECT_LT(std::sqrt(x.covariance(8, 8)), kScalePpm * 1e-6);
}

TEST(GyroCalibration, TheWindowLearnsWhatTheTurnsRevealAsTheBestCausalEstimate) {
  for (std::uint64_t seed : {1, 2, 3}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const Truth t = HarbourWithGyroErrors(seed, 185.0);
    // The simulator states its datasheet in the dataset: the prior the estimator takes.
    EXPECT_EQ(t.data.imu.gyro_scale_factor_sigma_ppm, kScalePpm);
    EXPECT_EQ(t.data.imu.gyro_misalignment_sigma_mrad, kMisalignmentMrad);
    EstimatorConfig config = LoadPreset("default");
    config.estimate_gyro_calibration = true;
    const WindowRun run = RunWindow(t.data, config);
    {
      SCOPED_TRACE("window");
      ExpectConsistentAndLearnt(run.gyro_calibration, t.E);
    }
    const BatchResult batch = SmoothUntil(t.data, config, run, t.data.imu_samples.back().t_ns);
    ASSERT_TRUE(batch.usable);
    {
      SCOPED_TRACE("batch");
      ExpectConsistentAndLearnt(batch.gyro_calibration, t.E);
    }
    // The window holds what the batch over the same data knows: the same sigmas within 5 % and
    // the same estimate within a quarter of a sigma (neither more confident nor less).
    for (int k = 0; k < 9; ++k) {
      const double sigma_w = std::sqrt(run.gyro_calibration.covariance(k, k));
      const double sigma_b = std::sqrt(batch.gyro_calibration.covariance(k, k));
      EXPECT_NEAR(sigma_w / sigma_b, 1.0, 0.05) << "entry " << k;
      EXPECT_LT(
          std::abs(run.gyro_calibration.E(k % 3, k / 3) - batch.gyro_calibration.E(k % 3, k / 3)),
          0.25 * sigma_b)
          << "entry " << k;
    }
  }
}

// Without the datasheet's sigmas in the dataset nothing is estimated, whatever the preset says,
// and the run is the plain window's to the last bit. With them the default preset estimates it.
TEST(GyroCalibration, NothingIsEstimatedWithoutTheDatasheet) {
  Dataset data = test::MatchedHarbour(2);
  data.imu.gyro_scale_factor_sigma_ppm = 0.0;
  data.imu.gyro_misalignment_sigma_mrad = 0.0;
  const EstimatorConfig preset = LoadPreset("default");
  EXPECT_TRUE(preset.estimate_gyro_calibration);
  EstimatorConfig config = preset;
  config.ceres.max_time_s = 0.0;  // no wall-clock budget: bit-identical runs
  config.estimate_gyro_calibration = false;
  const WindowRun plain = RunWindow(data, config);
  config.estimate_gyro_calibration = true;
  const WindowRun asked = RunWindow(data, config);
  EXPECT_FALSE(plain.gyro_calibration.estimated);
  EXPECT_FALSE(asked.gyro_calibration.estimated);
  ASSERT_EQ(plain.records.size(), asked.records.size());
  for (size_t k = 0; k < plain.records.size(); ++k) {
    ASSERT_EQ(plain.records[k].state.p_w_b, asked.records[k].state.p_w_b) << k;
  }
  data.imu.gyro_misalignment_sigma_mrad = 0.1;
  EXPECT_TRUE(RunWindow(data, preset).gyro_calibration.estimated);
}

}  // namespace
}  // namespace skerry
