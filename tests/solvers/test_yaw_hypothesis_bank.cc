// Start-up with the heading unknown (init.mode "align", YawHypothesisBank), on simulated data
// with exact truth. The harbour IMU is mounted 90 deg to the hull (x to port), so nothing in the
// accelerometer or the first fixes' course gives the heading of the IMU directly; the bank must
// find it from how the fixes follow the integrated motion.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "skerry/core/time_order.h"
#include "skerry/eval/evaluation.h"
#include "skerry/eval/event_metrics.h"
#include "skerry/sim/scenario.h"
#include "skerry/sim/simulator.h"
#include "skerry/solvers/pipeline.h"
#include "skerry/solvers/yaw_hypothesis_bank.h"
#include "solvers/solver_test_data.h"

namespace skerry {
namespace {

EstimatorConfig AlignConfig(double static_s) {
  EstimatorConfig c = LoadPreset("default");
  c.init.mode = "align";
  c.init.static_s = static_s;
  return c;
}

// Feeds a dataset to the bank in time order.
void Feed(const Dataset& data, YawHypothesisBank* bank) {
  ForEachInTimeOrder(
      data.imu_samples, data.gnss_fixes, [bank](const ImuSample& s) { bank->AddImu(s); },
      [bank](const GnssFix& f) { bank->AddGnss(f); });
}

// Heading error (deg) of the record nearest `t_s` seconds after the first truth sample.
double HeadingErrorAt(const EvaluationResult& ev, TimeNs t0, double t_s) {
  const EpochError* best = nullptr;
  for (const EpochError& e : ev.epochs) {
    if (best == nullptr ||
        std::abs(NsToSeconds(e.t_ns - t0) - t_s) < std::abs(NsToSeconds(best->t_ns - t0) - t_s)) {
      best = &e;
    }
  }
  return best == nullptr ? 1e9 : std::abs(best->heading_err_deg);
}

// Moving start, 12 hypotheses 30 deg apart: the bank decides within the harbour's first minute,
// and the kept estimator then meets the same requirements as one started from the course over
// ground with the mounting known.
TEST(YawHypothesisBank, MovingStartFindsTheHeadingOfAnUnknownlyMountedImu) {
  const Dataset data = test::MatchedHarbour(1);
  const EstimatorConfig config = AlignConfig(0.0);
  YawHypothesisBank bank(config, data.imu, data.gnss, data.Earth());
  Feed(data, &bank);
  ASSERT_TRUE(bank.decided());
  const TimeNs t0 = data.imu_samples.front().t_ns;
  const double t_decided = NsToSeconds(bank.decision_t_ns() - t0);
  EXPECT_GE(t_decided, config.init.align_min_s);
  EXPECT_LT(t_decided, 60.0);
  EXPECT_FALSE(bank.undecided());
  // The weights are a distribution and the kept one is the likeliest.
  ASSERT_EQ(bank.scores().size(), 12u);
  ASSERT_GE(bank.kept(), 0);
  double sum = 0.0;
  for (const auto& h : bank.scores()) {
    sum += h.weight;
    EXPECT_LE(h.log_likelihood, bank.scores()[bank.kept()].log_likelihood);
  }
  EXPECT_NEAR(sum, 1.0, 1e-9);

  const EvaluationResult ev = Evaluate(bank.winner()->outputs(), data.groundtruth);
  EXPECT_LT(HeadingErrorAt(ev, t0, t_decided), 5.0);
  EXPECT_LT(HeadingErrorAt(ev, t0, t_decided + 30.0), 1.0);
  const EventMetrics m = ComputeEventMetrics(ev, data.events, 60.0, 10.0);
  EXPECT_LE(m.horizontal_outside_outages.rmse, 0.3);
  EXPECT_LE(m.heading_outside_outages_deg.rmse, 0.5);

  // RunWindow takes the same path for init.mode "align".
  const WindowRun run = RunWindow(data, config);
  ASSERT_EQ(run.records.size(), bank.winner()->outputs().size());
  EXPECT_EQ(run.records.back().state.p_w_b, bank.winner()->outputs().back().state.p_w_b);
  EXPECT_EQ(run.align_decision_t_ns, bank.decision_t_ns());
  EXPECT_EQ(run.align_yaw0_deg, bank.scores()[bank.kept()].yaw0_deg);
  EXPECT_EQ(run.align_weight, bank.scores()[bank.kept()].weight);
}

// Forced to decide before the fixes tell the hypotheses apart (8 s in, align_min_s not reached),
// the kept window's heading sigma is the bank's spread about it: every hypothesis still carries
// weight, so it is tens of degrees, not the kept window's own 7.5 deg (half the spacing).
TEST(YawHypothesisBank, UndecidedKeepsTheBanksSpread) {
  Dataset data = test::MatchedHarbour(1);
  const TimeNs t_cut = data.imu_samples.front().t_ns + SecondsToNs(8.0);
  auto after = [t_cut](const auto& m) { return m.t_ns > t_cut; };
  data.imu_samples.erase(std::find_if(data.imu_samples.begin(), data.imu_samples.end(), after),
                         data.imu_samples.end());
  data.gnss_fixes.erase(std::find_if(data.gnss_fixes.begin(), data.gnss_fixes.end(), after),
                        data.gnss_fixes.end());
  YawHypothesisBank bank(AlignConfig(0.0), data.imu, data.gnss, data.Earth());
  Feed(data, &bank);
  ASSERT_FALSE(bank.decided());
  ASSERT_TRUE(bank.DecideNow());
  const auto& scores = bank.scores();
  const double kept_yaw = scores[bank.kept()].yaw0_deg;
  double second_moment = 0.0, max_weight = 0.0;
  for (const auto& h : scores) {
    const double d = std::remainder(h.yaw0_deg - kept_yaw, 360.0);
    second_moment += h.weight * d * d;
    max_weight = std::max(max_weight, h.weight);
  }
  ASSERT_LT(max_weight, 0.5);  // the premise: undecided
  EXPECT_TRUE(bank.undecided());
  EstimateRecord latest;
  ASSERT_TRUE(bank.winner()->Latest(&latest));
  const double sigma_deg = std::sqrt(latest.covariance(kRot + 2, kRot + 2)) * 180.0 / M_PI;
  // The hypotheses' headings have moved little from their starts in 8 s: the spread of the
  // starting yaws, plus the hypotheses' own 7.5 deg, within 10 %.
  const double expected = std::sqrt(second_moment + 7.5 * 7.5);
  EXPECT_GT(expected, 30.0);
  EXPECT_NEAR(sigma_deg, expected, 0.1 * expected);
}

// A hull at rest for 10 s with a consumer MEMS IMU (gyro bias ~0.1 deg/s): the rest period gives
// the gyro bias to a fraction of its prior, with a sigma that covers the error, and the bank then
// finds the heading once the hull gets under way.
TEST(YawHypothesisBank, StaticStartEstimatesTheGyroBiasThenTheHeading) {
  sim::ScenarioConfig sc = sim::LoadScenario("harbour");
  sc.imu.grade = "consumer";
  sc.imu.errors = sim::ImuGradePreset(sim::ImuGrade::kConsumer);
  sc.duration_s = 240.0;
  sc.gnss.jumps.clear();
  sc.gnss.outages.clear();
  sc.trajectory.start_speed_m_s = 0.0;
  sim::Leg rest;
  rest.type = sim::Leg::Type::kStraight;
  rest.duration_s = 10.0;
  sim::Leg go;
  go.type = sim::Leg::Type::kSpeedChange;
  go.to_m_s = 5.0;
  go.accel_m_s2 = 0.5;
  sc.trajectory.legs.insert(sc.trajectory.legs.begin(), {rest, go});
  const Dataset data = sim::Simulate(sc, 3);
  ASSERT_FALSE(data.truth_states.empty());

  const WindowRun run = RunWindow(data, AlignConfig(8.0));
  ASSERT_FALSE(run.records.empty());
  const EstimateRecord& first = run.records.front();
  const Eigen::Vector3d bg_err = first.state.bg - data.truth_states.front().bg;
  for (int i = 0; i < 3; ++i) {
    const double sigma = std::sqrt(first.covariance(kBg + i, kBg + i));
    EXPECT_LT(std::abs(bg_err[i]), 3.0 * sigma) << "axis " << i;
    EXPECT_LT(sigma, 0.5 * data.imu.gyro_bias_prior_sigma_rad_s) << "axis " << i;
  }
  EXPECT_LT(first.state.v_w.norm(), 1e-9);

  const EvaluationResult ev = Evaluate(run.records, data.groundtruth);
  const TimeNs t0 = data.imu_samples.front().t_ns;
  EXPECT_LT(HeadingErrorAt(ev, t0, 120.0), 2.0);
  EXPECT_LT(HeadingErrorAt(ev, t0, 230.0), 2.0);
}

// GNSS comes up 100 s after the IMU (the IMU before it is dropped as it waits, not replayed):
// the bank starts at the first fix and decides as from the start of the data.
TEST(YawHypothesisBank, FirstFixLateStartsThere) {
  Dataset data = sim::Simulate(sim::LoadScenario("harbour"), 1);
  const TimeNs t0 = data.imu_samples.front().t_ns;
  const TimeNs t_first = t0 + SecondsToNs(100.0);
  data.gnss_fixes.erase(data.gnss_fixes.begin(),
                        std::find_if(data.gnss_fixes.begin(), data.gnss_fixes.end(),
                                     [&](const GnssFix& f) { return f.t_ns >= t_first; }));
  const EstimatorConfig config = AlignConfig(0.0);
  YawHypothesisBank bank(config, data.imu, data.gnss, data.Earth());
  Feed(data, &bank);
  ASSERT_TRUE(bank.decided());
  const auto& out = bank.winner()->outputs();
  ASSERT_FALSE(out.empty());
  EXPECT_GE(out.front().state.t_ns, t_first);
  EXPECT_LT(out.front().state.t_ns, t_first + SecondsToNs(1.0));
  const double t_decided = NsToSeconds(bank.decision_t_ns() - t0);
  EXPECT_GE(t_decided, 100.0 + config.init.align_min_s);
  const EvaluationResult ev = Evaluate(out, data.groundtruth);
  EXPECT_LT(HeadingErrorAt(ev, t0, t_decided + 30.0), 1.0);
}

TEST(YawHypothesisBank, WithoutFixesItNeverStarts) {
  Dataset data = sim::Simulate(sim::LoadScenario("harbour"), 1);
  data.gnss_fixes.clear();
  YawHypothesisBank bank(AlignConfig(0.0), data.imu, data.gnss, data.Earth());
  Feed(data, &bank);
  EXPECT_FALSE(bank.decided());
  EXPECT_FALSE(bank.DecideNow());
  EXPECT_EQ(bank.winner(), nullptr);
  EXPECT_TRUE(RunWindow(data, AlignConfig(0.0)).records.empty());
}

TEST(YawHypothesisBank, TimeMustIncrease) {
  const Dataset data = sim::Simulate(sim::LoadScenario("harbour"), 1);
  YawHypothesisBank bank(AlignConfig(0.0), data.imu, data.gnss, data.Earth());
  bank.AddImu(data.imu_samples[1]);
  EXPECT_THROW(bank.AddImu(data.imu_samples[0]), std::invalid_argument);
  bank.AddGnss(data.gnss_fixes[1]);
  EXPECT_THROW(bank.AddGnss(data.gnss_fixes[1]), std::invalid_argument);
}

}  // namespace
}  // namespace skerry
