// How a GNSS fix enters the graph (solvers/gnss_fix_model.h) and what the window and the batch
// decide about it: each case a defect found by review, with the test that failed before the fix.

#include <gtest/gtest.h>

#include <cmath>

#include "skerry/core/earth_model.h"
#include "skerry/core/heading.h"
#include "skerry/core/so3.h"
#include "skerry/sim/scenario.h"
#include "skerry/sim/simulator.h"
#include "skerry/solvers/batch_smoother.h"
#include "skerry/solvers/gnss_fix_model.h"
#include "skerry/solvers/innovation_gate.h"
#include "skerry/solvers/pipeline.h"
#include "solvers/solver_test_data.h"

namespace skerry {
namespace {

constexpr double kDeg = M_PI / 180.0;

// A keyframe turning at 3 deg/s, and a dual-antenna fix 50 ms later that measures the heading
// there exactly. The factor must see the keyframe's attitude turned by the body rate over the
// 50 ms; before, it compared the keyframe's heading with the fix's: 0.15 deg off, 0.75 of the
// receiver's 0.2 deg sigma, on every fix in every turn.
TEST(GnssFixModel, HeadingFactorTurnsTheKeyframeToTheFixTime) {
  const EarthModel earth(GeoOrigin{47.6, 9.45, 400.0});
  ImuConfig imu;
  imu.q_b_i = Eigen::Quaterniond(Eigen::AngleAxisd(M_PI / 2.0, Eigen::Vector3d::UnitZ()));
  GnssConfig gnss;
  gnss.baseline_b = Eigen::Vector3d(1.0, 0.2, 0.0).normalized();
  const double rate = -3.0 * kDeg;  // starboard turn: heading increases
  Keyframe kf;
  kf.t_ns = SecondsToNs(100.0);
  NavState s;
  s.t_ns = kf.t_ns;
  s.q_w_b = QuaternionFromRollPitchHeading(0.01, -0.02, 70.0 * kDeg);
  s.bg = Eigen::Vector3d(1e-4, -2e-4, 3e-4);
  kf.set_state(s);
  // The IMU reads the body rate (about body z) plus the Earth's rate plus its bias.
  const Eigen::Vector3d omega_b(0.0, 0.0, rate);
  kf.gyro_rad_s =
      imu.q_b_i.conjugate() * (omega_b + s.q_w_b.conjugate() * earth.omega_ie_w()) + s.bg;

  GnssFix fix;
  fix.t_ns = kf.t_ns + SecondsToNs(0.05);
  fix.p_w = Eigen::Vector3d(100.0, 200.0, 0.0);
  const Eigen::Quaterniond q_at_fix = s.q_w_b * ExpQ(Eigen::Vector3d(omega_b * 0.05));
  const Eigen::Vector3d u_n = earth.LocalLevel(fix.p_w).transpose() * (q_at_fix * gnss.baseline_b);
  fix.has_heading = true;
  fix.heading_deg = std::atan2(u_n.x(), u_n.y()) / kDeg;
  fix.sigma_heading_deg = 0.2;

  const TiedFix tied = TieFix(fix, kf, gnss, imu, earth, 1.0);
  EXPECT_NEAR(tied.dt_s, 0.05, 1e-12);
  const std::unique_ptr<ceres::CostFunction> cost = GnssHeadingCost(fix, tied);
  const double* params[] = {kf.q};
  double r = 0.0;
  ASSERT_TRUE(cost->Evaluate(params, &r, nullptr));
  EXPECT_LT(std::abs(r) * 0.2, 1e-4) << "heading residual " << r * 0.2 << " deg";
  // The control: the same fix tied without the turn is the old 0.15 deg error.
  TiedFix unturned = tied;
  unturned.baseline_b = gnss.baseline_b;
  ASSERT_TRUE(GnssHeadingCost(fix, unturned)->Evaluate(params, &r, nullptr));
  EXPECT_NEAR(std::abs(r) * 0.2, 0.15, 0.005);
}

// The window's heading gate and position gate decide per fix; the batch must take exactly the
// headings the window took. Before, the batch re-added every heading whose position was not
// rejected, including the ones the heading gate had thrown out. Harbour (matched) with
// dual-antenna heading, and 20 fixes whose heading is 5 deg off while their position is right.
TEST(GnssFixDecisions, BatchTakesOnlyTheHeadingsTheWindowTook) {
  sim::ScenarioConfig sc = test::MatchedScenario("harbour");
  sc.duration_s = 150.0;
  sc.gnss.jumps.clear();
  sc.gnss.outages.clear();
  sc.gnss.dual_antenna_enabled = true;
  sc.gnss.heading_sigma_deg = 0.2;
  Dataset data = sim::Simulate(sc, 4);
  int corrupted = 0;
  for (GnssFix& f : data.gnss_fixes) {
    const double t = NsToSeconds(f.t_ns);
    if (t > 80.0 && corrupted < 20 && static_cast<int>(t * 2) % 4 == 0) {
      f.heading_deg = std::fmod(f.heading_deg + 5.0, 360.0);
      ++corrupted;
    }
  }
  ASSERT_EQ(corrupted, 20);
  const EstimatorConfig config = LoadPreset("default");
  const WindowRun run = RunWindow(data, config);
  ASSERT_FALSE(run.records.empty());
  EXPECT_GE(run.gnss.heading_rejected, 20);
  ASSERT_EQ(run.decisions.size(), data.gnss_fixes.size());
  int heading_accepted = 0, heading_rejected_position_accepted = 0;
  for (const FixRecord& d : run.decisions) {
    heading_accepted += d.heading == HeadingDecision::kAccepted;
    heading_rejected_position_accepted +=
        d.heading == HeadingDecision::kRejectedByGate && d.position == FixDecision::kAccepted;
  }
  EXPECT_EQ(heading_accepted, run.gnss.heading_accepted);
  EXPECT_GE(heading_rejected_position_accepted, 20);
  const BatchResult batch = SmoothBatch(data, config, run.records, run.decisions);
  ASSERT_TRUE(batch.usable);
  EXPECT_EQ(batch.headings_used, heading_accepted);
  // Decisions are about the fixes in order: a list that does not match them is refused.
  std::vector<FixRecord> shifted(run.decisions.begin() + 1, run.decisions.end());
  EXPECT_THROW(SmoothBatch(data, config, run.records, shifted), std::logic_error);
}

}  // namespace
}  // namespace skerry
