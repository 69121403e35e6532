// Faults through the API (issue "Robustness", item 3): what NavigationEstimator does with bad
// measurements and bad sensors, each outcome defined (refused with a reason, bridged, rejected
// by the gate, re-acquired) and measured on a realistic harbour run: the estimate never becomes
// NaN, and the run recovers to its normal accuracy within a stated time. docs/robustness.md has
// the table this test prints.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include "skerry/core/time_order.h"
#include "skerry/solvers/navigation_estimator.h"
#include "solvers/solver_test_data.h"

namespace skerry {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

using Item = std::variant<ImuSample, GnssFix>;

TimeNs TimeOf(const Item& item) {
  return std::holds_alternative<ImuSample>(item) ? std::get<ImuSample>(item).t_ns
                                                 : std::get<GnssFix>(item).t_ns;
}
bool IsImu(const Item& item) { return std::holds_alternative<ImuSample>(item); }

/// IMU samples and fixes in the order RunWindow gives them (core/time_order.h).
std::vector<Item> Merge(const std::vector<ImuSample>& imu, const std::vector<GnssFix>& fixes) {
  std::vector<Item> feed;
  ForEachInTimeOrder(
      imu, fixes, [&](const ImuSample& s) { feed.emplace_back(s); },
      [&](const GnssFix& f) { feed.emplace_back(f); });
  return feed;
}

/// The realistic harbour cut to 300 s, without its own GNSS jump and outage, and its feed.
struct Recording {
  Dataset data;
  std::vector<Item> feed;  // in the order RunWindow would give them
  TimeNs t0 = 0;
};

const Recording& Harbour() {
  static const Recording r = [] {
    Recording x;
    sim::ScenarioConfig sc = sim::LoadScenario("harbour");
    sc.duration_s = 300.0;
    sc.gnss.jumps.clear();
    sc.gnss.outages.clear();
    x.data = sim::Simulate(sc, 11);
    x.feed = Merge(x.data.imu_samples, x.data.gnss_fixes);
    x.t0 = x.data.imu_samples.front().t_ns;
    return x;
  }();
  return r;
}

TimeNs At(double s) { return Harbour().t0 + SecondsToNs(s); }

struct Outcome {
  int refused = 0;                 ///< calls that threw std::invalid_argument
  bool all_finite = true;          ///< every estimate finite
  int fixes_rejected = 0;          ///< by the gate
  int restarts = 0;                ///< watchdog events
  double first_rejected_s = kInf;  ///< the first fix the gate rejected (s from the start)
  int reacquisitions = 0;          ///< fixes that re-initialised the window
  std::string event_reasons;       ///< the watchdog's, joined
  std::vector<std::pair<double, double>> errors;  ///< (s from the start, horizontal error m)
  double max_error_after(double from_s) const {
    double m = 0.0;
    for (const auto& [t, e] : errors) {
      if (t >= from_s) m = std::max(m, e);
    }
    return m;
  }
  /// Seconds after `from_s` until the error stays below `bound` for the rest of the run
  /// (infinity: it never does).
  double recovery_s(double from_s, double bound) const {
    double last_bad = from_s;
    bool any = false;
    for (const auto& [t, e] : errors) {
      if (t < from_s) continue;
      any = true;
      if (!(e < bound)) last_bad = t;
    }
    if (!any) return kInf;
    return last_bad >= errors.back().first ? kInf : last_bad - from_s;
  }
};

/// A long run hands the estimates over as they become final (NavigationEstimator::TakeFinal):
/// `pieces`, taken every few measurements, must be exactly what the estimator kept whole (`e`),
/// through every restart, lock-out and re-acquisition a fault causes; `most_held` (the most
/// estimates the handing-over estimator held at once) must stay bounded.
void ExpectPiecesAreTheWhole(const NavigationEstimator& e,
                             const EstimatorHistory& pieces,
                             size_t most_held) {
  const std::vector<EstimateRecord> outputs = e.outputs();
  ASSERT_EQ(pieces.outputs.size(), outputs.size());
  for (size_t k = 0; k < outputs.size(); ++k) {
    ASSERT_EQ(pieces.outputs[k].state.t_ns, outputs[k].state.t_ns) << k;
    ASSERT_NEAR((pieces.outputs[k].state.p_w_b - outputs[k].state.p_w_b).norm(), 0.0, 1e-9) << k;
    ASSERT_NEAR((pieces.outputs[k].covariance - outputs[k].covariance).norm(), 0.0,
                1e-9 * (1.0 + outputs[k].covariance.norm()))
        << k;
  }
  const std::vector<UpdateStats> stats = e.update_stats();
  ASSERT_EQ(pieces.stats.size(), stats.size());
  for (size_t k = 0; k < stats.size(); ++k) {
    ASSERT_EQ(pieces.stats[k].t_ns, stats[k].t_ns) << k;
    ASSERT_EQ(pieces.stats[k].iterations, stats[k].iterations) << k;
  }
  const std::vector<FixRecord> decisions = e.fix_decisions();
  ASSERT_EQ(pieces.decisions.size(), decisions.size());
  for (size_t k = 0; k < decisions.size(); ++k) {
    ASSERT_EQ(pieces.decisions[k].t_ns, decisions[k].t_ns) << k;
    ASSERT_EQ(pieces.decisions[k].position, decisions[k].position) << k;
    ASSERT_EQ(pieces.decisions[k].heading, decisions[k].heading) << k;
  }
  // What the watchdog may still withdraw: from a lock-out (up to gnss_gate_max_reject_s before
  // its re-acquisition) while that re-acquisition is judged (watchdog.window_s), with a few
  // seconds for the window and the IMU a restart redoes. A bound of the configuration, not of
  // the run's length (3000 keyframes here, 864,000 in a day).
  const EstimatorConfig c = LoadPreset("default");
  const double held_s = c.watchdog.window_s + c.gnss_gate_max_reject_s + 10.0;
  EXPECT_LT(most_held, static_cast<size_t>(held_s * c.keyframe_rate_hz));
}

/// Feeds `feed` (after `fault` rewrote it) through a NavigationEstimator with the default
/// configuration (or `config`); a refused call is counted and the feed goes on. With
/// `hand_over`, a second estimator takes the same feed and hands its estimates over as a long run
/// does (ExpectPiecesAreTheWhole): on the faults that restart, lock out and re-acquire (it
/// doubles the time, which the sanitizer suite feels).
Outcome RunWithFault(const std::function<void(std::vector<Item>*)>& fault,
                     bool hand_over = false,
                     const EstimatorConfig& config = LoadPreset("default")) {
  const Recording& r = Harbour();
  std::vector<Item> feed = r.feed;
  if (fault) fault(&feed);
  NavigationEstimator e(config, r.data.imu, r.data.gnss, r.data.Earth());
  NavigationEstimator handing_over(config, r.data.imu, r.data.gnss, r.data.Earth());
  EstimatorHistory pieces;
  size_t most_held = 0, k = 0;
  Outcome o;
  for (const Item& item : feed) {
    for (NavigationEstimator* x : {&e, &handing_over}) {
      if (x == &handing_over && !hand_over) continue;
      try {
        if (IsImu(item)) {
          x->AddImu(std::get<ImuSample>(item));
        } else {
          x->AddGnss(std::get<GnssFix>(item));
        }
      } catch (const std::invalid_argument&) {
        o.refused += x == &e;
      }
    }
    if (hand_over && ++k % 97 == 0) {
      handing_over.TakeFinal(&pieces);
      most_held = std::max(most_held, handing_over.outputs().size());
    }
  }
  e.Finish();
  if (hand_over) {
    handing_over.Finish();
    handing_over.TakeFinal(&pieces);
    EXPECT_TRUE(handing_over.outputs().empty());
    ExpectPiecesAreTheWhole(e, pieces, most_held);
  }
  for (const EstimateRecord& rec : e.outputs()) {
    const NavState& s = rec.state;
    o.all_finite = o.all_finite && s.p_w_b.allFinite() && s.v_w.allFinite() &&
                   s.q_w_b.coeffs().allFinite() && s.bg.allFinite() && s.ba.allFinite();
    NavState truth;
    if (!test::TruthStateAt(r.data, s.t_ns, &truth)) continue;
    o.errors.emplace_back(NsToSeconds(s.t_ns - r.t0), (s.p_w_b - truth.p_w_b).head<2>().norm());
  }
  o.fixes_rejected = e.gnss_stats().rejected;
  o.reacquisitions = e.gnss_stats().reacquired;
  for (const FixRecord& d : e.fix_decisions()) {
    if (d.position == FixDecision::kRejectedByGate) {
      o.first_rejected_s = std::min(o.first_rejected_s, NsToSeconds(d.t_ns - r.t0));
    }
  }
  o.restarts = static_cast<int>(e.events().size());
  for (const EstimatorEvent& ev : e.events()) o.event_reasons += ev.reason + "; ";
  return o;
}

/// Inserts `extra` before the first item of the feed at or after `t`.
void InsertBefore(std::vector<Item>* feed, TimeNs t, const Item& extra, bool imu) {
  auto it = std::find_if(feed->begin(), feed->end(),
                         [&](const Item& x) { return TimeOf(x) >= t && IsImu(x) == imu; });
  feed->insert(it, extra);
}

ImuSample SampleAt(const std::vector<Item>& feed, TimeNs t) {
  for (const Item& x : feed) {
    if (IsImu(x) && TimeOf(x) >= t) return std::get<ImuSample>(x);
  }
  return {};
}

GnssFix FixAt(const std::vector<Item>& feed, TimeNs t) {
  for (const Item& x : feed) {
    if (!IsImu(x) && TimeOf(x) >= t) return std::get<GnssFix>(x);
  }
  return {};
}

class ApiFaults : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    clean_ = new Outcome(RunWithFault(nullptr, /*hand_over=*/true));
    // Normal accuracy: three times the clean run's worst error after its first minute, at
    // least a metre.
    bound_m_ = std::max(1.0, 3.0 * clean_->max_error_after(60.0));
  }
  static void TearDownTestSuite() { delete clean_; }

  // Every outcome: finite, and a line of the table in docs/robustness.md.
  void Report(const char* fault,
              const Outcome& o,
              double fault_start_s,
              double fault_end_s,
              const char* outcome) {
    EXPECT_TRUE(o.all_finite) << fault;
    ASSERT_FALSE(o.errors.empty()) << fault;
    const double recovery = o.recovery_s(fault_end_s, bound_m_);
    std::printf(
        "| %s | %s | %d | %d | %d | %.2f | %s |\n", fault, outcome, o.refused,
        o.fixes_rejected - clean_->fixes_rejected, o.restarts, o.max_error_after(fault_start_s),
        std::isinf(recovery) ? "never" : (std::to_string(recovery).substr(0, 5) + " s").c_str());
    if (!o.event_reasons.empty()) std::printf("  watchdog: %s\n", o.event_reasons.c_str());
  }

  static Outcome* clean_;
  static double bound_m_;
};
Outcome* ApiFaults::clean_ = nullptr;
double ApiFaults::bound_m_ = 0.0;

TEST_F(ApiFaults, CleanRun) {
  std::printf("normal accuracy bound: %.2f m (3x the clean run's worst after 60 s)\n", bound_m_);
  std::printf(
      "| fault | outcome | refused | extra fixes rejected | watchdog events | max error from the "
      "fault on (m) | back within the bound after its end |\n");
  Report("none", *clean_, 60.0, 60.0, "-");
  EXPECT_EQ(clean_->refused, 0);
}

// The start by heading hypotheses (init.mode align): the bank's estimates, and the fixes it
// dropped before its hypotheses started, are handed over as a single window's are.
TEST_F(ApiFaults, AnAlignedStartHandsOverItsHistoryAsAWindowDoes) {
  EstimatorConfig config = LoadPreset("default");
  config.init.mode = "align";
  const Outcome o = RunWithFault(nullptr, /*hand_over=*/true, config);
  EXPECT_TRUE(o.all_finite);
  EXPECT_GT(o.errors.size(), 1000u);
}

// Handing over before anything was measured (a given first state starts the window at once)
// takes nothing; then what the first seconds made.
TEST(TakeFinal, BeforeTheFirstMeasurementThereIsNothingToTake) {
  const Recording& r = Harbour();
  NavigationEstimator e(LoadPreset("default"), r.data.imu, r.data.gnss, r.data.Earth());
  e.SetInitialState(r.data.truth_states.front(), StateCovariance::Identity() * 1e-2);
  EstimatorHistory taken;
  e.TakeFinal(&taken);
  EXPECT_TRUE(taken.empty());
  for (const Item& item : r.feed) {
    if (TimeOf(item) > At(10.0)) break;
    if (IsImu(item)) {
      e.AddImu(std::get<ImuSample>(item));
    } else {
      e.AddGnss(std::get<GnssFix>(item));
    }
  }
  e.TakeFinal(&taken);
  EXPECT_GT(taken.outputs.size(), 50u);  // 10 keyframes a second, up to a second ago
  EXPECT_LE(taken.outputs.back().state.t_ns, At(9.0));
}

TEST_F(ApiFaults, NonFiniteImuValuesAreRefusedAndBridged) {
  const Outcome o = RunWithFault([](std::vector<Item>* feed) {
    for (const double bad : {kNaN, kInf, -kInf}) {
      ImuSample s = SampleAt(*feed, At(100.0));
      s.gyro_rad_s.y() = bad;
      InsertBefore(feed, At(100.0), s, true);
      s = SampleAt(*feed, At(150.0));
      s.accel_m_s2.z() = bad;
      InsertBefore(feed, At(150.0), s, true);
    }
  });
  Report("NaN / Inf in an IMU sample (6)", o, 100.0, 150.0,
         "refused (std::invalid_argument), next sample bridges");
  EXPECT_EQ(o.refused, 6);
  EXPECT_LT(o.recovery_s(100.0, bound_m_), 1.0);
}

TEST_F(ApiFaults, NonFiniteOrNonPositiveFixesAreRefused) {
  const Outcome o = RunWithFault([](std::vector<Item>* feed) {
    int k = 0;
    for (Item& x : *feed) {
      if (IsImu(x) || TimeOf(x) < At(100.0) || k >= 5) continue;
      GnssFix& f = std::get<GnssFix>(x);
      switch (k++) {
        case 0:
          f.lat_deg = kNaN;
          break;
        case 1:
          f.p_w.x() = kInf;
          break;
        case 2:
          f.sigma_enu_m.x() = 0.0;
          break;  // a covariance that is not positive definite
        case 3:
          f.sigma_enu_m.z() = -1.0;
          break;
        default:
          f.sigma_enu_m.y() = kNaN;
          break;
      }
    }
  });
  Report("NaN / Inf position, zero / negative / NaN sigma in a fix (5)", o, 100.0, 105.0,
         "refused (std::invalid_argument)");
  EXPECT_EQ(o.refused, 5);
  EXPECT_LT(o.recovery_s(100.0, bound_m_), 1.0);
}

TEST_F(ApiFaults, TimeGoingBackwardsAndDuplicatesAreRefused) {
  const Outcome o = RunWithFault([](std::vector<Item>* feed) {
    ImuSample back = SampleAt(*feed, At(100.0));
    back.t_ns -= SecondsToNs(1.0);
    InsertBefore(feed, At(100.02), back, true);
    const ImuSample dup = SampleAt(*feed, At(120.0));
    InsertBefore(feed, At(120.02), dup, true);
    GnssFix old = FixAt(*feed, At(130.0));
    old.t_ns -= SecondsToNs(5.0);
    InsertBefore(feed, At(131.0), old, false);
    const GnssFix dup_fix = FixAt(*feed, At(140.0));
    InsertBefore(feed, At(141.0), dup_fix, false);
  });
  Report("time backwards / duplicate stamp, IMU and GNSS (4)", o, 100.0, 141.0,
         "refused (std::invalid_argument)");
  EXPECT_EQ(o.refused, 4);
  EXPECT_LT(o.recovery_s(100.0, bound_m_), 1.0);
}

void DropImu(std::vector<Item>* feed, double from_s, double to_s) {
  feed->erase(std::remove_if(feed->begin(), feed->end(),
                             [&](const Item& x) {
                               return IsImu(x) && TimeOf(x) >= At(from_s) && TimeOf(x) < At(to_s);
                             }),
              feed->end());
}

TEST_F(ApiFaults, AnImuGapOfOneSecondIsBridged) {
  const Outcome o = RunWithFault([](std::vector<Item>* feed) { DropImu(feed, 100.0, 101.0); });
  Report("IMU gap of 1 s", o, 100.0, 101.0, "bridged (one preintegration over the gap)");
  EXPECT_EQ(o.restarts, 0);
  EXPECT_LT(o.recovery_s(101.0, bound_m_), 5.0);
}

TEST_F(ApiFaults, AnImuGapOfAMinuteIsBridgedByGnss) {
  const Outcome o = RunWithFault([](std::vector<Item>* feed) { DropImu(feed, 100.0, 160.0); },
                                 /*hand_over=*/true);
  Report("IMU gap of 60 s", o, 100.0, 160.0,
         "fixes rejected, re-acquired, watchdog restart from the data");
  EXPECT_LT(o.recovery_s(160.0, bound_m_), 30.0);
}

TEST_F(ApiFaults, GnssStampedLateIsNotDetected) {
  const Outcome o = RunWithFault([](std::vector<Item>* feed) {
    std::vector<GnssFix> late = Harbour().data.gnss_fixes;
    for (GnssFix& f : late) f.t_ns += SecondsToNs(0.2);
    *feed = Merge(Harbour().data.imu_samples, late);
  });
  Report("GNSS clock 0.2 s late", o, 60.0, 60.0,
         "not detected: an along-track bias of speed x 0.2 s");
  EXPECT_TRUE(o.all_finite);
}

TEST_F(ApiFaults, SaturatedGyroIsBridgedByGnss) {
  const Outcome o = RunWithFault(
      [](std::vector<Item>* feed) {
        for (Item& x : *feed) {
          if (!IsImu(x) || TimeOf(x) < At(100.0) || TimeOf(x) >= At(130.0)) continue;
          ImuSample& s = std::get<ImuSample>(x);
          s.gyro_rad_s = s.gyro_rad_s.cwiseMax(-0.02).cwiseMin(0.02);
          s.accel_m_s2 = s.accel_m_s2.cwiseMax(-9.0).cwiseMin(9.0);
        }
      },
      /*hand_over=*/true);
  Report("IMU clipped for 30 s (gyro 0.02 rad/s, accel 9 m/s^2)", o, 100.0, 130.0,
         "not detected; GNSS holds the position");
  EXPECT_LT(o.recovery_s(130.0, bound_m_), 60.0);
}

/// Moves every fix in [from_s, to_s) east by `east_m(fix)`, its latitude and longitude with it.
void MoveFixesEast(std::vector<Item>* feed,
                   double from_s,
                   double to_s,
                   const std::function<double(const GnssFix&)>& east_m) {
  const LocalFrame frame(Harbour().data.origin);
  for (Item& x : *feed) {
    if (IsImu(x) || TimeOf(x) < At(from_s) || TimeOf(x) >= At(to_s)) continue;
    GnssFix& f = std::get<GnssFix>(x);
    f.p_w.x() += east_m(f);
    const Eigen::Vector3d llh = frame.ToGeodetic(f.p_w);
    f.lat_deg = llh.x();
    f.lon_deg = llh.y();
    f.height_m = llh.z();
  }
}

void Jump(std::vector<Item>* feed, double from_s, double to_s, double east_m) {
  MoveFixesEast(feed, from_s, to_s, [east_m](const GnssFix&) { return east_m; });
}

TEST_F(ApiFaults, AOneKilometreJumpIsRejectedByTheGate) {
  const Outcome one =
      RunWithFault([](std::vector<Item>* feed) { Jump(feed, 100.0, 100.4, 1000.0); });
  Report("GNSS 1 km jump, one fix", one, 100.0, 100.4, "rejected by the gate");
  EXPECT_LT(one.max_error_after(99.0), bound_m_);
  const Outcome held =
      RunWithFault([](std::vector<Item>* feed) { Jump(feed, 100.0, 130.0, 1000.0); }, true);
  Report("GNSS 1 km jump held 30 s", held, 100.0, 130.0, "rejected; the fixes after it accepted");
  EXPECT_LT(held.recovery_s(130.0, bound_m_), 30.0);
}

// A spoofer that drags every fix away smoothly, east at `rate` m/s from t = 100 s on. Each fix is
// then only a little off the last, so the gate (which judges a fix against the window's
// prediction from the IMU and the fixes before) sees nothing until the drag outruns what the
// IMU can hold the position to; the estimate follows the spoofer before that. What IMU + GNSS
// alone can detect, and at what rate: docs/robustness.md.
TEST_F(ApiFaults, ASmoothSpooferIsDetectedOnlyWhenItOutrunsTheImu) {
  for (const double rate : {0.02, 0.1, 0.5, 2.0, 10.0}) {
    const Outcome o = RunWithFault(
        [rate](std::vector<Item>* feed) {
          MoveFixesEast(feed, 100.0, 1e6, [rate](const GnssFix& f) {
            return rate * NsToSeconds(f.t_ns - At(100.0));
          });
        },
        /*hand_over=*/rate == 2.0);  // rejected, re-acquired, restarted
    const double dragged_m = rate * (300.0 - 100.0);
    const double error_end = o.errors.back().second;
    const int rejected = o.fixes_rejected - clean_->fixes_rejected;
    const double seen_after_s = o.first_rejected_s - 100.0;
    const std::string seen = rejected > 0
                                 ? "first rejection " + std::to_string(seen_after_s).substr(0, 5) +
                                       " s after its start (" +
                                       std::to_string(rate * seen_after_s).substr(0, 5) + " m off)"
                                 : std::string("not detected");
    std::printf(
        "| spoofer %.2f m/s from 100 s (%.0f m by the end) | %s | %d rejected, %d "
        "re-acquisitions | error at the end %.1f m |\n",
        rate, dragged_m, seen.c_str(), rejected, o.reacquisitions - clean_->reacquisitions,
        error_end);
    EXPECT_TRUE(o.all_finite);
    if (rate <= 0.1) {
      // Too slow for IMU + GNSS to see: the estimate goes with it, nothing is rejected.
      EXPECT_EQ(rejected, 0) << rate;
      EXPECT_GT(error_end, 0.5 * dragged_m) << rate;
    }
    if (rate >= 2.0) {
      EXPECT_GT(rejected, 0) << rate << " m/s went unnoticed";
    }
  }
}

}  // namespace
}  // namespace skerry
