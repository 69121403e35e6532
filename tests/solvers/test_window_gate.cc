// The window's gate, re-acquisition, robust losses and solver statistics on the matched harbour
// (solver_test_data.h): each test a defect found by review that it would have caught.

#include <gtest/gtest.h>

#include <cmath>

#include "skerry/eval/evaluation.h"
#include "skerry/sim/scenario.h"
#include "skerry/sim/simulator.h"
#include "skerry/solvers/pipeline.h"
#include "solvers/solver_test_data.h"

namespace skerry {
namespace {

Dataset Harbour(double duration_s, std::uint64_t seed = 2) {
  sim::ScenarioConfig sc = test::MatchedScenario("harbour");
  sc.duration_s = duration_s;
  return sim::Simulate(sc, seed);
}

// Index of the first fix at or after t_s (seconds of data).
size_t FixAt(const Dataset& data, double t_s) {
  const TimeNs t = data.imu_samples.front().t_ns + SecondsToNs(t_s);
  for (size_t k = 0; k < data.gnss_fixes.size(); ++k) {
    if (data.gnss_fixes[k].t_ns >= t) return k;
  }
  ADD_FAILURE() << "no fix after " << t_s;
  return 0;
}

void Displace(Dataset* data, size_t k, const Eigen::Vector3d& offset) {
  data->gnss_fixes[k].p_w += offset;
}

// With compute_covariance false the newest covariance was only ever propagated, never updated:
// it grew without bound, the chi-square gate stopped rejecting anything and re-acquisition
// inflated a meaningless matrix. Outputs now carry no covariance, but the gate still has one.
TEST(WindowGate, ComputeCovarianceOffKeepsTheGate) {
  const Dataset data = Harbour(260.0);  // with the 14.5 m jump at 200-220 s
  EstimatorConfig with = LoadPreset("default");
  EstimatorConfig without = with;
  without.compute_covariance = false;
  const WindowRun a = RunWindow(data, with);
  const WindowRun b = RunWindow(data, without);
  EXPECT_GE(a.gnss.rejected, 30);
  EXPECT_EQ(b.gnss.rejected, a.gnss.rejected);
  EXPECT_EQ(b.gnss.reacquired, 0);
  ASSERT_EQ(a.decisions.size(), b.decisions.size());
  for (size_t k = 0; k < a.decisions.size(); ++k) {
    EXPECT_EQ(a.decisions[k].position, b.decisions[k].position) << "fix " << k;
  }
  for (const EstimateRecord& r : b.records) EXPECT_FALSE(r.has_covariance);
  // The estimates are the same: the covariance only ever fed the gate.
  EXPECT_LT((a.records.back().state.p_w_b - b.records.back().state.p_w_b).norm(), 1e-9);
}

// A rejection streak measures time spent rejecting fixes. Before, a single rejection before an
// outage started a streak that the outage stretched past gate_max_reject_s, so the first
// rejected fix after the outage re-initialised the window at once.
TEST(WindowGate, AnOutageBreaksTheRejectionStreak) {
  Dataset data = Harbour(500.0);  // outage 360-480 s
  const size_t before = FixAt(data, 350.0);
  const size_t after = FixAt(data, 480.0);
  ASSERT_GT(NsToSeconds(data.gnss_fixes[after].t_ns - data.gnss_fixes[after - 1].t_ns), 100.0);
  Displace(&data, before, Eigen::Vector3d(60.0, 0.0, 0.0));
  Displace(&data, after + 4, Eigen::Vector3d(0.0, 200.0, 0.0));  // far beyond the outage's drift
  const WindowRun run = RunWindow(data, LoadPreset("default"));
  ASSERT_EQ(run.decisions.size(), data.gnss_fixes.size());
  EXPECT_EQ(run.decisions[before].position, FixDecision::kRejectedByGate);
  EXPECT_EQ(run.decisions[after + 4].position, FixDecision::kRejectedByGate);
  EXPECT_EQ(run.gnss.reacquired, 0);
}

// Ceres counts its iteration 0 (the evaluation at the start) in Summary::iterations; skerry's
// iteration counts are steps tried. With max_iterations 1, no solve may report 2.
TEST(WindowGate, IterationCountsAreStepsTried) {
  const Dataset data = Harbour(40.0);
  EstimatorConfig config = LoadPreset("default");
  config.ceres.max_iterations = 1;
  const WindowRun run = RunWindow(data, config);
  int solves = 0, ones = 0;
  for (const UpdateStats& s : run.stats) {
    if (!s.solved) continue;
    ++solves;
    EXPECT_LE(s.iterations, 1);
    ones += s.iterations == 1;
  }
  EXPECT_GT(solves, 50);
  EXPECT_GT(ones, solves / 2);
}

// The configured robust loss is what the window applies: with the gate off, a fix 5 m off pulls
// the estimate by the least-squares weight with no loss, less with Huber and least with Cauchy.
TEST(WindowGate, TheConfiguredRobustLossIsApplied) {
  Dataset data = Harbour(130.0);
  const size_t k = FixAt(data, 120.0);
  const Dataset clean = data;
  Displace(&data, k, Eigen::Vector3d(5.0, 0.0, 0.0));
  auto pull = [&](LossType loss) {
    EstimatorConfig c = LoadPreset("default");
    c.gnss_gate_probability = 0.0;
    c.gnss_loss = {loss, 3.0};
    const WindowRun bad = RunWindow(data, c), good = RunWindow(clean, c);
    // The estimate at the keyframe the fix went to, with and without the outlier.
    double worst = 0.0;
    EXPECT_EQ(bad.records.size(), good.records.size());
    for (size_t i = 0; i < std::min(bad.records.size(), good.records.size()); ++i) {
      worst = std::max(worst, (bad.records[i].state.p_w_b - good.records[i].state.p_w_b).norm());
    }
    return worst;
  };
  const double none = pull(LossType::kNone), huber = pull(LossType::kHuber),
               cauchy = pull(LossType::kCauchy);
  std::printf("pull of a 5 m outlier: no loss %.3f m, Huber %.3f m, Cauchy %.3f m\n", none, huber,
              cauchy);
  EXPECT_GT(none, 0.3);
  EXPECT_LT(huber, 0.5 * none);
  EXPECT_LT(cauchy, huber);
}

}  // namespace
}  // namespace skerry
