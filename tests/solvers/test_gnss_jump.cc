// A receiver's jump against a drifting estimate (gnss_jump_test.h): the test on numbers, then
// the window on a consumer-grade (MEMS) harbour run with a 14.5 m jump for 20 s.
//
// Measured before the test existed (harbour-consumer seed 1, the window as `skerry run`): the
// gate rejected the jump's fixes until the dead-reckoned covariance let one in at ~215 s, the
// window followed the jump, locked the good fixes out for 27 s after it ended, and re-acquired
// at 247.6 s, 140 m off at worst; with the test the jump's fixes stay out and the error through
// the jump and the minute after it stays under 3 m.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <random>

#include "skerry/core/chi_square.h"
#include "skerry/eval/evaluation.h"
#include "skerry/io/importers.h"
#include "skerry/sim/scenario.h"
#include "skerry/sim/simulator.h"
#include "skerry/solvers/gnss_jump_test.h"
#include "skerry/solvers/pipeline.h"

namespace skerry {
namespace {

const double kGate = ChiSquareQuantile(0.999, 3.0);
constexpr double kMaxGapS = 5.0;

// A fix's innovation y with receiver sigma `sigma_m` on every axis and innovation covariance
// (sigma^2 + p^2) I, p the estimate's own sigma.
MetricInnovation Innov(const Eigen::Vector3d& y, double p_m, double sigma_m = 0.5) {
  MetricInnovation in;
  in.y = y;
  in.R = sigma_m * sigma_m * Eigen::Matrix3d::Identity();
  in.S = (sigma_m * sigma_m + p_m * p_m) * Eigen::Matrix3d::Identity();
  return in;
}

double D2(const MetricInnovation& in) { return in.y.dot(in.S.ldlt().solve(in.y)); }

TimeNs Sec(double s) { return static_cast<TimeNs>(std::llround(s * 1e9)); }

// The window with the default preset, the jump test on or off.
WindowRun RunWithJumpTest(const Dataset& data, bool jump_test) {
  EstimatorConfig config = LoadPreset("default");
  config.gnss_jump_test = jump_test;
  WindowRun run = RunWindow(data, config);
  EXPECT_FALSE(run.diverged) << run.failure;
  return run;
}

TEST(GnssJumpTest, AJumpThatOpenedTheStreakExplainsTheFixesUntilItStepsBack) {
  GnssJumpTest t;
  const Eigen::Vector3d jump(14.5, 0.0, 0.0);
  t.Accepted(Sec(10.0), Innov(Eigen::Vector3d(0.3, -0.2, 0.1), 0.3), kGate);
  EXPECT_EQ(t.StreakStarted(Sec(10.2), Innov(jump, 0.3), kGate, kMaxGapS), StreakStart::kJump);
  EXPECT_NEAR((t.outstanding_m() - Eigen::Vector3d(14.2, 0.2, -0.1)).norm(), 0.0, 1e-12);
  // The estimate dead-reckons and its sigma grows until a jumped fix is inside the gate.
  double p = 0.3;
  bool explained_inside_the_gate = false;
  for (double s = 10.4; s < 20.0; s += 0.2) {
    p += 0.4;
    const MetricInnovation in = Innov(jump + Eigen::Vector3d(0.2 * (s - 10.0), 0.0, 0.0), p);
    t.Observe(Sec(s), in, kGate);
    if (D2(in) <= kGate) {
      EXPECT_TRUE(t.Explains(in, D2(in), kGate)) << "at " << s << " s";
      explained_inside_the_gate = true;
    }
  }
  EXPECT_TRUE(explained_inside_the_gate) << "the premise: a jumped fix gets inside the gate";
  // The receiver steps back: the next fix's innovation is the estimate's own drift.
  const MetricInnovation back = Innov(Eigen::Vector3d(2.1, 0.3, 0.0), p);
  t.Observe(Sec(0), back, kGate);
  EXPECT_LT(t.outstanding_m().norm(), 1.0);
  EXPECT_FALSE(t.Explains(back, D2(back), kGate));
}

TEST(GnssJumpTest, AStreakOpenedByADriftingEstimateIsTheGatesAlone) {
  GnssJumpTest t;
  // The innovation grows smoothly, 0.3 m per fix: no two fixes are a step apart.
  double p = 0.3;
  t.Accepted(Sec(10.0), Innov(Eigen::Vector3d(2.0, 0.0, 0.0), p), kGate);
  p += 0.05;
  EXPECT_EQ(t.StreakStarted(Sec(10.2), Innov(Eigen::Vector3d(2.3, 0.0, 0.0), p), kGate, kMaxGapS),
            StreakStart::kNoStep);
  for (int k = 2; k < 40; ++k) {
    p += 0.05;
    const MetricInnovation in = Innov(Eigen::Vector3d(2.0 + 0.3 * k, 0.0, 0.0), p);
    t.Observe(Sec(10.0 + 0.2 * k), in, kGate);
    EXPECT_FALSE(t.Explains(in, D2(in), kGate)) << k;
  }
  // A receiver stepping further while its fixes are rejected anyway makes no jump either.
  const MetricInnovation stepped = Innov(Eigen::Vector3d(20.0, 0.0, 4.0), p);
  t.Observe(Sec(0), stepped, kGate);
  EXPECT_TRUE(t.outstanding_m().isZero());
}

// Only a step back is followed: one that takes the receiver further off (seed 6 of the MEMS
// harbour: a 3.5 m multipath step while the estimate drifted out of the gate) would make every
// later fix in that direction look like the jump, however far the estimate drifts.
TEST(GnssJumpTest, AStepFurtherOffIsNotAddedToTheJump) {
  GnssJumpTest t;
  t.Accepted(Sec(10.0), Innov(Eigen::Vector3d::Zero(), 0.3), kGate);
  ASSERT_EQ(t.StreakStarted(Sec(10.2), Innov(Eigen::Vector3d(14.5, 0, 0), 0.3), kGate, kMaxGapS),
            StreakStart::kJump);
  t.Observe(Sec(0), Innov(Eigen::Vector3d(14.5, 0.0, 4.0), 0.35), kGate);
  EXPECT_NEAR((t.outstanding_m() - Eigen::Vector3d(14.5, 0, 0)).norm(), 0.0, 1e-12);
  t.Observe(Sec(0), Innov(Eigen::Vector3d(0.2, 0.0, 4.0), 0.4), kGate);  // back in x
  EXPECT_LT(t.outstanding_m().norm(), 0.5);
}

TEST(GnssJumpTest, AStaleReferenceOrAnInvalidInnovationMakesNoJump) {
  GnssJumpTest t;
  t.Accepted(Sec(10.0), Innov(Eigen::Vector3d::Zero(), 0.3), kGate);
  // The last accepted fix is older than the streak gap: after an outage, not a step.
  EXPECT_EQ(t.StreakStarted(Sec(16.0), Innov(Eigen::Vector3d(14.5, 0, 0), 0.3), kGate, kMaxGapS),
            StreakStart::kNoStep);
  MetricInnovation nan = Innov(Eigen::Vector3d(14.5, 0, 0), 0.3);
  nan.y.x() = std::nan("");
  t.Accepted(Sec(20.0), Innov(Eigen::Vector3d::Zero(), 0.3), kGate);
  EXPECT_EQ(t.StreakStarted(Sec(20.2), nan, kGate, kMaxGapS), StreakStart::kNoStep);
  EXPECT_FALSE(t.Explains(nan, 1.0, kGate));
  t.Accepted(Sec(30.0), nan, kGate);  // a covariance that gates nothing: no reference
  EXPECT_EQ(t.StreakStarted(Sec(30.2), Innov(Eigen::Vector3d(14.5, 0, 0), 0.3), kGate, kMaxGapS),
            StreakStart::kNoStep);
  // After Reset the reference is gone.
  t.Accepted(Sec(40.0), Innov(Eigen::Vector3d::Zero(), 0.3), kGate);
  t.Reset();
  EXPECT_EQ(t.StreakStarted(Sec(40.2), Innov(Eigen::Vector3d(14.5, 0, 0), 0.3), kGate, kMaxGapS),
            StreakStart::kNoStep);
}

// The jump as a step for the state (gnss.jump_as_drift_step): the mean over the fixes it explains,
// once it has explained enough of them for long enough; then absorbed, the receiver's step back
// is a jump of its own (the window's position never followed it).
TEST(GnssJumpTest, AJumpBecomesAStepOnceItHasExplainedTheStreak) {
  GnssJumpTest t;
  const Eigen::Vector3d jump(14.5, -1.0, 0.5);  // the receiver's offset: y = predicted - fix
  const double p = 0.3, sigma = 0.5;
  std::mt19937 rng(3);
  std::normal_distribution<double> normal(0.0, sigma);
  const auto noisy = [&](const Eigen::Vector3d& y) {
    return Innov(y + Eigen::Vector3d(normal(rng), normal(rng), normal(rng)), p, sigma);
  };
  t.Accepted(Sec(10.0), noisy(Eigen::Vector3d::Zero()), kGate);
  ASSERT_EQ(t.StreakStarted(Sec(10.1), noisy(-jump), kGate, kMaxGapS), StreakStart::kJump);
  JumpStep step;
  int n = 1;
  for (double s = 10.2; s < 11.05; s += 0.1, ++n) {
    t.Observe(Sec(s), noisy(-jump), kGate);
    EXPECT_FALSE(t.Step(Sec(s), 5, 1.0, kGate, &step)) << "too early at " << s << " s";
  }
  t.Observe(Sec(11.1), noisy(-jump), kGate);
  ++n;
  ASSERT_TRUE(t.Step(Sec(11.1), 5, 1.0, kGate, &step));
  EXPECT_EQ(step.fixes, n);
  // Mean of n fixes: within 4 sigma of the receiver noise over sqrt(n) (the shared estimate's
  // error is zero here), and the covariance says so.
  const Eigen::Matrix3d expected_cov = (p * p + sigma * sigma / n) * Eigen::Matrix3d::Identity();
  EXPECT_LT((step.cov - expected_cov).norm(), 1e-9);
  for (int a = 0; a < 3; ++a) {
    EXPECT_LT(std::abs(step.step_m[a] - jump[a]), 4.0 * sigma / std::sqrt(n)) << a;
  }
  // A fix the jump does not explain (an outlier on top) does not count.
  t.Observe(Sec(11.2), noisy(-jump + Eigen::Vector3d(0.0, 30.0, 0.0)), kGate);
  JumpStep again;
  ASSERT_TRUE(t.Step(Sec(11.2), 5, 1.0, kGate, &again));
  EXPECT_EQ(again.fixes, n);
  // Taken into the state: nothing outstanding, nothing taken in; the receiver's step back is a
  // jump (by -jump) that explains the streak it opens.
  t.Absorbed(Sec(11.3), noisy(Eigen::Vector3d::Zero()));
  EXPECT_TRUE(t.outstanding_m().isZero());
  EXPECT_TRUE(t.taken_m().isZero());
  EXPECT_FALSE(t.Step(Sec(11.3), 1, 0.0, kGate, &step));
  ASSERT_EQ(t.StreakStarted(Sec(11.5), noisy(jump), kGate, kMaxGapS), StreakStart::kJump);
  t.Observe(Sec(11.6), noisy(jump), kGate);
  ASSERT_TRUE(t.Step(Sec(11.6), 2, 0.05, kGate, &step));
  EXPECT_LT((step.step_m + jump).norm(), 4.0 * sigma);
  // A streak the gate opened alone (no step) never becomes one.
  GnssJumpTest drifting;
  drifting.Accepted(Sec(10.0), Innov(Eigen::Vector3d(2.0, 0.0, 0.0), 0.3), kGate);
  ASSERT_EQ(drifting.StreakStarted(Sec(10.2), Innov(Eigen::Vector3d(2.3, 0.0, 0.0), 0.35), kGate,
                                   kMaxGapS),
            StreakStart::kNoStep);
  for (int k = 2; k < 20; ++k) {
    drifting.Observe(Sec(10.0 + 0.2 * k), Innov(Eigen::Vector3d(2.0 + 0.3 * k, 0, 0), 0.4), kGate);
  }
  EXPECT_FALSE(drifting.Step(Sec(14.0), 1, 0.0, kGate, &step));
}

// An IMU that cannot bridge the jump (a rover's, Husky's): the estimate drifts as far as the
// jump, a jumped fix that the jump does not explain better is taken, and the window follows the
// receiver. Its step back is then the end of that jump, not a jump of its own.
TEST(GnssJumpTest, AStepBackFromAJumpTakenInIsTheReceiverComingBack) {
  const Eigen::Vector3d jump(14.5, 0.0, 0.0);
  const auto take_in = [&](GnssJumpTest* t) {
    t->Accepted(Sec(10.0), Innov(Eigen::Vector3d::Zero(), 0.3), kGate);
    ASSERT_EQ(t->StreakStarted(Sec(10.2), Innov(jump, 0.3), kGate, kMaxGapS), StreakStart::kJump);
    // The estimate drifted 25 m across the jump: the fix is no nearer the jump than no jump.
    const MetricInnovation drifted = Innov(Eigen::Vector3d(-6.0, -24.0, 0.0), 25.0);
    t->Observe(Sec(0), drifted, kGate);
    ASSERT_FALSE(t->Explains(drifted, D2(drifted), kGate));
    t->Accepted(Sec(16.0), drifted, kGate);
    EXPECT_NEAR((t->taken_m() - jump).norm(), 0.0, 1e-12);
    EXPECT_TRUE(t->outstanding_m().isZero());
    t->Accepted(Sec(16.4), Innov(Eigen::Vector3d(0.4, 0.1, 0.0), 0.5), kGate);  // following it
  };
  {
    GnssJumpTest t;
    take_in(&t);
    EXPECT_EQ(t.StreakStarted(Sec(16.8), Innov(-jump + Eigen::Vector3d(0.3, 0.2, 0.0), 0.5), kGate,
                              kMaxGapS),
              StreakStart::kBack);
    EXPECT_TRUE(t.outstanding_m().isZero());
    EXPECT_TRUE(t.taken_m().isZero()) << "the jump ended: forgotten";
    // The same step again, from no jump taken in, is a jump.
    t.Accepted(Sec(17.0), Innov(Eigen::Vector3d::Zero(), 0.5), kGate);
    EXPECT_EQ(t.StreakStarted(Sec(17.2), Innov(-jump, 0.5), kGate, kMaxGapS), StreakStart::kJump);
  }
  {
    // A step that does not undo it (across the jump) is a jump of its own; the one taken in stays.
    GnssJumpTest t;
    take_in(&t);
    EXPECT_EQ(
        t.StreakStarted(Sec(16.8), Innov(Eigen::Vector3d(0.0, 14.5, 0.0), 0.5), kGate, kMaxGapS),
        StreakStart::kJump);
    EXPECT_NEAR((t.taken_m() - jump).norm(), 0.0, 1e-12);
  }
  {
    // A jump that had stepped back before a fix was taken is not taken in.
    GnssJumpTest t;
    t.Accepted(Sec(10.0), Innov(Eigen::Vector3d::Zero(), 0.3), kGate);
    ASSERT_EQ(t.StreakStarted(Sec(10.2), Innov(jump, 0.3), kGate, kMaxGapS), StreakStart::kJump);
    t.Observe(Sec(0), Innov(Eigen::Vector3d(0.2, 0.1, 0.0), 0.5), kGate);
    t.Accepted(Sec(10.6), Innov(Eigen::Vector3d(0.3, 0.0, 0.0), 0.5), kGate);
    EXPECT_TRUE(t.taken_m().isZero());
  }
  {
    // Pulled by the jumped fixes it took, the window drifts out of the gate before the receiver
    // steps back: the streak opens without a step, and the step back comes inside it.
    GnssJumpTest t;
    take_in(&t);
    ASSERT_EQ(
        t.StreakStarted(Sec(16.8), Innov(Eigen::Vector3d(2.0, 0.0, 0.0), 0.4), kGate, kMaxGapS),
        StreakStart::kNoStep);
    EXPECT_FALSE(t.Observe(Sec(17.2), Innov(Eigen::Vector3d(2.6, 0.0, 0.0), 0.45), kGate))
        << "the window's own drift is no step";
    EXPECT_NEAR((t.taken_m() - jump).norm(), 0.0, 1e-12);
    EXPECT_FALSE(t.Observe(Sec(17.6), Innov(Eigen::Vector3d(2.9, 14.5, 0.0), 0.5), kGate))
        << "a step across the jump does not undo it";
    EXPECT_NEAR((t.taken_m() - jump).norm(), 0.0, 1e-12);
    EXPECT_TRUE(t.Observe(Sec(18.0), Innov(Eigen::Vector3d(3.3, 14.4, 0.0) - jump, 0.5), kGate));
    EXPECT_TRUE(t.taken_m().isZero()) << "the jump ended: forgotten";
    EXPECT_FALSE(
        t.Observe(Sec(18.4), Innov(Eigen::Vector3d(3.6, 14.4, 0.0) - 2.0 * jump, 0.5), kGate))
        << "the same step again is not a second return";
  }
  {
    // A restart forgets it.
    GnssJumpTest t;
    take_in(&t);
    t.Reset();
    EXPECT_TRUE(t.taken_m().isZero());
  }
  {
    // A re-acquisition on a jumped fix (the jump lasted gate_max_reject_s) takes it in and forgets
    // the rest: no reference until a fix is accepted, then the step back is the receiver back.
    GnssJumpTest t;
    t.Accepted(Sec(10.0), Innov(Eigen::Vector3d::Zero(), 0.3), kGate);
    ASSERT_EQ(t.StreakStarted(Sec(10.2), Innov(jump, 0.3), kGate, kMaxGapS), StreakStart::kJump);
    t.Reacquired(Innov(jump, 0.5), kGate);
    EXPECT_NEAR((t.taken_m() - jump).norm(), 0.0, 1e-12);
    EXPECT_TRUE(t.outstanding_m().isZero());
    EXPECT_EQ(t.StreakStarted(Sec(40.6), Innov(-jump, 0.5), kGate, kMaxGapS), StreakStart::kNoStep);
    t.Accepted(Sec(41.0), Innov(Eigen::Vector3d(0.2, 0.0, 0.0), 0.5), kGate);
    EXPECT_EQ(t.StreakStarted(Sec(41.4), Innov(-jump, 0.5), kGate, kMaxGapS), StreakStart::kBack);
  }
}

// The window on the consumer-grade harbour run as the simulator makes it (realistic receiver,
// MEMS IMU), cut before its outage: with the test, the jump's fixes stay out (the error is the
// IMU's own over the 20 s) and the fixes are taken again within a second of its end; without it
// the window follows the jump and is a hundred metres off after it.
TEST(GnssJumpTest, TheWindowRidesThroughAJumpOnAConsumerImu) {
  sim::ScenarioConfig sc = sim::LoadScenario("harbour-consumer");
  sc.duration_s = 300.0;
  sc.gnss.outages.clear();
  ASSERT_EQ(sc.gnss.jumps.size(), 1u);
  const double jump_start = sc.gnss.jumps[0].start_s;
  const double jump_end = jump_start + sc.gnss.jumps[0].duration_s;
  const Dataset data = sim::Simulate(sc, 1);
  const double t0 = NsToSeconds(data.imu_samples.front().t_ns);

  struct Outcome {
    double worst_m = 0.0;       // horizontal, from the jump's start to 60 s after its end
    double first_taken_s = -1;  // first accepted fix after the jump's end, seconds after it
    int as_jump = 0;
  };
  const auto run_with = [&](bool jump_test) {
    const WindowRun run = RunWithJumpTest(data, jump_test);
    Outcome o;
    for (const EpochError& e : Evaluate(run.records, data.groundtruth).epochs) {
      const double t = NsToSeconds(e.t_ns) - t0;
      if (t >= jump_start && t <= jump_end + 60.0) {
        o.worst_m = std::max(o.worst_m, e.p_err_w.head<2>().norm());
      }
    }
    for (const FixRecord& d : run.decisions) {
      const double t = NsToSeconds(d.t_ns) - t0;
      if (t >= jump_end && o.first_taken_s < 0.0 && d.position == FixDecision::kAccepted) {
        o.first_taken_s = t - jump_end;
      }
    }
    o.as_jump = run.gnss.rejected_as_jump;
    return o;
  };
  const Outcome with = run_with(true);
  const Outcome without = run_with(false);
  std::printf(
      "jump %.0f-%.0f s: worst horizontal error with the test %.2f m (first fix taken %.1f s "
      "after the jump, %d refused as the jump), without %.1f m (%.1f s)\n",
      jump_start, jump_end, with.worst_m, with.first_taken_s, with.as_jump, without.worst_m,
      without.first_taken_s);
  EXPECT_LT(with.worst_m, 5.0);  // 20 s of a MEMS IMU alone: measured 2.8 m
  EXPECT_GE(with.first_taken_s, 0.0);
  EXPECT_LT(with.first_taken_s, 1.0);
  EXPECT_GT(with.as_jump, 0);
  EXPECT_GT(without.worst_m, 10.0) << "the premise: without the test the jump gets in";
  EXPECT_EQ(without.as_jump, 0);
}

// The window that followed a jump and then drifted out of the gate on its own before the receiver
// stepped back (harbour-consumer seed 11, cut before its outage). Measured before the step back
// was looked for inside a streak: the window took the jumped fixes at 217 s (its dead-reckoned
// error had grown to half the jump), their pull on its velocity (1.4 m/s) took it out of the gate
// at 219 s, the receiver's step back at 220 s came inside that streak and was not recognised,
// and the good fixes were locked out until the re-acquisition at 249.6 s, 95 m off. Re-initialised
// on the position alone at the step back, the window was rejected again within a second and the
// watchdog restarted it from the data at 230 s; with the attitude's and velocity's covariance
// widened by its own drift, it is back under a metre at the step back and stays there.
TEST(GnssJumpTest, TheWindowRejoinsAReceiverThatStepsBackInsideAStreak) {
  sim::ScenarioConfig sc = sim::LoadScenario("harbour-consumer");
  sc.duration_s = 300.0;
  sc.gnss.outages.clear();
  ASSERT_EQ(sc.gnss.jumps.size(), 1u);
  const double jump_end = sc.gnss.jumps[0].start_s + sc.gnss.jumps[0].duration_s;
  const Dataset data = sim::Simulate(sc, 11);
  const double t0 = NsToSeconds(data.imu_samples.front().t_ns);
  const WindowRun run = RunWithJumpTest(data, true);
  double followed_m = 0.0, worst_after_m = 0.0;
  for (const EpochError& e : Evaluate(run.records, data.groundtruth).epochs) {
    const double t = NsToSeconds(e.t_ns) - t0;
    const double err = e.p_err_w.head<2>().norm();
    if (t >= jump_end - 2.0 && t < jump_end) followed_m = std::max(followed_m, err);
    if (t >= jump_end + 0.5 && t <= jump_end + 60.0) worst_after_m = std::max(worst_after_m, err);
  }
  std::printf(
      "seed 11: %.1f m off while following the jump, worst %.2f m over the minute after it; %d "
      "re-acquisitions (%d back from the jump), %d watchdog events\n",
      followed_m, worst_after_m, run.gnss.reacquired, run.gnss.reacquired_back_from_jump,
      static_cast<int>(run.events.size()));
  EXPECT_GT(followed_m, 10.0) << "the premise: the window followed the jump";
  EXPECT_EQ(run.gnss.reacquired_back_from_jump, 1);
  EXPECT_LT(worst_after_m, 2.0);
  EXPECT_TRUE(run.events.empty()) << run.events.front().reason;
}

// Real data: Husky's IMU and GPS (robot_localization's test1.bag, ../shared/data/husky) with a
// 14.5 m jump east injected into the fixes from 200 s to 220 s. The rover's IMU drifts about as far
// as the jump in 16 s, so a jumped fix is taken at ~217 s and the window follows the receiver.
// Measured: with the test the receiver's step back re-initialises the window's position at once
// (back under 2 m 0.4 s after the jump, RMS 0.34 m over the minute after it); without it the good
// fixes are locked out until the gate lets them in (5.6 s, RMS 4.19 m), and before the step back
// was told from a jump of its own, they were refused as that jump (8.4 s, 4.32 m).
TEST(GnssJumpTest, TheWindowRejoinsAReceiverBackFromAJumpItFollowedOnRealData) {
  const std::string dir = std::string(SKERRY_SHARED_DATA_DIR) + "/husky";
  if (!std::filesystem::exists(dir)) GTEST_SKIP() << dir << " missing";
  const Dataset truth = ImportHusky(dir);
  Dataset data = truth;
  const TimeNs t0 = data.gnss_fixes.front().t_ns;
  const double start_s = 200.0, end_s = 220.0;
  for (GnssFix& f : data.gnss_fixes) {
    const double t = NsToSeconds(f.t_ns - t0);
    if (t >= start_s && t < end_s) f.p_w.x() += 14.5;
  }
  struct Outcome {
    double rms_after_m = 0.0;  // horizontal, against the un-jumped fixes, the minute after the jump
    double back_s = -1.0;      // first epoch under 2 m after the jump, seconds after it
    int back_from_jump = 0;
  };
  const auto run_with = [&](bool jump_test) {
    const WindowRun run = RunWithJumpTest(data, jump_test);
    Outcome o;
    size_t i = 0, n = 0;
    double sum2 = 0.0;
    for (const GnssFix& f : truth.gnss_fixes) {
      const double t = NsToSeconds(f.t_ns - t0);
      if (t < end_s || t >= end_s + 60.0) continue;
      while (i + 1 < run.records.size() && run.records[i].state.t_ns < f.t_ns) ++i;
      const double e = (run.records[i].state.p_w_b - f.p_w).head<2>().norm();
      sum2 += e * e;
      ++n;
      if (o.back_s < 0.0 && e < 2.0) o.back_s = t - end_s;
    }
    o.rms_after_m = n > 0 ? std::sqrt(sum2 / n) : 1e9;
    o.back_from_jump = run.gnss.reacquired_back_from_jump;
    return o;
  };
  const Outcome with = run_with(true);
  const Outcome without = run_with(false);
  std::printf(
      "the minute after the jump: with the test RMS %.2f m, under 2 m %.1f s after it (%d back "
      "from the jump); without RMS %.2f m, %.1f s\n",
      with.rms_after_m, with.back_s, with.back_from_jump, without.rms_after_m, without.back_s);
  EXPECT_EQ(with.back_from_jump, 1);
  EXPECT_LT(with.rms_after_m, 1.0);
  EXPECT_GE(with.back_s, 0.0);
  EXPECT_LT(with.back_s, 1.5);
  EXPECT_GT(without.rms_after_m, 2.0) << "the premise: the window follows the jump";
  EXPECT_EQ(without.back_from_jump, 0);
}

}  // namespace
}  // namespace skerry
