// SlidingWindowEstimator::Rebase: the window restarted from its newest keyframe with a prior at
// the current estimate and covariance carries the same information, so the estimate and its
// covariance go on as without it (up to the linearisation points it drops). Harbour seed 1,
// rebased at 100 s, compared with an untouched twin over the next 50 s (one outage-free stretch
// with fixes every 0.5 s).

#include <gtest/gtest.h>

#include <cmath>

#include "skerry/core/heading.h"
#include "skerry/core/so3.h"
#include "skerry/core/time_order.h"
#include "skerry/sim/scenario.h"
#include "skerry/sim/simulator.h"
#include "skerry/solvers/estimator_config.h"
#include "skerry/solvers/sliding_window_estimator.h"
#include "solvers/solver_test_data.h"

namespace skerry {
namespace {

TEST(WindowRebase, KeepsTheEstimateAndItsCovariance) {
  const Dataset data = test::MatchedHarbour(1);
  const EstimatorConfig config = LoadPreset("default");
  SlidingWindowEstimator a(config, data.imu, data.gnss, data.Earth()),
      b(config, data.imu, data.gnss, data.Earth());
  b.Rebase();  // before initialisation: nothing to do
  const TimeNs t0 = data.imu_samples.front().t_ns;
  const TimeNs t_rebase = t0 + SecondsToNs(100.0), t_end = t0 + SecondsToNs(150.0);
  bool rebased = false;
  double max_dp = 0.0, max_dheading = 0.0, max_sigma_ratio = 0.0;
  const Dataset until = DatasetUntil(data, t_end);
  const auto on_gnss = [&](const GnssFix& f) {
    a.AddGnss(f);
    b.AddGnss(f);
  };
  const auto on_imu = [&](const ImuSample& s) {
    a.AddImu(s);
    b.AddImu(s);
    if (!rebased && s.t_ns >= t_rebase) {
      EstimateRecord before;
      ASSERT_TRUE(b.Latest(&before));
      b.Rebase();
      // The rebased graph is one keyframe and its prior: the prior's information must be the
      // covariance the window had (computed anew from the graph, not read back from the
      // window's cache), and it must pull nowhere (its mean is the estimate).
      ASSERT_EQ(b.graph().num_keyframes(), 1u);
      StateCovariance P;
      ASSERT_TRUE(b.graph().NewestCovariance(&P));
      for (int i = 0; i < kStateDim; ++i) {
        for (int j = 0; j < kStateDim; ++j) {
          EXPECT_NEAR(P(i, j), before.covariance(i, j),
                      1e-6 * std::sqrt(before.covariance(i, i) * before.covariance(j, j)))
              << i << "," << j;
        }
      }
      const std::vector<FactorId> priors = b.graph().factor_ids(FactorKind::kMarginalPrior);
      ASSERT_EQ(priors.size(), 1u);
      EXPECT_LT(b.graph().FactorResidual(priors.front()).norm(), 1e-9);
      EXPECT_EQ(b.graph().newest().state().p_w_b, before.state.p_w_b);
      rebased = true;
    }
    if (rebased) {
      EstimateRecord ra, rb;
      ASSERT_TRUE(a.Latest(&ra));
      ASSERT_TRUE(b.Latest(&rb));
      max_dp = std::max(max_dp, (ra.state.p_w_b - rb.state.p_w_b).norm());
      max_dheading =
          std::max(max_dheading,
                   std::abs(WrapAngle((HeadingDeg(ra.state.q_w_b) - HeadingDeg(rb.state.q_w_b)) *
                                      M_PI / 180.0)) *
                       180.0 / M_PI);
      for (int i = 0; i < kStateDim; ++i) {
        const double ratio = std::sqrt(rb.covariance(i, i) / ra.covariance(i, i));
        max_sigma_ratio = std::max(max_sigma_ratio, std::abs(std::log(ratio)));
      }
    }
  };
  ForEachInTimeOrder(until.imu_samples, until.gnss_fixes, on_imu, on_gnss);
  ASSERT_TRUE(rebased);
  EXPECT_LT(max_dp, 0.02);
  EXPECT_LT(max_dheading, 0.01);
  EXPECT_LT(max_sigma_ratio, std::log(1.05));
  std::printf(
      "after rebase: max |dp| %.4f m, max |dheading| %.5f deg, max |log sigma ratio| %.4f\n",
      max_dp, max_dheading, max_sigma_ratio);
}

}  // namespace
}  // namespace skerry
