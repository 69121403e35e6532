// The estimator against ground truth on the simulated harbour scenario (10 min, 2 Hz GNSS with
// drift, a 14.5 m jump for 20 s, a 120 s outage; tactical IMU; the round, rotating Earth). These
// are the acceptance figures of the engine: the thresholds are the requirements (0.3 m outside
// the outage and 0.5 deg heading on the median seed with a ceiling on every seed, under 1 m
// while GNSS jumps on every seed) and a consistency test, not fitted to one run.
//
// The requirements are checked over five seeds in the world of the estimator's model
// (solver_test_data.h), where an estimator can be asked to be consistent; the same scenario with
// a real receiver's and IMU's errors (latency, multipath, a second drift, scale factors, a bounded
// bias) is run too, and must stay sound: docs/results.md gives its figures beside these.

#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

#include "skerry/core/chi_square.h"
#include "skerry/eval/evaluation.h"
#include "skerry/eval/event_metrics.h"
#include "skerry/io/estimate_io.h"
#include "skerry/sim/scenario.h"
#include "skerry/sim/simulator.h"
#include "skerry/solvers/batch_smoother.h"
#include "skerry/solvers/pipeline.h"
#include "solvers/solver_test_data.h"
#include "workload.h"

namespace skerry {
namespace {

struct SeedRun {
  Dataset data;
  WindowRun window;
  EvaluationResult eval;
  EventMetrics metrics;
};

std::unique_ptr<SeedRun> RunSeed(const Dataset& data, const EstimatorConfig& config) {
  auto r = std::make_unique<SeedRun>();
  r->data = data;
  r->window = RunWindow(r->data, config);
  r->eval = Evaluate(r->window.records, r->data.groundtruth);
  r->metrics = ComputeEventMetrics(r->eval, r->data.events, 30.0, 10.0);
  return r;
}

// The first GNSS event of `type` ("outage", "jump").
const GnssEvent& FirstEvent(const Dataset& data, const std::string& type) {
  for (const GnssEvent& e : data.events) {
    if (e.type == type) return e;
  }
  ADD_FAILURE() << "no " << type;
  return data.events.front();
}

// The window's last estimate inside the first event of `type`.
const EstimateRecord* LastIn(const SeedRun& r, const std::string& type) {
  const TimeNs end = FirstEvent(r.data, type).t_end_ns;
  const EstimateRecord* last = nullptr;
  for (const EstimateRecord& rec : r.window.records) {
    if (rec.state.t_ns < end) last = &rec;
  }
  return last;
}

class HarbourMatched : public ::testing::Test {
 protected:
  static constexpr int kSeeds = test::Workload(5, 1);
  static void SetUpTestSuite() {
    config_ = new EstimatorConfig(LoadPreset("default"));
    runs_ = new std::vector<std::unique_ptr<SeedRun>>();
    for (int seed = 1; seed <= kSeeds; ++seed) {
      runs_->push_back(RunSeed(test::MatchedHarbour(seed), *config_));
    }
  }
  static void TearDownTestSuite() {
    delete runs_;
    delete config_;
  }
  static EstimatorConfig* config_;
  static std::vector<std::unique_ptr<SeedRun>>* runs_;
};

EstimatorConfig* HarbourMatched::config_ = nullptr;
std::vector<std::unique_ptr<SeedRun>>* HarbourMatched::runs_ = nullptr;

TEST_F(HarbourMatched, WindowMeetsTheHarbourRequirementsOverSeeds) {
  std::vector<double> rmse, heading;
  for (const auto& r : *runs_) {
    SCOPED_TRACE("seed " + std::to_string(&r - &runs_->front() + 1));
    ASSERT_FALSE(r->window.records.empty());
    // One estimate per keyframe at 10 Hz over (almost) the whole run.
    EXPECT_GT(r->window.records.size(), 5900u);
    rmse.push_back(r->metrics.horizontal_outside_outages.rmse);
    heading.push_back(r->metrics.heading_outside_outages_deg.rmse);
    ASSERT_EQ(r->metrics.jumps.size(), 1u);
    EXPECT_NEAR(r->metrics.jumps[0].offset_m, 14.5, 1e-9);
    EXPECT_LT(r->metrics.jumps[0].max_horizontal_error_m, 1.0);
    // The gate saw the jump: about 40 fixes rejected, most fixes accepted.
    EXPECT_GE(r->window.gnss.rejected, 30);
    EXPECT_GT(r->window.gnss.accepted, 880);
    // Free inertial for two minutes: within the estimator's own uncertainty (chi2_2 at 99.9 %).
    const EstimateRecord* last = LastIn(*r, "outage");
    ASSERT_NE(last, nullptr);
    const EvaluationResult e = Evaluate({*last}, r->data.groundtruth);
    ASSERT_EQ(e.epochs.size(), 1u);
    const Eigen::Vector2d dp = e.epochs[0].p_err_w.head<2>();
    const Eigen::Matrix2d P = last->covariance.block<2, 2>(kPos, kPos);
    EXPECT_LT(dp.dot(P.ldlt().solve(dp)), ChiSquareQuantile(0.999, 2.0))
        << "outage end " << dp.norm() << " m, sigma " << HorizontalSigmaM(last->covariance);
    // The uncertainty grew during the outage and is small again after re-acquisition.
    EXPECT_GT(HorizontalSigmaM(last->covariance), 1.0);
    EXPECT_LT(HorizontalSigmaM(r->window.records.back().covariance), 0.5);
  }
  // The requirements on the median seed; no seed far above them (the worst of 20 seeds in the
  // bench: 0.353 m and 0.62 deg, docs/results.md).
  if (!test::kFullWorkload) return;  // statistics over the five seeds
  EXPECT_LE(Percentile(rmse, 50.0), 0.3);
  EXPECT_LE(Percentile(heading, 50.0), 0.5);
  EXPECT_LE(Percentile(rmse, 100.0), 0.4);
  EXPECT_LE(Percentile(heading, 100.0), 0.75);
}

// The Monte-Carlo NEES test (core MonteCarloNeesTest): at every keyframe the position NEES
// averaged over the five runs lies inside its 95 % chi-square bounds about 95 % of the time for
// a consistent estimator, and the time average is 3. A covariance a third too small or too large
// moves the average by a third; a real receiver's errors (HarbourRealWorld) take it to about 6.
TEST_F(HarbourMatched, PositionCovarianceIsConsistentOverSeeds) {
  std::vector<const EvaluationResult*> evals;
  for (const auto& r : *runs_) evals.push_back(&r->eval);
  const NeesTest t =
      MonteCarloNeesTest(evals, kSeeds, 0.95, SecondsToNs(1.0 / config_->keyframe_rate_hz));
  EXPECT_GT(t.epochs, 5900);
  if (!test::kFullWorkload) return;  // a Monte-Carlo test over five seeds
  EXPECT_GT(t.inside, 0.90) << "above " << t.above << ", below " << t.below;
  EXPECT_NEAR(t.time_average, 3.0, 0.6);
}

// The window against the best any live estimator could do: the batch smoother over the data up to
// the end of the outage (MAP given everything received so far, nothing marginalised or fixed at
// old linearisation points), built from the start state alone: its own keyframes, values and fix
// decisions (SmoothUntil). If marginalisation threw information away, or FEJ or the window's
// linearisation points biased the estimate, the window's sigma would exceed the batch's, or its
// estimate would differ. Measured: 0.01-0.15 m apart with 5.1 m sigmas (docs/results.md).
TEST_F(HarbourMatched, WindowAtTheOutageEndIsTheBestCausalEstimate) {
  for (int seed = 1; seed <= test::Workload(3, 1); ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const auto& r = (*runs_)[seed - 1];
    const EstimateRecord* w = LastIn(*r, "outage");
    ASSERT_NE(w, nullptr);
    const BatchResult bound = SmoothUntil(r->data, *config_, r->window, w->state.t_ns);
    ASSERT_TRUE(bound.usable);
    ASSERT_FALSE(bound.records.empty());
    const EstimateRecord& b = bound.records.back();
    ASSERT_EQ(b.state.t_ns, w->state.t_ns);
    const auto horizontal_error = [&r](const EstimateRecord& x) {
      return Evaluate({x}, r->data.groundtruth).horizontal.max;
    };
    const double e_w = horizontal_error(*w), e_b = horizontal_error(b);
    const double s_w = HorizontalSigmaM(w->covariance), s_b = HorizontalSigmaM(b.covariance);
    // The two estimates agree to a small part of the sigma, and so do the sigmas.
    EXPECT_LT((w->state.p_w_b - b.state.p_w_b).head<2>().norm(), 0.05 * s_b)
        << "window error " << e_w << " m, best causal " << e_b << " m";
    EXPECT_NEAR(s_w / s_b, 1.0, 0.03) << "window sigma " << s_w << " m, best causal " << s_b;
  }
}

// The best causal estimate is a reference only if the window cannot steer it: with every window
// estimate after the first moved 100 m and every fix decision turned to a rejection, it is the
// same to the last bit. (It used to start from the window's states and keep its decisions.)
// Under the sanitizers (workload.h) at the end of the GNSS jump (220 s in) rather than of the
// outage (480 s): the same property at a quarter of the batch's cost.
TEST_F(HarbourMatched, BestCausalEstimateIsIndependentOfTheWindow) {
  const auto& r = (*runs_)[0];
  const EstimateRecord* w = LastIn(*r, test::kFullWorkload ? "outage" : "jump");
  ASSERT_NE(w, nullptr);
  WindowRun tampered = r->window;
  for (size_t k = 1; k < tampered.records.size(); ++k) {
    tampered.records[k].state.p_w_b += Eigen::Vector3d(100.0, -100.0, 0.0);
  }
  for (FixRecord& d : tampered.decisions) d.position = FixDecision::kRejectedByGate;
  const BatchResult a = SmoothUntil(r->data, *config_, r->window, w->state.t_ns);
  const BatchResult b = SmoothUntil(r->data, *config_, tampered, w->state.t_ns);
  ASSERT_TRUE(a.usable && b.usable);
  ASSERT_EQ(a.records.size(), b.records.size());
  EXPECT_EQ(a.records.back().state.p_w_b, b.records.back().state.p_w_b);
  EXPECT_EQ(a.records.back().covariance, b.records.back().covariance);
}

TEST_F(HarbourMatched, BatchSmootherIsAtLeastAsAccurateAsTheWindow) {
  const SeedRun& r = *runs_->front();
  const BatchResult batch = SmoothBatch(r.data, *config_, r.window.records, r.window.decisions);
  ASSERT_TRUE(batch.usable);
  ASSERT_EQ(batch.records.size(), r.window.records.size());
  const EvaluationResult eb = Evaluate(batch.records, r.data.groundtruth);
  EXPECT_LE(eb.horizontal.rmse, r.eval.horizontal.rmse);
  EXPECT_LE(eb.heading_deg.rmse, r.eval.heading_deg.rmse);
  const EventMetrics mb = ComputeEventMetrics(eb, r.data.events, 30.0, 10.0);
  EXPECT_LE(mb.horizontal_outside_outages.rmse, r.metrics.horizontal_outside_outages.rmse);
  // Smoothing through the outage: both ends are anchored by GNSS.
  EXPECT_LT(mb.outages[0].horizontal_error_at_end_m, 1.0);
  EXPECT_LT(mb.jumps[0].max_horizontal_error_m, 1.0);
  // Every state has a positive-definite marginal covariance.
  for (const EstimateRecord& x : batch.records) {
    ASSERT_TRUE(x.has_covariance);
    const Eigen::Matrix3d P = x.covariance.block<3, 3>(kPos, kPos);
    ASSERT_GT(P.determinant(), 0.0);
  }
}

// The same with a navigation-grade IMU, whose bias information (1e15-1e20) keeps Ceres from
// converging in the five iterations the best causal estimate allows its growing spans: judging
// the fixes at those unconverged solutions rejected nearly all of them and put it 2.7 km off
// (seed 1) while the window was at 0.15 m. Fixes are now judged only where a span converged.
TEST(HarbourNavigationGrade, WindowAtTheOutageEndIsTheBestCausalEstimate) {
  const EstimatorConfig config = LoadPreset("default");
  sim::ScenarioConfig sc = sim::LoadScenario("harbour");
  sc.imu.grade = "navigation";
  sc.imu.errors = sim::ImuGradePreset(sim::ImuGrade::kNavigation);
  const std::unique_ptr<SeedRun> r =
      RunSeed(sim::Simulate(sim::MatchedToEstimator(sc, test::DriftOf(config)), 1), config);
  const EstimateRecord* w = LastIn(*r, "outage");
  ASSERT_NE(w, nullptr);
  const BatchResult bound = SmoothUntil(r->data, config, r->window, w->state.t_ns);
  ASSERT_TRUE(bound.usable);
  const EstimateRecord& b = bound.records.back();
  const double s_w = HorizontalSigmaM(w->covariance), s_b = HorizontalSigmaM(b.covariance);
  EXPECT_LT((w->state.p_w_b - b.state.p_w_b).head<2>().norm(), 0.1 * s_b);
  EXPECT_NEAR(s_w / s_b, 1.0, 0.05) << "window sigma " << s_w << " m, best causal " << s_b;
  EXPECT_LE(bound.gnss_rejected_after_solve, 45);  // the jump's 40 fixes
}

// The scenario as it is: latency (0.1 m along-track at 5 m/s), multipath bursts, a second GNSS
// process, IMU scale factors and a bounded bias, none of which the estimator models. It must
// still use the fixes, reject the jump and come back after the outage; its accuracy and NEES
// against the matched world's are in docs/results.md.
TEST(HarbourRealWorld, UnmodelledErrorsCostAccuracyButNothingBreaks) {
  const std::unique_ptr<SeedRun> r =
      RunSeed(sim::Simulate(sim::LoadScenario("harbour"), 1), LoadPreset("default"));
  ASSERT_GT(r->window.records.size(), 5900u);
  for (const UpdateStats& s : r->window.stats) EXPECT_TRUE(s.solve_usable);
  EXPECT_GT(r->window.gnss.accepted, 850);
  EXPECT_EQ(r->window.gnss.reacquired, 0);
  EXPECT_LT(r->metrics.jumps[0].max_horizontal_error_m, 1.0);
  EXPECT_LT(r->metrics.horizontal_outside_outages.rmse, 0.6);
  EXPECT_LT(r->metrics.outages[0].horizontal_error_at_end_m, 15.0);
  EXPECT_LT(HorizontalSigmaM(r->window.records.back().covariance), 0.5);
}

}  // namespace
}  // namespace skerry
