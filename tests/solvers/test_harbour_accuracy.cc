// The estimator against ground truth on the simulated harbour scenario (10 min, 2 Hz GNSS with
// drift, a 14.5 m jump for 20 s, a 120 s outage; tactical IMU). These are the acceptance figures
// of the engine: the thresholds are the requirements, not fitted to one run.

#include <gtest/gtest.h>

#include "skerry/core/estimate_io.h"
#include "skerry/core/evaluation.h"
#include "skerry/core/event_metrics.h"
#include "skerry/sim/scenario.h"
#include "skerry/sim/simulator.h"
#include "skerry/solvers/batch_smoother.h"
#include "skerry/solvers/pipeline.h"

namespace skerry {
namespace {

class HarbourAccuracy : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    data_ = new Dataset(sim::Simulate(sim::LoadScenario("harbour"), 1));
    config_ = new EstimatorConfig(LoadPreset("default"));
    window_ = new WindowRun(RunWindow(*data_, *config_));
  }
  static void TearDownTestSuite() {
    delete window_;
    delete config_;
    delete data_;
  }
  static Dataset* data_;
  static EstimatorConfig* config_;
  static WindowRun* window_;
};

Dataset* HarbourAccuracy::data_ = nullptr;
EstimatorConfig* HarbourAccuracy::config_ = nullptr;
WindowRun* HarbourAccuracy::window_ = nullptr;

TEST_F(HarbourAccuracy, WindowMeetsTheHarbourRequirements) {
  ASSERT_FALSE(window_->records.empty());
  // One estimate per keyframe at 10 Hz over (almost) the whole run.
  EXPECT_GT(window_->records.size(), 5900u);
  const EvaluationResult ev = Evaluate(window_->records, data_->groundtruth);
  const EventMetrics m = ComputeEventMetrics(ev, data_->events, 30.0, 10.0);
  EXPECT_LE(m.horizontal_outside_outages.rmse, 0.3);
  EXPECT_LE(m.heading_outside_outages_deg.rmse, 0.5);
  EXPECT_LE(ev.heading_deg.rmse, 0.5);
  ASSERT_EQ(m.jumps.size(), 1u);
  EXPECT_NEAR(m.jumps[0].offset_m, 14.5, 1e-9);
  EXPECT_LT(m.jumps[0].max_horizontal_error_m, 1.0);
  ASSERT_EQ(m.outages.size(), 1u);
  EXPECT_NEAR(m.outages[0].duration_s, 120.0, 1e-9);
  // Free inertial for two minutes: bounded, and within the estimator's own 3-sigma.
  EXPECT_LT(m.outages[0].horizontal_error_at_end_m, 15.0);
  // The gate saw the jump: about 40 fixes rejected, most fixes accepted.
  EXPECT_GE(window_->gnss.rejected, 30);
  EXPECT_GT(window_->gnss.accepted, 900);
}

TEST_F(HarbourAccuracy, OutageErrorIsWithinTheEstimatorsOwnUncertainty) {
  const EvaluationResult ev = Evaluate(window_->records, data_->groundtruth);
  const GnssEvent& outage = data_->events[1].type == "outage" ? data_->events[1] : data_->events[0];
  ASSERT_EQ(outage.type, "outage");
  // Last estimate inside the outage.
  const EstimateRecord* last = nullptr;
  for (const EstimateRecord& r : window_->records) {
    if (r.state.t_ns < outage.t_end_ns) last = &r;
  }
  ASSERT_NE(last, nullptr);
  ASSERT_TRUE(last->has_covariance);
  const EpochError* e = nullptr;
  for (const EpochError& x : ev.epochs) {
    if (x.t_ns == last->state.t_ns) e = &x;
  }
  ASSERT_NE(e, nullptr);
  const Eigen::Matrix2d P = last->covariance.block<2, 2>(kPos, kPos);
  const double d2 = e->p_err_w.head<2>().dot(P.ldlt().solve(e->p_err_w.head<2>()));
  // chi2(2) at 99.9%: 13.8.
  EXPECT_LT(d2, 13.8) << "horizontal error " << e->p_err_w.head<2>().norm() << " m, sigma "
                      << std::sqrt(P.trace()) << " m";
  // The uncertainty grew during the outage and is small again after re-acquisition.
  EXPECT_GT(std::sqrt(P.trace()), 1.0);
  EXPECT_LT(HorizontalSigmaM(window_->records.back().covariance), 0.5);
}

// The window against the best any live estimator could do: the batch smoother over the data up to
// the end of the outage (MAP given everything received so far, nothing marginalised or fixed at
// old linearisation points). If marginalisation threw information away, or FEJ or the window's
// linearisation points biased the estimate, the window's sigma would exceed the batch's, or its
// error would differ. Measured on seed 1: both 8.6 m from the truth with a 5.3 m sigma, so the
// outage error is what the IMU and the fixes allow, not an estimator loss (docs/results.md).
TEST_F(HarbourAccuracy, WindowAtTheOutageEndIsTheBestCausalEstimate) {
  const GnssEvent& outage = data_->events[1].type == "outage" ? data_->events[1] : data_->events[0];
  ASSERT_EQ(outage.type, "outage");
  const BatchResult bound = SmoothUntil(*data_, *config_, *window_, outage.t_end_ns - 1);
  ASSERT_TRUE(bound.usable);
  ASSERT_FALSE(bound.records.empty());
  const EstimateRecord& b = bound.records.back();
  const EstimateRecord* w = nullptr;
  for (const EstimateRecord& r : window_->records) {
    if (r.state.t_ns == b.state.t_ns) w = &r;
  }
  ASSERT_NE(w, nullptr);
  EXPECT_GT(NsToSeconds(b.state.t_ns - outage.t_start_ns), 119.8);
  const auto horizontal_error = [this](const EstimateRecord& r) {
    const EvaluationResult ev = Evaluate({r}, data_->groundtruth);
    return ev.horizontal.max;
  };
  const double e_w = horizontal_error(*w), e_b = horizontal_error(b);
  const double s_w = HorizontalSigmaM(w->covariance), s_b = HorizontalSigmaM(b.covariance);
  // The two estimates agree to a small part of the sigma, and so do the sigmas.
  EXPECT_LT((w->state.p_w_b - b.state.p_w_b).head<2>().norm(), 0.05 * s_b)
      << "window error " << e_w << " m, best causal " << e_b << " m";
  EXPECT_NEAR(s_w / s_b, 1.0, 0.03) << "window sigma " << s_w << " m, best causal " << s_b << " m";
  EXPECT_NEAR(e_w, e_b, 0.05 * s_b);
}

TEST_F(HarbourAccuracy, BatchSmootherIsAtLeastAsAccurateAsTheWindow) {
  const BatchResult batch = SmoothBatch(*data_, *config_, window_->records, window_->decisions);
  ASSERT_TRUE(batch.usable);
  ASSERT_EQ(batch.records.size(), window_->records.size());
  const EvaluationResult ew = Evaluate(window_->records, data_->groundtruth);
  const EvaluationResult eb = Evaluate(batch.records, data_->groundtruth);
  EXPECT_LE(eb.horizontal.rmse, ew.horizontal.rmse);
  EXPECT_LE(eb.heading_deg.rmse, ew.heading_deg.rmse);
  const EventMetrics mb = ComputeEventMetrics(eb, data_->events, 30.0, 10.0);
  const EventMetrics mw = ComputeEventMetrics(ew, data_->events, 30.0, 10.0);
  EXPECT_LE(mb.horizontal_outside_outages.rmse, mw.horizontal_outside_outages.rmse);
  // Smoothing through the outage: both ends are anchored by GNSS.
  EXPECT_LT(mb.outages[0].horizontal_error_at_end_m, 1.0);
  EXPECT_LT(mb.jumps[0].max_horizontal_error_m, 1.0);
  // Every state has a positive-definite marginal covariance.
  for (const EstimateRecord& r : batch.records) {
    ASSERT_TRUE(r.has_covariance);
    const Eigen::Matrix3d P = r.covariance.block<3, 3>(kPos, kPos);
    ASSERT_GT(P.determinant(), 0.0);
  }
}

}  // namespace
}  // namespace skerry
