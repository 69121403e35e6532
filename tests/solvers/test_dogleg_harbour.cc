// Regression test for the dogleg-sparse preset on the harbour scenario (seed 1).
//
// Ceres' dogleg regularises its Gauss-Newton step with mu * diag(J^T J), mu >= 1e-8 whatever the
// trust region radius. The window's GNSS-determined directions lie below that floor (the IMU
// factors carry far more information per column), so every window solve hit its iteration cap
// having moved them a few percent of the way; the estimate drifted kilometres off and the gate
// rejected every fix after the first ~40 solves. MakeSolverOptions now clamps dogleg's diagonal
// to a constant (docs/configuration.md); these tests pin the option and the accuracy it buys.

#include <gtest/gtest.h>

#include "skerry/eval/evaluation.h"
#include "skerry/eval/event_metrics.h"
#include "skerry/sim/scenario.h"
#include "skerry/sim/simulator.h"
#include "skerry/solvers/nav_graph.h"
#include "skerry/solvers/pipeline.h"
#include "solvers/solver_test_data.h"

namespace skerry {
namespace {

TEST(DoglegOptions, DiagonalIsClampedToAConstantForDoglegOnly) {
  CeresConfig dogleg;
  dogleg.trust_region = "dogleg";
  const ceres::Solver::Options d = MakeSolverOptions(dogleg);
  EXPECT_EQ(d.trust_region_strategy_type, ceres::DOGLEG);
  EXPECT_EQ(d.max_lm_diagonal, d.min_lm_diagonal);
  std::string why;
  EXPECT_TRUE(d.IsValid(&why)) << why;

  dogleg.dogleg_type = "subspace";
  const ceres::Solver::Options s = MakeSolverOptions(dogleg);
  EXPECT_EQ(s.max_lm_diagonal, s.min_lm_diagonal);

  // Levenberg-Marquardt keeps Ceres' defaults: its damping follows the trust region radius.
  const ceres::Solver::Options lm = MakeSolverOptions(CeresConfig{});
  EXPECT_EQ(lm.max_lm_diagonal, ceres::Solver::Options{}.max_lm_diagonal);
  EXPECT_EQ(lm.min_lm_diagonal, ceres::Solver::Options{}.min_lm_diagonal);
}

TEST(DoglegHarbour, DoglegSparseMatchesTheHarbourRequirements) {
  const Dataset data = test::MatchedHarbour(1);
  const EstimatorConfig config = LoadPreset("dogleg-sparse");
  ASSERT_EQ(config.ceres.trust_region, "dogleg");
  const WindowRun run = RunWindow(data, config);

  // Diverged, the window solved ~40 times before the gate locked every fix out; healthy, it
  // solves at every accepted fix (920 on this seed, as the default preset does).
  int solves = 0, capped = 0;
  for (const UpdateStats& s : run.stats) {
    if (!s.solved) continue;
    ++solves;
    EXPECT_TRUE(s.solve_usable);
    if (s.iterations >= config.ceres.max_iterations) ++capped;
  }
  EXPECT_GT(solves, 900);
  // Converged solves: only a handful may reach the iteration cap (before: every one did).
  EXPECT_LT(capped, 20) << "of " << solves << " solves";
  EXPECT_GT(run.gnss.accepted, 900);

  const EvaluationResult ev = Evaluate(run.records, data.groundtruth);
  const EventMetrics m = ComputeEventMetrics(ev, data.events, 30.0, 10.0);
  EXPECT_LE(m.horizontal_outside_outages.rmse, 0.3);
  EXPECT_LE(m.heading_outside_outages_deg.rmse, 0.5);
  ASSERT_EQ(m.jumps.size(), 1u);
  EXPECT_LT(m.jumps[0].max_horizontal_error_m, 1.0);
  ASSERT_EQ(m.outages.size(), 1u);
  EXPECT_LT(m.outages[0].horizontal_error_at_end_m, 15.0);
}

}  // namespace
}  // namespace skerry
