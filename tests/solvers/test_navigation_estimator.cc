// NavigationEstimator: the defaults start on platforms that neither move fast nor carry a
// dual-antenna receiver, rest is found in the IMU, and the watchdog restarts a window that has
// lost the truth and gives up, saying why, on one that cannot be saved.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "skerry/eval/evaluation.h"
#include "skerry/io/importers.h"
#include "skerry/sim/scenario.h"
#include "skerry/sim/simulator.h"
#include "skerry/solvers/navigation_estimator.h"
#include "skerry/solvers/pipeline.h"
#include "skerry/solvers/rest_detection.h"
#include "solvers/solver_test_data.h"

namespace skerry {
namespace {

const std::string kEurocDir = std::string(SKERRY_SHARED_DATA_DIR) + "/euroc_v1_01";

bool HasEvent(const WindowRun& run, EstimatorEvent::Kind kind) {
  return std::any_of(run.events.begin(), run.events.end(),
                     [kind](const EstimatorEvent& e) { return e.kind == kind; });
}

// Errors of the records after `after_s` seconds of data.
EvaluationResult ScoreAfter(const Dataset& data, const WindowRun& run, double after_s) {
  std::vector<EstimateRecord> kept;
  const TimeNs t = data.imu_samples.front().t_ns + SecondsToNs(after_s);
  for (const EstimateRecord& r : run.records) {
    if (r.state.t_ns >= t) kept.push_back(r);
  }
  return Evaluate(kept, data.groundtruth);
}

// A survey boat at 0.3 m/s covers 6 m in init.max_cog_time_s: the course over ground never came
// and the default start waited forever. It now falls back to the yaw-hypothesis bank.
TEST(NavigationEstimatorStart, DefaultsStartASlowSurveyBoat) {
  sim::ScenarioConfig sc = sim::LoadScenario("slow-survey");
  sc.duration_s = 300.0;
  const Dataset data = sim::Simulate(sc, 1);
  const WindowRun run = RunWindow(data, LoadPreset("default"));
  ASSERT_FALSE(run.records.empty());
  EXPECT_FALSE(run.diverged);
  EXPECT_TRUE(HasEvent(run, EstimatorEvent::Kind::kFellBackToAlign));
  EXPECT_GT(run.align_decision_t_ns, 0);
  const EvaluationResult ev = ScoreAfter(data, run, 120.0);
  EXPECT_LT(ev.horizontal.rmse, 0.6);
  EXPECT_LT(ev.heading_deg.rmse, 3.0);
}

// The first fix is the position plus the receiver's drift, which may be anywhere in its
// stationary distribution: the first state's position variance is the fix's (times
// init.position_sigma_scale) plus the drift's, not the fix's alone (docs/estimator.md, Start-up).
TEST(NavigationEstimatorStart, TheFirstPositionCarriesTheReceiversDrift) {
  sim::ScenarioConfig sc = sim::LoadScenario("harbour");
  sc.duration_s = 30.0;
  const Dataset data = sim::Simulate(sc, 1);
  EstimatorConfig without = LoadPreset("default");
  without.gnss_drift.sigma_horizontal_m = 0.0;
  without.gnss_drift.sigma_vertical_m = 0.0;
  EstimatorConfig with = LoadPreset("default");
  with.gnss_drift.sigma_horizontal_m = 2.0;
  with.gnss_drift.sigma_vertical_m = 3.0;
  const WindowRun a = RunWindow(data, without), b = RunWindow(data, with);
  ASSERT_FALSE(a.records.empty());
  ASSERT_FALSE(b.records.empty());
  const EstimateRecord &ra = a.records.front(), &rb = b.records.front();
  ASSERT_TRUE(ra.has_covariance && rb.has_covariance);
  ASSERT_EQ(ra.state.t_ns, rb.state.t_ns);
  const Eigen::Vector3d added =
      (rb.covariance.diagonal() - ra.covariance.diagonal()).segment<3>(kPos);
  EXPECT_NEAR(added.x(), 4.0, 1e-9);
  EXPECT_NEAR(added.y(), 4.0, 1e-9);
  EXPECT_NEAR(added.z(), 9.0, 1e-9);
  // Everything else of the start is the same.
  EXPECT_NEAR((rb.covariance.diagonal() - ra.covariance.diagonal()).segment<3>(kRot).norm(), 0.0,
              1e-15);
  EXPECT_NEAR((rb.state.p_w_b - ra.state.p_w_b).norm(), 0.0, 1e-12);
}

// A vessel at anchor: no way on, swinging and rolling. The heading comes from the antenna's
// swing about the IMU; measured 6 deg RMS after the decision (docs/results.md).
TEST(NavigationEstimatorStart, DefaultsStartAVesselAtAnchor) {
  sim::ScenarioConfig sc = sim::LoadScenario("at-anchor");
  sc.duration_s = 300.0;
  const Dataset data = sim::Simulate(sc, 1);
  const WindowRun run = RunWindow(data, LoadPreset("default"));
  ASSERT_FALSE(run.records.empty());
  EXPECT_FALSE(run.diverged);
  EXPECT_TRUE(HasEvent(run, EstimatorEvent::Kind::kFellBackToAlign));
  const EvaluationResult ev = ScoreAfter(data, run, 120.0);
  EXPECT_LT(ev.horizontal.rmse, 1.0);
  EXPECT_LT(ev.heading_deg.rmse, 15.0);
}

TEST(RestDetection, FindsTheRestOfARealMavAndNoneOnAMovingOrRollingHull) {
  if (!std::filesystem::exists(kEurocDir)) GTEST_SKIP() << kEurocDir << " missing";
  // EuRoC V1_01: on the ground with its motors running (gyro shaking 0.01-0.1 rad/s) until it
  // takes off 5.0 s in (the Vicon truth starts moving at 5.0-5.5 s).
  const Dataset euroc = ImportEuroc(kEurocDir);
  const RestPeriod rest = DetectRestAtStart(euroc.imu_samples, euroc.imu, euroc.earth.gravity_m_s2);
  EXPECT_TRUE(rest.decided);
  EXPECT_NEAR(rest.duration_s, 5.0, 0.6);
  for (const char* name : {"harbour", "at-anchor"}) {
    SCOPED_TRACE(name);
    sim::ScenarioConfig sc = sim::LoadScenario(name);
    sc.duration_s = 40.0;
    const Dataset d = sim::Simulate(sc, 2);
    const RestPeriod r = DetectRestAtStart(d.imu_samples, d.imu, 9.807);
    EXPECT_TRUE(r.decided);
    EXPECT_EQ(r.duration_s, 0.0);
  }
  // Truly at rest on the quay: all of the 30 s looked at.
  sim::ScenarioConfig quay = sim::LoadScenario("harbour");
  quay.duration_s = 40.0;
  quay.trajectory.start_speed_m_s = 0.0;
  quay.trajectory.legs.clear();
  quay.waves = sim::WaveSpec();
  const Dataset q = sim::Simulate(quay, 2);
  const RestPeriod r = DetectRestAtStart(q.imu_samples, q.imu, 9.807);
  EXPECT_TRUE(r.decided);
  EXPECT_EQ(r.duration_s, kRestMaxS);
}

// EuRoC with init.mode align and the rest period denied (static_s 0): the MAV's gyro bias of
// 0.077 rad/s is 77 sigma of the sensor's prior, every hypothesis drifts off and re-acquisition
// cannot hold it (it used to run to 13.8 km and report ANEES 9000 as a result). The watchdog
// restarts it with wider bias priors, and the kilometres of lost estimates are withdrawn.
TEST(NavigationEstimatorWatchdog, RestartsAWindowThatLostTheTruth) {
  if (!std::filesystem::exists(kEurocDir)) GTEST_SKIP() << kEurocDir << " missing";
  Dataset data = ImportEuroc(kEurocDir);
  AddFixesFromGroundTruth(2.0, 0.5, 1, &data);
  EstimatorConfig config = LoadPreset("default");
  config.init.mode = "align";
  config.init.static_s = 0.0;
  EstimatorConfig unwatched = config;
  unwatched.watchdog.enabled = false;
  const WindowRun blind = RunWindow(data, unwatched);
  const WindowRun watched = RunWindow(data, config);
  const EvaluationResult eb = Evaluate(blind.records, data.groundtruth);
  const EvaluationResult ew = Evaluate(watched.records, data.groundtruth);
  std::printf(
      "EuRoC, align without its rest: unwatched max %.0f m, watched max %.0f m, %zu of "
      "%zu keyframes kept\n",
      eb.horizontal.max, ew.horizontal.max, watched.records.size(), blind.records.size());
  EXPECT_GT(eb.horizontal.max, 1000.0);
  EXPECT_TRUE(HasEvent(watched, EstimatorEvent::Kind::kRestarted));
  EXPECT_LT(ew.horizontal.max, 0.1 * eb.horizontal.max);
  EXPECT_LT(watched.records.size(), blind.records.size());  // the lost stretch is withdrawn
  // Time still increases through the records.
  for (size_t k = 1; k < watched.records.size(); ++k) {
    ASSERT_GT(watched.records[k].state.t_ns, watched.records[k - 1].state.t_ns);
  }
}

// Harbour with a gyro bias drawn with sigma 0.3 rad/s while the dataset tells the estimator 1e-6.
Dataset HopelessGyroBias() {
  sim::ScenarioConfig sc = test::MatchedScenario("harbour");
  sc.duration_s = 600.0;
  sc.gnss.outages.clear();
  sc.imu.errors.gyro_bias_initial_sigma_rad_s = 0.3;
  Dataset data = sim::Simulate(sc, 3);
  data.imu.gyro_bias_prior_sigma_rad_s = 1e-6;  // what the estimator is told
  return data;
}

int Restarts(const WindowRun& run) {
  return static_cast<int>(std::count_if(
      run.events.begin(), run.events.end(),
      [](const EstimatorEvent& e) { return e.kind == EstimatorEvent::Kind::kRestarted; }));
}

// A gyro bias beyond anything the estimator may assume (0.5 rad/s; the dataset's prior says 1e-6
// and even widened a thousandfold by three restarts it stays far below): the watchdog gives up,
// the run is marked diverged and says why.
TEST(NavigationEstimatorWatchdog, GivesUpOnAnEstimatorThatCannotBeSavedAndSaysWhy) {
  const Dataset data = HopelessGyroBias();
  const WindowRun run = RunWindow(data, LoadPreset("default"));
  EXPECT_TRUE(run.diverged);
  EXPECT_TRUE(HasEvent(run, EstimatorEvent::Kind::kGaveUp));
  EXPECT_NE(run.failure.find("diverged"), std::string::npos) << run.failure;
  const int restarts = Restarts(run);
  EXPECT_EQ(restarts, LoadPreset("default").watchdog.max_restarts);
}

// The same hopeless gyro bias, started from a given state with init.mode align (a user who knows
// the first state): every restart must start again from the data (the course over ground), not
// wait for a given state that never comes a second time, so the watchdog restarts as often as it
// may and then gives up; the records it kept stay in time order.
TEST(NavigationEstimatorWatchdog, RestartsAGivenStartInAlignModeFromTheData) {
  const Dataset data = HopelessGyroBias();
  EstimatorConfig config = LoadPreset("default");
  config.init.mode = "align";
  EstimateRecord first;
  first.state = data.truth_states.front();
  first.state.bg.setZero();
  first.state.ba.setZero();
  first.has_covariance = true;
  first.covariance.diagonal() << 1e-4, 1e-4, 1e-3, 0.25, 0.25, 0.25, 0.01, 0.01, 0.01, 1e-12, 1e-12,
      1e-12, 1e-4, 1e-4, 1e-4;
  const WindowRun run = RunWindow(data, config, {}, &first);
  const int restarts = Restarts(run);
  EXPECT_EQ(restarts, config.watchdog.max_restarts);
  EXPECT_TRUE(run.diverged);
  for (size_t k = 1; k < run.records.size(); ++k) {
    ASSERT_GT(run.records[k].state.t_ns, run.records[k - 1].state.t_ns);
  }
}

// On the data skerry is tested on every day the watchdog stays quiet.
TEST(NavigationEstimatorWatchdog, StaysQuietOnAHealthyRun) {
  const WindowRun run = RunWindow(test::MatchedHarbour(1), LoadPreset("default"));
  EXPECT_TRUE(run.events.empty());
  EXPECT_FALSE(run.diverged);
}

}  // namespace
}  // namespace skerry
