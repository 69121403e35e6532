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
#include <Eigen/LU>
#include <cmath>
#include <limits>

#include "skerry/factors/linear_prior_factor.h"
#include "skerry/sim/scenario.h"
#include "skerry/sim/simulator.h"
#include "skerry/solvers/motion_factors.h"
#include "skerry/solvers/nav_graph.h"
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
    if (seed == 1) {
      // The batch takes the calibration's covariance from the keyframes' covariance pass (the
      // sensor blocks' joint marginal); without that pass, from a pass of its own: the same.
      EstimatorConfig no_covariances = config;
      no_covariances.compute_covariance = false;
      const BatchResult own =
          SmoothUntil(t.data, no_covariances, run, t.data.imu_samples.back().t_ns);
      ASSERT_TRUE(own.gyro_calibration.has_covariance);
      ASSERT_FALSE(own.records.front().has_covariance);
      ASSERT_TRUE(batch.records.front().has_covariance);
      const Eigen::Matrix<double, 9, 1> sd =
          own.gyro_calibration.covariance.diagonal().cwiseSqrt().cwiseInverse();
      EXPECT_LT(
          (sd.asDiagonal() * (batch.gyro_calibration.covariance - own.gyro_calibration.covariance) *
           sd.asDiagonal())
              .cwiseAbs()
              .maxCoeff(),
          1e-6);
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

// What a rebuilt graph (a re-acquisition) starts from: the old graph's estimate with its
// covariance as the prior when that covariance is one, else the datasheet's zero-mean prior. The
// prior's information J^T J is the inverse of that covariance.
TEST(GyroCalibration, ARebuiltGraphCarriesTheEstimateAndItsCovarianceElseTheDatasheet) {
  using Matrix9 = Eigen::Matrix<double, 9, 9>;
  ImuConfig imu;
  imu.gyro_scale_factor_sigma_ppm = 50.0;
  imu.gyro_misalignment_sigma_mrad = 0.1;
  Matrix9 datasheet = Matrix9::Zero();
  for (int k = 0; k < 9; ++k) {
    datasheet(k, k) = k % 3 == k / 3 ? 50e-6 * 50e-6 : 1e-4 * 1e-4;
  }
  ImuCalibration learnt;
  for (int k = 0; k < 9; ++k) learnt.value[k] = 1e-5 * (k + 1) * (k % 2 ? -1.0 : 1.0);
  const Eigen::Matrix<double, 9, 9> A = Eigen::Matrix<double, 9, 9>::Random() * 2e-5;
  const Matrix9 carried = A * A.transpose() + Matrix9::Identity() * 1e-10;

  const auto check = [&](const Matrix9* covariance, const Matrix9& expected_cov,
                         bool expect_learnt) {
    NavGraph graph(false);
    AddImuCalibration(&graph, imu, &learnt, covariance);
    ASSERT_TRUE(graph.has_imu_calibration());
    for (int k = 0; k < 9; ++k) {
      EXPECT_EQ(graph.imu_calibration().value[k], expect_learnt ? learnt.value[k] : 0.0) << k;
    }
    const std::vector<FactorId> priors = graph.factor_ids(FactorKind::kExtrinsicPrior);
    ASSERT_EQ(priors.size(), 1u);
    const auto* prior = dynamic_cast<const LinearPriorFactor*>(&graph.cost_function(priors[0]));
    ASSERT_NE(prior, nullptr);
    ASSERT_EQ(prior->x0().size(), 1u);
    for (int k = 0; k < 9; ++k) EXPECT_EQ(prior->x0()[0][k], graph.imu_calibration().value[k]);
    EXPECT_EQ(prior->r0().norm(), 0.0);
    const Matrix9 cov = (prior->J().transpose() * prior->J()).inverse();
    EXPECT_LT((cov - expected_cov).norm(), 1e-6 * expected_cov.norm()) << cov;
  };
  {
    SCOPED_TRACE("carried");
    check(&carried, carried, true);
  }
  Matrix9 indefinite = carried;
  indefinite(3, 3) = -1e-8;
  {
    SCOPED_TRACE("not positive definite");
    check(&indefinite, datasheet, false);
  }
  Matrix9 nan = carried;
  nan(0, 5) = std::numeric_limits<double>::quiet_NaN();
  {
    SCOPED_TRACE("not finite");
    check(&nan, datasheet, false);
  }
  {
    SCOPED_TRACE("none");
    check(nullptr, datasheet, false);
  }
}

}  // namespace
}  // namespace skerry
