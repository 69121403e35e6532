// The case the flat-world engine failed (issue 9): the 60-minute, 18 km transit
// (config/scenarios/transit.yaml; tactical IMU, 1 Hz GNSS, outages of 120 s and 300 s) simulated
// once on the round, rotating WGS84 Earth and once in the flat world, same motion and same sensor
// errors, each told to the estimator by its dataset. With the Earth in the mechanisation the
// round run must be as good as the flat one: the outage-end errors within 10 % of each other (the
// requirement), where the flat-world engine on the round Earth was 11x and 110x worse (233 m and
// 3.99 km against 21 m and 36 m) and never recovered after the second outage.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <future>
#include <string>
#include <vector>

#include "skerry/eval/evaluation.h"
#include "skerry/eval/event_metrics.h"
#include "skerry/sim/scenario.h"
#include "skerry/sim/simulator.h"
#include "skerry/solvers/estimator_config.h"
#include "skerry/solvers/pipeline.h"
#include "workload.h"

namespace skerry {
namespace {

struct TransitRun {
  bool diverged = false;
  std::vector<double> outage_end_m;  ///< horizontal error at the end of each outage
  double outside_rmse_m = 0.0;       ///< horizontal RMSE outside the outages
  double final_horizontal_m = 0.0;   ///< at the last estimate
};

// Under the sanitizers (workload.h) only the first outage is flown.
constexpr size_t kOutages = test::Workload(2, 1);

TransitRun RunTransit(EarthKind earth, std::uint64_t seed) {
  sim::ScenarioConfig scenario = sim::LoadScenario("transit");
  scenario.earth.kind = earth;
  if (!test::kFullWorkload) {  // the first 25 minutes: the first outage and three minutes after it
    scenario.duration_s = 1500.0;
    scenario.gnss.outages.resize(kOutages);
  }
  const Dataset data = sim::Simulate(scenario, seed);
  const WindowRun window = RunWindow(data, LoadPreset("default"));
  const EvaluationResult eval = Evaluate(window.records, data.groundtruth);
  const EventMetrics metrics = ComputeEventMetrics(eval, data.events, 30.0, 10.0);
  TransitRun r;
  r.diverged = window.diverged;
  for (const OutageMetric& o : metrics.outages)
    r.outage_end_m.push_back(o.horizontal_error_at_end_m);
  r.outside_rmse_m = metrics.horizontal_outside_outages.rmse;
  if (!eval.epochs.empty()) r.final_horizontal_m = eval.epochs.back().p_err_w.head<2>().norm();
  return r;
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Same motion and same sensor errors in both worlds, but not the same observability (on the round
// Earth the gyros also see the Earth's rate, which helps the heading), so single seeds differ by
// up to 20 % either way; the requirement is on the medians over the ten seeds
// `build/bench/skerry_harbour_monte_carlo --seeds 10 --scenario transit [--earth flat]` reports.
TEST(TransitRoundEarth, OutageEndErrorsMatchTheFlatWorldCopy) {
  constexpr int kSeeds = test::Workload(10, 1);
  std::vector<TransitRun> round, flat;
  for (int seed = 1; seed <= kSeeds; ++seed) {  // two runs at a time
    auto r = std::async(std::launch::async, RunTransit, EarthKind::kWgs84, seed);
    auto f = std::async(std::launch::async, RunTransit, EarthKind::kFlat, seed);
    round.push_back(r.get());
    flat.push_back(f.get());
  }
  for (int k = 0; k < kSeeds; ++k) {
    SCOPED_TRACE("seed " + std::to_string(k + 1));
    ASSERT_FALSE(round[k].diverged);
    ASSERT_FALSE(flat[k].diverged);
    ASSERT_EQ(round[k].outage_end_m.size(), kOutages);
    ASSERT_EQ(flat[k].outage_end_m.size(), kOutages);
    // GNSS is back for the last 15 minutes (3 under the sanitizers): back at GNSS accuracy at the
    // end (the flat-world engine on the round Earth ended 1,146 km off).
    EXPECT_LT(round[k].final_horizontal_m, 3.0);
    EXPECT_LT(flat[k].final_horizontal_m, 3.0);
  }
  if (!test::kFullWorkload) return;  // the requirement is on medians over ten seeds
  for (size_t i = 0; i < kOutages; ++i) {
    std::vector<double> e_round, e_flat;
    for (int k = 0; k < kSeeds; ++k) {
      e_round.push_back(round[k].outage_end_m[i]);
      e_flat.push_back(flat[k].outage_end_m[i]);
    }
    const double m_round = Median(e_round), m_flat = Median(e_flat);
    std::printf(
        "outage %zu: end error median over %d seeds: round %.2f m, flat %.2f m (%+.1f %%)\n", i + 1,
        kSeeds, m_round, m_flat, 100.0 * (m_round - m_flat) / m_flat);
    EXPECT_LE(std::abs(m_round - m_flat), 0.10 * m_flat) << "outage " << i + 1;
  }
  std::vector<double> out_round, out_flat;
  for (int k = 0; k < kSeeds; ++k) {
    out_round.push_back(round[k].outside_rmse_m);
    out_flat.push_back(flat[k].outside_rmse_m);
  }
  std::printf("outside the outages: median horizontal RMSE round %.3f m, flat %.3f m\n",
              Median(out_round), Median(out_flat));
  EXPECT_LT(Median(out_round), 1.5);
  EXPECT_LE(std::abs(Median(out_round) - Median(out_flat)), 0.10 * Median(out_flat));
}

}  // namespace
}  // namespace skerry
