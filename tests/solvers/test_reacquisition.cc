// Re-acquisition after the gate has rejected every fix for gate_max_reject_s: the window
// re-initialises from its newest estimate with the covariance inflated so that the fix is a
// typical innovation (SlidingWindowEstimator::Reinitialize).
//
// The case: harbour seed 1 with the estimator told that its IMU is 10x quieter than it is. Through
// the 120 s outage it drifts 8 m while believing 1.4 m, so after the outage the 99.9 % gate rejects
// every fix (position NEES above 100) until gate_max_reject_s = 30 s have passed. Measured: the
// old rule (accept the fix into the overconfident window) left the estimate 3-4.5 m off with a
// 1 m sigma and locked out again for another 30 s (160 fixes rejected, two re-acquisitions);
// re-initialising brings it back to 0.23 m within half a second (100 rejected, one).

#include <gtest/gtest.h>

#include <cmath>

#include "skerry/core/chi_square.h"
#include "skerry/core/evaluation.h"
#include "skerry/sim/scenario.h"
#include "skerry/sim/simulator.h"
#include "skerry/solvers/pipeline.h"
#include "solvers/solver_test_data.h"

namespace skerry {
namespace {

constexpr double kNoiseUnderstatement = 10.0;

class Reacquisition : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    data_ = new Dataset(test::MatchedHarbour(1));
    ImuNoise& n = data_->imu.noise;  // what the estimator is told, not what the IMU does
    n.gyro_noise_density_rad_s_sqrt_hz /= kNoiseUnderstatement;
    n.accel_noise_density_m_s2_sqrt_hz /= kNoiseUnderstatement;
    n.gyro_bias_random_walk_rad_s2_sqrt_hz /= kNoiseUnderstatement;
    n.accel_bias_random_walk_m_s3_sqrt_hz /= kNoiseUnderstatement;
    config_ = new EstimatorConfig(LoadPreset("default"));
    run_ = new WindowRun(RunWindow(*data_, *config_));
    eval_ = new EvaluationResult(Evaluate(run_->records, data_->groundtruth));
  }
  static void TearDownTestSuite() {
    delete eval_;
    delete run_;
    delete config_;
    delete data_;
  }

  // Index of the record whose time is closest to `t_s` seconds after the first record.
  static size_t RecordAt(double t_s) {
    const TimeNs t0 = run_->records.front().state.t_ns;
    size_t best = 0;
    for (size_t k = 0; k < run_->records.size(); ++k) {
      if (std::abs(NsToSeconds(run_->records[k].state.t_ns - t0) - t_s) <
          std::abs(NsToSeconds(run_->records[best].state.t_ns - t0) - t_s)) {
        best = k;
      }
    }
    return best;
  }
  static const EpochError& ErrorAt(size_t k) {
    for (const EpochError& e : eval_->epochs) {
      if (e.t_ns == run_->records[k].state.t_ns) return e;
    }
    ADD_FAILURE() << "no evaluated epoch for record " << k;
    return eval_->epochs.front();
  }

  static Dataset* data_;
  static EstimatorConfig* config_;
  static WindowRun* run_;
  static EvaluationResult* eval_;
};

Dataset* Reacquisition::data_ = nullptr;
EstimatorConfig* Reacquisition::config_ = nullptr;
WindowRun* Reacquisition::run_ = nullptr;
EvaluationResult* Reacquisition::eval_ = nullptr;

TEST_F(Reacquisition, OverconfidentWindowIsLockedOutAfterTheOutage) {
  // The premise of the other tests: the outage ends at 480 s, the fixes are rejected until 510 s.
  const size_t k = RecordAt(509.9);
  const EpochError& e = ErrorAt(k);
  EXPECT_GT(e.p_err_w.head<2>().norm(), 5.0);
  EXPECT_GT(e.nees_pos, 50.0);
  int rejected_after_outage = 0;
  for (const FixRecord& d : run_->decisions) {
    const double t_s = NsToSeconds(d.t_ns - run_->records.front().state.t_ns);
    if (t_s >= 480.0 && d.position == FixDecision::kRejectedByGate) ++rejected_after_outage;
  }
  EXPECT_GE(rejected_after_outage, 59);  // 30 s at 2 Hz
}

TEST_F(Reacquisition, WindowIsReinitialisedOnceAndIsConsistentAgain) {
  ASSERT_EQ(run_->gnss.reacquired, 1);
  TimeNs t_reacquired = 0;
  for (const FixRecord& d : run_->decisions) {
    if (d.position == FixDecision::kAcceptedOnReacquisition) t_reacquired = d.t_ns;
  }
  const double t_s = NsToSeconds(t_reacquired - run_->records.front().state.t_ns);
  EXPECT_NEAR(t_s, 480.0 + config_->gnss_gate_max_reject_s, 1.0);
  // No second lock-out: only the jump's fixes (about 40) and the 30 s after the outage (60).
  EXPECT_LE(run_->gnss.rejected, 110);
  const double gate = ChiSquareQuantile(0.999, 3.0);
  for (double after_s : {0.5, 2.0, 5.0, 10.0, 30.0}) {
    const EpochError& e = ErrorAt(RecordAt(t_s + after_s));
    EXPECT_LT(e.p_err_w.head<2>().norm(), 1.0) << after_s << " s after re-acquisition";
    EXPECT_LT(e.nees_pos, gate) << after_s << " s after re-acquisition";
  }
}

TEST_F(Reacquisition, InflationStopsAtTheBiasPriors) {
  TimeNs t_reacquired = 0;
  for (const FixRecord& d : run_->decisions) {
    if (d.position == FixDecision::kAcceptedOnReacquisition) t_reacquired = d.t_ns;
  }
  ASSERT_GT(t_reacquired, 0);
  const EstimateRecord* first_after = nullptr;
  for (const EstimateRecord& r : run_->records) {
    if (r.state.t_ns >= t_reacquired) {
      first_after = &r;
      break;
    }
  }
  ASSERT_NE(first_after, nullptr);
  ASSERT_TRUE(first_after->has_covariance);
  const StateCovariance& P = first_after->covariance;
  for (int i = 0; i < 3; ++i) {
    EXPECT_LE(std::sqrt(P(kBg + i, kBg + i)), data_->imu.gyro_bias_prior_sigma_rad_s * 1.000001);
    EXPECT_LE(std::sqrt(P(kBa + i, kBa + i)), data_->imu.accel_bias_prior_sigma_m_s2 * 1.000001);
  }
}

}  // namespace
}  // namespace skerry
