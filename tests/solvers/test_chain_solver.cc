// The batch's own Levenberg-Marquardt over the keyframe chain (NavGraph::SolveChain with
// block_tridiagonal.h) against dense linear algebra and against Ceres on the same problems.

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>
#include <random>

#include "skerry/core/so3.h"
#include "skerry/sim/scenario.h"
#include "skerry/sim/simulator.h"
#include "skerry/solvers/batch_smoother.h"
#include "skerry/solvers/block_tridiagonal.h"
#include "skerry/solvers/pipeline.h"
#include "solvers/solver_test_data.h"

namespace skerry {
namespace {

// A random symmetric positive definite block-tridiagonal matrix with diagonal scales from 1e-4
// to 1e8 (the spread of a navigation state's information), as blocks and as a dense matrix.
struct Chain {
  std::vector<ChainBlock> D, O;
  Eigen::MatrixXd H;
};

Chain RandomChain(size_t n, std::mt19937* rng) {
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> log_scale(-2.0, 4.0);
  const int N = 18 * static_cast<int>(n);
  // H = A^T A with A banded: rows per keyframe touching it and the next one.
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(N + 18, N);
  for (size_t k = 0; k < n; ++k) {
    const int r = 18 * static_cast<int>(k);
    for (int i = 0; i < 36; ++i) {
      for (int j = 0; j < 18; ++j) A(r + i, r + j) = normal(*rng);
    }
  }
  Eigen::VectorXd s(N);
  for (int i = 0; i < N; ++i) s[i] = std::pow(10.0, log_scale(*rng));
  A = A * s.asDiagonal();
  Chain c;
  c.H = A.transpose() * A;
  c.D.resize(n);
  c.O.resize(n - 1);
  for (size_t k = 0; k < n; ++k) {
    c.D[k] = c.H.block<18, 18>(18 * k, 18 * k);
    if (k + 1 < n) c.O[k] = c.H.block<18, 18>(18 * k, 18 * (k + 1));
  }
  return c;
}

TEST(BlockTridiagonal, MatchesTheDenseDampedSolve) {
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  for (const double mu : {0.0, 1e-3, 1.0}) {
    const size_t n = 6;
    Chain c = RandomChain(n, &rng);
    std::vector<ChainVector> b(n);
    Eigen::VectorXd b_dense(18 * n);
    for (size_t k = 0; k < n; ++k) {
      for (int i = 0; i < 18; ++i) b[k][i] = normal(rng);
      b_dense.segment<18>(18 * k) = b[k];
    }
    // Reference: (S H S + mu I) y = S b, x = S y with S = diag(H)^-1/2.
    const Eigen::VectorXd s = c.H.diagonal().cwiseSqrt().cwiseInverse();
    Eigen::MatrixXd Hs = s.asDiagonal() * c.H * s.asDiagonal();
    Hs.diagonal().array() += mu;
    const Eigen::VectorXd y = Hs.ldlt().solve(s.cwiseProduct(b_dense));
    const Eigen::VectorXd x = s.cwiseProduct(y);

    double y_norm2 = 0.0, bx = 0.0;
    ASSERT_TRUE(SolveBlockTridiagonal(c.D, c.O, &b, mu, &y_norm2, &bx));
    for (size_t k = 0; k < n; ++k) {
      for (int i = 0; i < 18; ++i) {
        const double ref = x[18 * static_cast<int>(k) + i];
        EXPECT_NEAR(b[k][i], ref, 1e-7 * std::abs(ref) + 1e-12) << "mu " << mu << " k " << k;
      }
    }
    EXPECT_NEAR(y_norm2, y.squaredNorm(), 1e-8 * y.squaredNorm());
    EXPECT_NEAR(bx, b_dense.dot(x), 1e-8 * std::abs(b_dense.dot(x)));
  }
}

// With an arrow of m columns that every keyframe touches (a sensor's calibrated extrinsic and
// its parameter): the same step as the dense damped solve of the whole bordered matrix, Jacobi
// scaling and damping on the arrow's columns too, and a zero C_k taken as null.
TEST(BlockTridiagonal, WithAnArrowMatchesTheDenseDampedSolve) {
  std::mt19937 rng(11);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> log_scale(-2.0, 4.0);
  // One solver for the three solves, its storage released after each (Release): the next Start
  // must find what it needs again.
  BlockTridiagonalSolver solver;
  for (const double mu : {0.0, 1e-3, 1.0}) {
    const size_t n = 5;
    const int m = 7, N = 18 * static_cast<int>(n);
    // H = A^T A with A = [banded chain rows | dense arrow columns], the arrow's columns scaled
    // like the states' and keyframe 2 not touching the arrow.
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(N + 18 + 2 * m, N + m);
    for (size_t k = 0; k < n; ++k) {
      const int r = 18 * static_cast<int>(k);
      for (int i = 0; i < 36; ++i) {
        for (int j = 0; j < 18; ++j) A(r + i, r + j) = normal(rng);
      }
    }
    for (int i = 0; i < N + 18; ++i) {
      if (!A.row(i).segment<18>(36).isZero()) continue;  // rows on keyframe 2
      for (int j = 0; j < m; ++j) A(i, N + j) = 0.3 * normal(rng);
    }
    for (int i = 0; i < 2 * m; ++i) {
      for (int j = 0; j < m; ++j) A(N + 18 + i, N + j) = normal(rng);
    }
    Eigen::VectorXd s(N + m);
    for (int i = 0; i < N + m; ++i) s[i] = std::pow(10.0, log_scale(rng));
    A = A * s.asDiagonal();
    const Eigen::MatrixXd H = A.transpose() * A;
    Eigen::VectorXd b_dense(N + m);
    for (int i = 0; i < N + m; ++i) b_dense[i] = normal(rng);
    const Eigen::VectorXd sc = H.diagonal().cwiseSqrt().cwiseInverse();
    Eigen::MatrixXd Hs = sc.asDiagonal() * H * sc.asDiagonal();
    Hs.diagonal().array() += mu;
    const Eigen::VectorXd y = Hs.ldlt().solve(sc.cwiseProduct(b_dense));
    const Eigen::VectorXd x = sc.cwiseProduct(y);

    solver.Start(n, mu, m);
    for (size_t k = 0; k < n; ++k) {
      const int r = 18 * static_cast<int>(k);
      const ChainBlock D = H.block<18, 18>(r, r);
      const ChainVector b = b_dense.segment<18>(r);
      const ChainBlock O = k > 0 ? ChainBlock(H.block<18, 18>(r - 18, r)) : ChainBlock::Zero();
      const ArrowBlock C = H.block(r, N, 18, m);
      ASSERT_EQ(C.isZero(), k == 2);
      ASSERT_TRUE(solver.Push(D, b, k > 0 ? &O : nullptr, k == 2 ? nullptr : &C));
    }
    std::vector<ChainVector> xs;
    Eigen::VectorXd x_e;
    double y_norm2 = 0.0, bx = 0.0;
    ASSERT_TRUE(solver.Finish(H.block(N, N, m, m), b_dense.tail(m), &xs, &x_e, &y_norm2, &bx));
    for (size_t k = 0; k < n; ++k) {
      for (int i = 0; i < 18; ++i) {
        const double ref = x[18 * static_cast<int>(k) + i];
        EXPECT_NEAR(xs[k][i], ref, 1e-7 * std::abs(ref) + 1e-12) << "mu " << mu << " k " << k;
      }
    }
    for (int i = 0; i < m; ++i) {
      EXPECT_NEAR(x_e[i], x[N + i], 1e-7 * std::abs(x[N + i]) + 1e-12) << "mu " << mu;
    }
    EXPECT_NEAR(y_norm2, y.squaredNorm(), 1e-8 * y.squaredNorm());
    EXPECT_NEAR(bx, b_dense.dot(x), 1e-8 * std::abs(b_dense.dot(x)));
    EXPECT_GT(solver.gain_bytes(), 0u);
    solver.Release();
    EXPECT_EQ(solver.gain_bytes(), 0u);
  }
  // An arrow whose Schur complement is not positive definite is refused.
  solver.Start(1, 0.0, 1);
  const ArrowBlock C = ArrowBlock::Ones(18, 1);
  ASSERT_TRUE(solver.Push(ChainBlock::Identity(), ChainVector::Ones(), nullptr, &C));
  std::vector<ChainVector> xs;
  Eigen::VectorXd x_e;
  EXPECT_FALSE(
      solver.Finish(Eigen::MatrixXd::Constant(1, 1, 1.0), Eigen::VectorXd::Ones(1), &xs, &x_e));
  // A solve started with an arrow is not finished without it.
  solver.Start(1, 0.0, 1);
  ASSERT_TRUE(solver.Push(ChainBlock::Identity(), ChainVector::Ones(), nullptr, &C));
  EXPECT_FALSE(solver.Finish(&xs));
}

// The gains kept in float (GainPrecision::kSingle) on a chain of 300 keyframes with an arrow of
// 9 columns, assembled block by block (the dense matrix would take 0.7 GB): the same step as in
// double to the rounding of the gains, both forms and with and without damping, in half the
// memory. A gain dropped or stored at the wrong keyframe moves the step by its whole size.
TEST(BlockTridiagonal, SinglePrecisionGainsStayWithinTheirRounding) {
  std::mt19937 rng(17);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> log_scale(-2.0, 4.0);
  const size_t n = 300;
  const int m = 9;
  // H = A^T A, A's row block j touching keyframes j - 1 and j (B[j][0], B[j][1]) and the arrow
  // (P[j]); the columns scaled from 1e-2 to 1e4.
  std::vector<ChainBlock> B0(n + 1), B1(n + 1);
  std::vector<ArrowBlock> P(n + 1);
  std::vector<ChainVector> s(n);
  for (size_t j = 0; j <= n; ++j) {
    B0[j] = ChainBlock::NullaryExpr([&](Eigen::Index, Eigen::Index) { return normal(rng); });
    B1[j] = ChainBlock::NullaryExpr([&](Eigen::Index, Eigen::Index) { return normal(rng); });
    P[j] = ArrowBlock::NullaryExpr(18, m,
                                   [&](Eigen::Index, Eigen::Index) { return 0.3 * normal(rng); });
  }
  for (size_t k = 0; k < n; ++k) {
    for (int i = 0; i < 18; ++i) s[k][i] = std::pow(10.0, log_scale(rng));
    B1[k] = B1[k] * s[k].asDiagonal();          // row block k on keyframe k
    B0[k + 1] = B0[k + 1] * s[k].asDiagonal();  // row block k + 1 on keyframe k
  }
  std::vector<ChainBlock> D(n), O(n - 1);
  std::vector<ArrowBlock> C(n);
  std::vector<ChainVector> b(n);
  for (size_t k = 0; k < n; ++k) {
    D[k] = B1[k].transpose() * B1[k] + B0[k + 1].transpose() * B0[k + 1];
    if (k + 1 < n) O[k] = B0[k + 1].transpose() * B1[k + 1];
    C[k] = B1[k].transpose() * P[k] + B0[k + 1].transpose() * P[k + 1];
    for (int i = 0; i < 18; ++i) b[k][i] = normal(rng);
  }
  Eigen::MatrixXd E = Eigen::MatrixXd::Identity(m, m);
  for (size_t j = 0; j <= n; ++j) E += P[j].transpose() * P[j];
  Eigen::VectorXd b_e(m);
  for (int i = 0; i < m; ++i) b_e[i] = normal(rng);

  for (const int arrow : {0, m}) {
    for (const double mu : {0.0, 1e-3}) {
      std::vector<ChainVector> x[2];
      Eigen::VectorXd x_e[2];
      size_t bytes[2] = {0, 0};
      for (const GainPrecision p : {GainPrecision::kDouble, GainPrecision::kSingle}) {
        const int i = p == GainPrecision::kSingle;
        BlockTridiagonalSolver solver;
        solver.Start(n, mu, arrow, p);
        for (size_t k = 0; k < n; ++k) {
          ASSERT_TRUE(
              solver.Push(D[k], b[k], k > 0 ? &O[k - 1] : nullptr, arrow > 0 ? &C[k] : nullptr));
        }
        ASSERT_TRUE(arrow > 0 ? solver.Finish(E, b_e, &x[i], &x_e[i]) : solver.Finish(&x[i]));
        bytes[i] = solver.gain_bytes();
      }
      // The error in the scaled step y = diag(H)^1/2 x, where all entries weigh alike.
      double err2 = 0.0, norm2 = 0.0;
      for (size_t k = 0; k < n; ++k) {
        const ChainVector w = D[k].diagonal().cwiseSqrt();
        err2 += w.cwiseProduct(x[1][k] - x[0][k]).squaredNorm();
        norm2 += w.cwiseProduct(x[0][k]).squaredNorm();
      }
      if (arrow > 0) {
        const Eigen::VectorXd w = E.diagonal().cwiseSqrt();
        err2 += w.cwiseProduct(x_e[1] - x_e[0]).squaredNorm();
        norm2 += w.cwiseProduct(x_e[0]).squaredNorm();
      }
      const double relative = std::sqrt(err2 / norm2);
      std::printf("arrow %d, mu %g: relative step difference %.2e\n", arrow, mu, relative);
      EXPECT_LT(relative, 1e-5) << "arrow " << arrow << " mu " << mu;
      EXPECT_GT(relative, 0.0) << "the float gains were not used";
      EXPECT_EQ(bytes[0], (n - 1) * 18 * 18 * 8 + n * 18 * arrow * 8);
      EXPECT_EQ(bytes[1] * 2, bytes[0]);
    }
  }
}

TEST(BlockTridiagonal, RefusesAnIndefiniteMatrix) {
  std::mt19937 rng(3);
  Chain c = RandomChain(4, &rng);
  c.D[2](5, 5) = -c.D[2](5, 5);  // diagonal scaling then leaves -1 on the diagonal
  std::vector<ChainVector> b(4, ChainVector::Ones());
  EXPECT_FALSE(SolveBlockTridiagonal(c.D, c.O, &b, 0.0));
}

// The window's output, smoothed once by Ceres' sparse normal Cholesky and once by the chain
// solver: the same optimum (cost, every state), in a similar number of iterations, and the
// robust losses and the gate's re-solves taken the same way (a harbour run with a jump).
// 120 s of the simulated harbour (seed 5) and the default preset's window over it, the start
// of the batches below: simulated and run once for all of them.
struct HarbourRun {
  Dataset data;
  WindowRun run;
};

const HarbourRun& Harbour120() {
  static const HarbourRun* run = [] {
    sim::ScenarioConfig sc = test::MatchedScenario("harbour");
    sc.duration_s = 120.0;
    auto* r = new HarbourRun;
    r->data = sim::Simulate(sc, 5);
    r->run = RunWindow(r->data, LoadPreset("default"));
    return r;
  }();
  return *run;
}

// The largest position and attitude differences between two batches' states, keyframe by
// keyframe (the same keyframes).
struct StateDifference {
  double dp = 0.0;      // m
  double dtheta = 0.0;  // rad
};

StateDifference MaxStateDifference(const BatchResult& a, const BatchResult& b) {
  StateDifference d;
  for (size_t k = 0; k < a.records.size() && k < b.records.size(); ++k) {
    const NavState& x = a.records[k].state;
    const NavState& y = b.records[k].state;
    d.dp = std::max(d.dp, (x.p_w_b - y.p_w_b).norm());
    d.dtheta = std::max(d.dtheta, LogQ<double>(x.q_w_b * y.q_w_b.conjugate()).norm());
  }
  return d;
}

TEST(ChainSolver, ReachesCeresOptimumOnTheBatch) {
  const Dataset& data = Harbour120().data;
  const WindowRun& run = Harbour120().run;
  EstimatorConfig ceres_config = LoadPreset("default");
  ceres_config.batch_ceres.linear_solver = "sparse_normal_cholesky";
  EstimatorConfig chain_config = ceres_config;
  chain_config.batch_ceres.linear_solver = "chain";
  ASSERT_GT(run.records.size(), 1000u);
  const BatchResult a = SmoothBatch(data, ceres_config, run.records, run.decisions);
  const BatchResult b = SmoothBatch(data, chain_config, run.records, run.decisions);
  ASSERT_TRUE(a.usable);
  ASSERT_TRUE(b.usable);
  EXPECT_EQ(a.gnss_used, b.gnss_used);
  EXPECT_EQ(a.gnss_rejected_after_solve, b.gnss_rejected_after_solve);
  EXPECT_LE(b.iterations, a.iterations + 2);
  ASSERT_EQ(a.records.size(), b.records.size());
  double max_dp = 0.0, max_dtheta = 0.0, max_dv = 0.0, max_dsigma = 0.0;
  for (size_t k = 0; k < a.records.size(); ++k) {
    const NavState& x = a.records[k].state;
    const NavState& y = b.records[k].state;
    max_dp = std::max(max_dp, (x.p_w_b - y.p_w_b).norm());
    max_dv = std::max(max_dv, (x.v_w - y.v_w).norm());
    max_dtheta = std::max(max_dtheta, LogQ<double>(x.q_w_b * y.q_w_b.conjugate()).norm());
    ASSERT_TRUE(a.records[k].has_covariance && b.records[k].has_covariance);
    const Eigen::VectorXd sa = a.records[k].covariance.diagonal().cwiseSqrt();
    const Eigen::VectorXd sb = b.records[k].covariance.diagonal().cwiseSqrt();
    max_dsigma = std::max(max_dsigma, ((sa - sb).array() / sa.array()).abs().maxCoeff());
  }
  EXPECT_LT(max_dp, 1e-6) << "m";
  EXPECT_LT(max_dv, 1e-7) << "m/s";
  EXPECT_LT(max_dtheta, 1e-8) << "rad";
  EXPECT_LT(max_dsigma, 1e-4) << "relative sigma";
  std::printf(
      "batch: Ceres %d iterations, chain %d; max differences %.2e m, %.2e m/s, %.2e rad, "
      "%.2e of a sigma\n",
      a.iterations, b.iterations, max_dp, max_dv, max_dtheta, max_dsigma);
}

// With num_threads > 1 a worker linearises the next chunk of keyframes (512) while the
// elimination consumes the current one. The assembly runs in keyframe order on either side, so
// the batch (1200 keyframes: three chunks, two hand-overs) comes out the same to the last bit.
TEST(ChainSolver, TheSameBatchOnAnyNumberOfThreads) {
  const Dataset& data = Harbour120().data;
  const WindowRun& run = Harbour120().run;
  EstimatorConfig config = LoadPreset("default");
  ASSERT_EQ(config.batch_ceres.linear_solver, "chain");
  ASSERT_GT(run.records.size(), 1024u);
  config.batch_ceres.num_threads = 1;
  const BatchResult one = SmoothBatch(data, config, run.records, run.decisions);
  config.batch_ceres.num_threads = 2;
  const BatchResult two = SmoothBatch(data, config, run.records, run.decisions);
  ASSERT_TRUE(one.usable);
  ASSERT_TRUE(two.usable);
  EXPECT_EQ(one.iterations, two.iterations);
  EXPECT_EQ(one.gnss_used, two.gnss_used);
  ASSERT_EQ(one.records.size(), two.records.size());
  size_t differing = 0;
  for (size_t k = 0; k < one.records.size(); ++k) {
    const NavState& x = one.records[k].state;
    const NavState& y = two.records[k].state;
    const bool same = x.p_w_b == y.p_w_b && x.v_w == y.v_w &&
                      x.q_w_b.coeffs() == y.q_w_b.coeffs() && x.bg == y.bg && x.ba == y.ba &&
                      one.records[k].covariance == two.records[k].covariance;
    differing += !same;
  }
  EXPECT_EQ(differing, 0u) << "of " << one.records.size() << " keyframes";
}

// The default batch keeps the chain's gains in float (chain_gains: single): the same iterations,
// the same gate decisions and the same estimates as in double to far below their sigmas.
TEST(ChainSolver, SinglePrecisionGainsTakeTheSameBatch) {
  const Dataset& data = Harbour120().data;
  const WindowRun& run = Harbour120().run;
  EstimatorConfig config = LoadPreset("default");
  ASSERT_EQ(config.batch_ceres.chain_gains, "single");
  const BatchResult single = SmoothBatch(data, config, run.records, run.decisions);
  config.batch_ceres.chain_gains = "double";
  const BatchResult twice = SmoothBatch(data, config, run.records, run.decisions);
  ASSERT_TRUE(single.usable);
  ASSERT_TRUE(twice.usable);
  EXPECT_EQ(single.iterations, twice.iterations);
  EXPECT_EQ(single.gnss_used, twice.gnss_used);
  ASSERT_EQ(single.records.size(), twice.records.size());
  const auto [max_dp, max_dtheta] = MaxStateDifference(single, twice);
  std::printf("single against double gains: max %.2e m, %.2e rad\n", max_dp, max_dtheta);
  EXPECT_LT(max_dp, 1e-6) << "m";
  EXPECT_LT(max_dtheta, 1e-8) << "rad";
}

// The chain solver gates inside its iterations (NavGraph::SolveChain's `decide`), Ceres' solvers
// after each solve, re-solving while the decisions change (BatchGraph::SolveAndDecide). Given
// every fix as accepted, with one in ten moved 2.5 m east (5 of the receiver's sigmas: outside
// the gate) and one in ten 1.2 m north (near its edge), the first solve takes them all and the
// gate must then change its mind: both ways reach the same decisions and the same optimum.
TEST(ChainSolver, GateInsideTheIterationsDecidesAsAfterTheSolve) {
  Dataset data = Harbour120().data;
  std::vector<FixRecord> decisions = Harbour120().run.decisions;
  ASSERT_EQ(decisions.size(), data.gnss_fixes.size());
  for (size_t f = 0; f < data.gnss_fixes.size(); ++f) {
    decisions[f].position = FixDecision::kAccepted;
    decisions[f].across_jump = false;
    if (f % 10 == 3) data.gnss_fixes[f].p_w.x() += 2.5;
    if (f % 10 == 7) data.gnss_fixes[f].p_w.y() += 1.2;
  }
  EstimatorConfig ceres_config = LoadPreset("default");
  ceres_config.batch_ceres.linear_solver = "sparse_normal_cholesky";
  EstimatorConfig chain_config = ceres_config;
  chain_config.batch_ceres.linear_solver = "chain";
  const std::vector<EstimateRecord>& start = Harbour120().run.records;
  const BatchResult a = SmoothBatch(data, ceres_config, start, decisions);
  const BatchResult b = SmoothBatch(data, chain_config, start, decisions);
  ASSERT_TRUE(a.usable);
  ASSERT_TRUE(b.usable);
  // The gate did change its mind: at least the 2.5 m ones are out.
  EXPECT_GE(a.gnss_rejected_after_solve, static_cast<int>(data.gnss_fixes.size() / 10));
  EXPECT_EQ(a.gnss_used, b.gnss_used);
  EXPECT_EQ(a.gnss_rejected_after_solve, b.gnss_rejected_after_solve);
  ASSERT_EQ(a.records.size(), b.records.size());
  const auto [max_dp, max_dtheta] = MaxStateDifference(a, b);
  std::printf(
      "gate after the solve (Ceres): %d iterations, %d fixes out; inside the iterations "
      "(chain): %d iterations, %d out; max differences %.2e m, %.2e rad\n",
      a.iterations, a.gnss_rejected_after_solve, b.iterations, b.gnss_rejected_after_solve, max_dp,
      max_dtheta);
  EXPECT_LT(max_dp, 1e-6) << "m";
  EXPECT_LT(max_dtheta, 1e-8) << "rad";
}

TEST(ChainSolver, NeedsLevenbergMarquardt) {
  CeresConfig c;
  c.linear_solver = "chain";
  c.trust_region = "dogleg";
  EXPECT_THROW(MakeSolverOptions(c), std::invalid_argument);
  c.trust_region = "levenberg_marquardt";
  EXPECT_EQ(MakeSolverOptions(c).linear_solver_type, ceres::SPARSE_NORMAL_CHOLESKY);
}

}  // namespace
}  // namespace skerry
