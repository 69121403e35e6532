// Accuracy around GNSS events: the error at an outage's end, the worst error during a jump, and
// an honest "none" when no estimate lies inside an event.

#include "skerry/eval/event_metrics.h"

#include <gtest/gtest.h>

#include <cmath>

namespace skerry {
namespace {

EpochError At(double t_s, double east_m) {
  EpochError e;
  e.t_ns = SecondsToNs(t_s);
  e.p_err_w = Eigen::Vector3d(east_m, 0.0, 0.0);
  return e;
}

GnssEvent Event(const char* type, double t0_s, double t1_s) {
  GnssEvent ev;
  ev.type = type;
  ev.t_start_ns = SecondsToNs(t0_s);
  ev.t_end_ns = SecondsToNs(t1_s);
  ev.offset_enu_m = Eigen::Vector3d(3.0, 4.0, 0.0);
  return ev;
}

TEST(EventMetrics, OutageEndAndJumpWorst) {
  EvaluationResult ev;
  for (int k = 0; k < 100; ++k) ev.epochs.push_back(At(k, k < 20 ? 0.5 : (k < 40 ? k - 19 : 1.0)));
  const EventMetrics m =
      ComputeEventMetrics(ev, {Event("outage", 20.0, 40.0), Event("jump", 60.0, 70.0)}, 0.0, 0.0);
  ASSERT_EQ(m.outages.size(), 1u);
  EXPECT_DOUBLE_EQ(m.outages[0].horizontal_error_at_end_m, 20.0);  // t = 39 s
  EXPECT_DOUBLE_EQ(m.outages[0].max_horizontal_error_m, 20.0);
  ASSERT_EQ(m.jumps.size(), 1u);
  EXPECT_DOUBLE_EQ(m.jumps[0].offset_m, 5.0);
  EXPECT_DOUBLE_EQ(m.jumps[0].max_horizontal_error_m, 1.0);
  EXPECT_EQ(m.horizontal_outside_outages.count, 80);
}

// Estimates withdrawn by the watchdog leave an event without any: its figures are NaN, not the
// 0 m that would read as perfect.
TEST(EventMetrics, EventWithoutEstimatesIsNaN) {
  EvaluationResult ev;
  for (int k = 0; k < 20; ++k) ev.epochs.push_back(At(k, 0.5));
  for (int k = 50; k < 100; ++k) ev.epochs.push_back(At(k, 0.5));
  const EventMetrics m =
      ComputeEventMetrics(ev, {Event("outage", 20.0, 40.0), Event("jump", 30.0, 45.0)});
  ASSERT_EQ(m.outages.size(), 1u);
  EXPECT_TRUE(std::isnan(m.outages[0].horizontal_error_at_end_m));
  EXPECT_TRUE(std::isnan(m.outages[0].max_horizontal_error_m));
  ASSERT_EQ(m.jumps.size(), 1u);
  EXPECT_TRUE(std::isnan(m.jumps[0].max_horizontal_error_m));
}

}  // namespace
}  // namespace skerry
