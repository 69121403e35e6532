#include "skerry/eval/span_summary.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace skerry {
namespace {

// Epochs at 10 Hz over [0, 1400] s: the horizontal error grows linearly from 1 m at 100 s to
// 3 m at 1300 s (along east), heading error 0.01 deg, horizontal NEES 2 and 3-D NEES 3 inside.
EvaluationResult Growing() {
  EvaluationResult ev;
  for (int k = 0; k <= 14000; ++k) {
    const double t = 0.1 * k;
    EpochError e;
    e.t_ns = SecondsToNs(t);
    e.p_err_w.x() = 1.0 + 2.0 * (t - 100.0) / 1200.0;
    e.heading_err_deg = (k % 2 == 0 ? 0.01 : -0.01);
    e.has_nees = true;
    e.nees_horizontal = (k % 2 == 0 ? 1.0 : 3.0);
    e.nees_pos = (k % 2 == 0 ? 2.0 : 4.0);
    ev.epochs.push_back(e);
  }
  return ev;
}

TEST(SpanSummary, MeanMaxGrowthAndConsistencyOverTheSpanOnly) {
  const SpanSummary s = SummariseSpan(Growing(), SecondsToNs(100.0), SecondsToNs(1300.0), 300.0);
  EXPECT_EQ(s.count, 12001);
  EXPECT_NEAR(s.horizontal.mean, 2.0, 1e-9);
  EXPECT_NEAR(s.horizontal.max, 3.0, 1e-9);
  EXPECT_NEAR(s.first_mean_m, 1.25, 1e-3);  // mean over [100, 400): 1 + 0.25
  EXPECT_NEAR(s.last_mean_m, 2.75, 1e-3);
  EXPECT_NEAR(s.growth, 2.2, 1e-2);
  EXPECT_NEAR(s.heading_rmse_deg, 0.01, 1e-12);
  EXPECT_EQ(s.nees_count, 12001);
  EXPECT_NEAR(s.anees_horizontal, 2.0, 1e-3);
  EXPECT_NEAR(s.anees_pos, 3.0, 1e-3);
  EXPECT_LT(s.bounds_horizontal.first, 2.0);
  EXPECT_GT(s.bounds_horizontal.second, 2.0);
  EXPECT_LT(s.bounds_pos.first, 3.0);
  EXPECT_GT(s.bounds_pos.second, 3.0);
}

TEST(SpanSummary, BadSpansAreErrors) {
  const EvaluationResult ev = Growing();
  EXPECT_THROW(SummariseSpan(ev, SecondsToNs(10.0), SecondsToNs(5.0)), std::invalid_argument);
  EXPECT_THROW(SummariseSpan(ev, SecondsToNs(2000.0), SecondsToNs(3000.0)), std::invalid_argument);
  EXPECT_THROW(SummariseSpan(ev, 0, SecondsToNs(10.0), 0.0), std::invalid_argument);
  // No covariance: the consistency figures stay empty, the errors are still summarised.
  EvaluationResult bare = ev;
  for (EpochError& e : bare.epochs) e.has_nees = false;
  const SpanSummary s = SummariseSpan(bare, 0, SecondsToNs(1400.0));
  EXPECT_EQ(s.nees_count, 0);
  EXPECT_GT(s.count, 0);
}

}  // namespace
}  // namespace skerry
