// NavGraph: marginalisation by Schur complement and the chain covariance recursions, checked
// against a dense reference built independently (Ceres' own Jacobians, converted to skerry's
// tangent, then a dense inverse of J^T J); SlidingWindowEstimator on a short simulated harbour
// run.
//
// Tangent conventions. skerry perturbs a quaternion on the left by a full-angle world-frame
// rotation vector theta: q(theta) = Exp(theta) * q (factor_linearization.h). Ceres'
// EigenQuaternionManifold also multiplies on the left, but its tangent delta is HALF the rotation
// vector: Plus(q, delta) = [sin|delta| delta/|delta|, cos|delta|] * q, i.e. theta = 2 delta. So
// J_theta = J_delta * d(delta)/d(theta) = 0.5 * J_delta for the three rotation columns.

#include <ceres/ceres.h>
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <stdexcept>
#include <vector>

#include "factors/test_utils.h"
#include "skerry/core/chi_square.h"
#include "skerry/core/heading.h"
#include "skerry/core/so3.h"
#include "skerry/eval/evaluation.h"
#include "skerry/factors/bias_random_walk_factor.h"
#include "skerry/factors/factor_linearization.h"
#include "skerry/factors/gnss_heading_factor.h"
#include "skerry/factors/gnss_position_factor.h"
#include "skerry/factors/imu_factor.h"
#include "skerry/factors/imu_preintegration.h"
#include "skerry/factors/linear_prior_factor.h"
#include "skerry/factors/state_prior_factor.h"
#include "skerry/sim/scenario.h"
#include "skerry/sim/simulator.h"
#include "skerry/solvers/estimator_config.h"
#include "skerry/solvers/nav_graph.h"
#include "skerry/solvers/sliding_window_estimator.h"
#include "solvers/solver_test_data.h"
#include "workload.h"

namespace skerry {
namespace {

using Mat15 = Eigen::Matrix<double, 15, 15>;
using test::AnalyticTrajectory;
using test::AngleBetween;
using test::RandomQuaternion;
using test::RandomVector;

// ----------------------------------------------------------------------------------------------
// Problem description shared by the graphs under test and the dense reference.

/// One factor: how to make its cost function (each graph and the reference get their own copy)
/// and which blocks it touches. Keyframe indices are the NavGraph ids of a fresh graph (0, 1, ...).
struct FactorSpec {
  FactorKind kind;
  std::function<std::unique_ptr<ceres::CostFunction>()> make;
  std::vector<BlockRef> blocks;
};

struct ChainProblem {
  std::vector<NavState> initial;  ///< one per keyframe, increasing time
  std::vector<FactorSpec> factors;
};

std::vector<BlockRef> AllSlots(KeyframeId id) {
  return {{id, Slot::kQ}, {id, Slot::kP}, {id, Slot::kV}, {id, Slot::kBg}, {id, Slot::kBa}};
}

/// Builds a NavGraph from the problem; `keyframes` receives mutable handles (to move states).
std::unique_ptr<NavGraph> BuildGraph(const ChainProblem& problem,
                                     std::vector<Keyframe*>* keyframes = nullptr) {
  auto graph = std::make_unique<NavGraph>();
  for (size_t k = 0; k < problem.initial.size(); ++k) {
    Keyframe& kf = graph->AddKeyframe(problem.initial[k], Eigen::Vector3d::Zero());
    EXPECT_EQ(kf.id, static_cast<KeyframeId>(k));
    if (keyframes != nullptr) keyframes->push_back(&kf);
  }
  for (const FactorSpec& f : problem.factors) graph->AddFactor(f.kind, f.make(), nullptr, f.blocks);
  return graph;
}

std::vector<NavState> GraphStates(const NavGraph& graph) {
  std::vector<NavState> states;
  for (KeyframeId id : graph.keyframe_ids()) states.push_back(graph.keyframe(id).state());
  return states;
}

/// Dense Jacobian (15 K columns, skerry tangent, keyframes in order) of the factors at `states`,
/// from Ceres' own Problem::Evaluate: independent of NavGraph's linearisation code.
Eigen::MatrixXd DenseJacobian(const std::vector<NavState>& states,
                              const std::vector<FactorSpec>& factors) {
  struct Params {
    double q[4], p[3], v[3], bg[3], ba[3], gb[3] = {0, 0, 0};
    double* block(Slot s) {
      switch (s) {
        case Slot::kQ:
          return q;
        case Slot::kP:
          return p;
        case Slot::kV:
          return v;
        case Slot::kBg:
          return bg;
        case Slot::kBa:
          return ba;
        case Slot::kGb:
          return gb;
        default:
          return nullptr;  // no extrinsics in these graphs
      }
    }
  };
  std::vector<Params> x(states.size());
  ceres::Problem::Options options;
  options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(options);
  ceres::EigenQuaternionManifold manifold;
  std::vector<double*> order;
  for (size_t k = 0; k < states.size(); ++k) {
    Eigen::Map<Eigen::Vector4d>(x[k].q) = states[k].q_w_b.coeffs();
    Eigen::Map<Eigen::Vector3d>(x[k].p) = states[k].p_w_b;
    Eigen::Map<Eigen::Vector3d>(x[k].v) = states[k].v_w;
    Eigen::Map<Eigen::Vector3d>(x[k].bg) = states[k].bg;
    Eigen::Map<Eigen::Vector3d>(x[k].ba) = states[k].ba;
    problem.AddParameterBlock(x[k].q, 4, &manifold);
    for (Slot s : {Slot::kP, Slot::kV, Slot::kBg, Slot::kBa}) {
      problem.AddParameterBlock(x[k].block(s), 3);
    }
    problem.AddParameterBlock(x[k].gb, 3);
    problem.SetParameterBlockConstant(x[k].gb);
    for (Slot s : {Slot::kQ, Slot::kP, Slot::kV, Slot::kBg, Slot::kBa}) {
      order.push_back(x[k].block(s));
    }
  }
  std::vector<std::unique_ptr<ceres::CostFunction>> costs;
  for (const FactorSpec& f : factors) {
    costs.push_back(f.make());
    std::vector<double*> ptrs;
    for (const BlockRef& b : f.blocks) ptrs.push_back(x.at(b.keyframe).block(b.slot));
    problem.AddResidualBlock(costs.back().get(), nullptr, ptrs);
  }
  ceres::Problem::EvaluateOptions eval;
  eval.parameter_blocks = order;
  ceres::CRSMatrix crs;
  EXPECT_TRUE(problem.Evaluate(eval, nullptr, nullptr, nullptr, &crs));
  const int n = 15 * static_cast<int>(states.size());
  EXPECT_EQ(crs.num_cols, n);
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(crs.num_rows, n);
  for (int r = 0; r < crs.num_rows; ++r) {
    for (int i = crs.rows[r]; i < crs.rows[r + 1]; ++i) J(r, crs.cols[i]) = crs.values[i];
  }
  for (size_t k = 0; k < states.size(); ++k) J.middleCols(15 * k, 3) *= 0.5;  // see top of file
  return J;
}

/// Dense information J^T J of the factors at `states`.
Eigen::MatrixXd DenseInformation(const std::vector<NavState>& states,
                                 const std::vector<FactorSpec>& factors) {
  const Eigen::MatrixXd J = DenseJacobian(states, factors);
  return J.transpose() * J;
}

/// The dense covariance (J^T J)^-1 in long double (64-bit mantissa), from a Householder QR of
/// the column-scaled Jacobian (never forming J^T J, whose conditioning is the square of J's): a
/// reference for information spanning 1e-2 to 1e20.
Eigen::MatrixXd LongDoubleCovariance(const std::vector<NavState>& states,
                                     const std::vector<FactorSpec>& factors) {
  using MatL = Eigen::Matrix<long double, Eigen::Dynamic, Eigen::Dynamic>;
  const MatL J = DenseJacobian(states, factors).cast<long double>();
  const Eigen::Matrix<long double, Eigen::Dynamic, 1> d = J.colwise().norm().transpose();
  const MatL Js = J * d.cwiseInverse().asDiagonal();
  const Eigen::HouseholderQR<MatL> qr(Js);
  const long n = J.cols();
  const MatL R = qr.matrixQR().topRows(n).template triangularView<Eigen::Upper>();
  const MatL R_inv = R.template triangularView<Eigen::Upper>().solve(MatL::Identity(n, n));
  const MatL Sigma_s = R_inv * R_inv.transpose();
  return (d.cwiseInverse().asDiagonal() * Sigma_s * d.cwiseInverse().asDiagonal()).cast<double>();
}

/// Covariances compared entry by entry relative to the reference's standard deviations:
/// |A_ij - B_ij| <= tol * sqrt(B_ii B_jj) (a correlation-scale tolerance, fair to every unit).
void ExpectCovarianceNear(const Mat15& actual, const Mat15& reference, double tol) {
  double worst = 0.0;
  int wi = 0, wj = 0;
  for (int i = 0; i < 15; ++i) {
    for (int j = 0; j < 15; ++j) {
      const double scale = std::sqrt(reference(i, i) * reference(j, j));
      const double err = std::abs(actual(i, j) - reference(i, j)) / scale;
      if (!(err <= worst)) {
        worst = err;
        wi = i;
        wj = j;
      }
    }
  }
  EXPECT_LE(worst, tol) << "worst entry (" << wi << "," << wj << "): " << actual(wi, wj) << " vs "
                        << reference(wi, wj) << "\nactual diagonal "
                        << actual.diagonal().transpose() << "\nreference diagonal "
                        << reference.diagonal().transpose();
}

Mat15 RandomSpd(std::mt19937* rng, const Eigen::Matrix<double, 15, 1>& sigmas) {
  // Correlation matrix C = A A^T normalised, then scaled by the sigmas.
  std::normal_distribution<double> n01(0.0, 1.0);
  Mat15 A;
  for (int i = 0; i < 15; ++i) {
    for (int j = 0; j < 15; ++j) A(i, j) = n01(*rng);
  }
  Mat15 C = A * A.transpose() / 15.0 + 0.3 * Mat15::Identity();
  const Eigen::Matrix<double, 15, 1> d = C.diagonal().cwiseSqrt().cwiseInverse();
  C = d.asDiagonal() * C * d.asDiagonal();
  return sigmas.asDiagonal() * C * sigmas.asDiagonal();
}

CeresConfig TightSolver() {
  CeresConfig c;
  c.linear_solver = "dense_qr";
  c.max_iterations = 200;
  c.max_time_s = 0.0;
  c.function_tolerance = 1e-16;
  c.gradient_tolerance = 1e-16;
  c.parameter_tolerance = 1e-16;
  return c;
}

// ----------------------------------------------------------------------------------------------
// A chain that is exactly linear-Gaussian in skerry's tangent.
//
// Rotation appears only in each keyframe's own StatePriorFactor, Log(q q0^-1): in the coordinates
// delta = Log(q q0^-1) that residual is exactly delta, and every other factor is affine in
// p, v, bg, ba (a constant-velocity "odometry" factor, the bias random walk, GNSS positions with
// zero lever arm at dt = 0). So the problem is a linear least-squares problem, marginalisation
// by Schur complement is exact wherever it is linearised, and the window's estimates must equal
// the full solution.

/// r = L * [ p_j - p_i - v_i dt - dp ; v_j - v_i - dv ]   (blocks p_i, v_i, p_j, v_j)
class ConstantVelocityFactor : public ceres::SizedCostFunction<6, 3, 3, 3, 3> {
 public:
  ConstantVelocityFactor(const Eigen::Matrix<double, 6, 6>& sqrt_info,
                         double dt_s,
                         const Eigen::Matrix<double, 6, 1>& z)
      : sqrt_info_(sqrt_info), dt_s_(dt_s), z_(z) {}

  bool Evaluate(double const* const* x, double* residuals, double** jacobians) const override {
    using Vec3 = Eigen::Map<const Eigen::Vector3d>;
    const Vec3 p_i(x[0]), v_i(x[1]), p_j(x[2]), v_j(x[3]);
    Eigen::Matrix<double, 6, 1> e;
    e.head<3>() = p_j - p_i - v_i * dt_s_;
    e.tail<3>() = v_j - v_i;
    Eigen::Map<Eigen::Matrix<double, 6, 1>>{residuals} = sqrt_info_ * (e - z_);
    if (jacobians == nullptr) return true;
    const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
    Eigen::Matrix<double, 6, 3> d[4];
    d[0] << -I, Eigen::Matrix3d::Zero();
    d[1] << -dt_s_ * I, -I;
    d[2] << I, Eigen::Matrix3d::Zero();
    d[3] << Eigen::Matrix3d::Zero(), I;
    for (int k = 0; k < 4; ++k) {
      if (jacobians[k] != nullptr) {
        Eigen::Map<Eigen::Matrix<double, 6, 3, Eigen::RowMajor>>{jacobians[k]} = sqrt_info_ * d[k];
      }
    }
    return true;
  }

 private:
  Eigen::Matrix<double, 6, 6> sqrt_info_;
  double dt_s_;
  Eigen::Matrix<double, 6, 1> z_;
};

ChainProblem LinearChain(int num_keyframes, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  const double dt = 0.1;
  ImuNoise noise;
  noise.gyro_bias_random_walk_rad_s2_sqrt_hz = 1e-3;  // comparable to the other information
  noise.accel_bias_random_walk_m_s3_sqrt_hz = 1e-2;
  ChainProblem problem;
  for (int k = 0; k < num_keyframes; ++k) {
    NavState truth;
    truth.t_ns = SecondsToNs(k * dt);
    truth.q_w_b = RandomQuaternion(&rng);
    truth.p_w_b = Eigen::Vector3d(3.0 * k * dt, 0.5, 0.1) + RandomVector(&rng, 0.05);
    truth.v_w = Eigen::Vector3d(3.0, 0.0, 0.0) + RandomVector(&rng, 0.05);
    truth.bg = RandomVector(&rng, 1e-3);
    truth.ba = RandomVector(&rng, 1e-2);
    // A prior on every keyframe with correlated errors (rotation correlated with the rest).
    Eigen::Matrix<double, 15, 1> sigmas;
    sigmas << 0.02, 0.02, 0.05, 0.5, 0.5, 0.8, 0.2, 0.2, 0.2, 2e-3, 2e-3, 2e-3, 0.05, 0.05, 0.05;
    const Mat15 P = RandomSpd(&rng, sigmas);
    NavState mean = truth;
    mean.p_w_b += RandomVector(&rng, 0.3);
    mean.v_w += RandomVector(&rng, 0.1);
    mean.bg += RandomVector(&rng, 1e-3);
    mean.ba += RandomVector(&rng, 0.03);
    problem.factors.push_back({FactorKind::kStatePrior,
                               [mean, P] { return StatePriorFactor::Create(mean, P); },
                               AllSlots(k)});
    // Initial guess: the prior's rotation, Euclidean parts far off (the problem is linear).
    NavState initial = mean;
    initial.p_w_b += RandomVector(&rng, 2.0);
    initial.v_w += RandomVector(&rng, 1.0);
    initial.bg += RandomVector(&rng, 1e-2);
    initial.ba += RandomVector(&rng, 0.1);
    problem.initial.push_back(initial);
    if (k % 2 == 1) {
      const Eigen::Vector3d z = truth.p_w_b + RandomVector(&rng, 0.3);
      const Eigen::Vector3d sigma(0.3, 0.4, 0.6);
      problem.factors.push_back({FactorKind::kGnssPosition,
                                 [z, sigma] {
                                   return GnssPositionFactor::Create(z, sigma,
                                                                     Eigen::Vector3d::Zero(), 0.0);
                                 },
                                 {{k, Slot::kQ}, {k, Slot::kP}, {k, Slot::kV}, {k, Slot::kGb}}});
    }
    if (k > 0) {
      Eigen::Matrix<double, 6, 6> L = Eigen::Matrix<double, 6, 6>::Identity() * 8.0;
      for (int i = 0; i < 6; ++i) {
        for (int j = i; j < 6; ++j) L(i, j) += n01(rng);
      }
      Eigen::Matrix<double, 6, 1> z;
      for (int i = 0; i < 6; ++i) z[i] = 0.05 * n01(rng);
      problem.factors.push_back(
          {FactorKind::kImu,
           [L, dt, z] { return std::make_unique<ConstantVelocityFactor>(L, dt, z); },
           {{k - 1, Slot::kP}, {k - 1, Slot::kV}, {k, Slot::kP}, {k, Slot::kV}}});
      problem.factors.push_back(
          {FactorKind::kBiasRandomWalk,
           [noise, dt] { return std::make_unique<BiasRandomWalkFactor>(noise, dt); },
           {{k - 1, Slot::kBg}, {k - 1, Slot::kBa}, {k, Slot::kBg}, {k, Slot::kBa}}});
    }
  }
  return problem;
}

void ExpectStatesEqual(const NavState& actual, const NavState& expected, double tol) {
  EXPECT_LE(AngleBetween(actual.q_w_b, expected.q_w_b), tol);
  EXPECT_LE((actual.p_w_b - expected.p_w_b).norm(), tol)
      << actual.p_w_b.transpose() << " vs " << expected.p_w_b.transpose();
  EXPECT_LE((actual.v_w - expected.v_w).norm(), tol);
  EXPECT_LE((actual.bg - expected.bg).norm(), tol);
  EXPECT_LE((actual.ba - expected.ba).norm(), tol);
}

TEST(NavGraphTest, SinglePriorCovarianceIsThePriorAndTheReferenceAgrees) {
  // Checks the reference (and its half-angle conversion) as much as NavGraph.
  std::mt19937 rng(3);
  Eigen::Matrix<double, 15, 1> sigmas;
  sigmas << 0.01, 0.02, 0.1, 1, 2, 3, 0.1, 0.2, 0.3, 1e-3, 2e-3, 3e-3, 0.01, 0.02, 0.03;
  const Mat15 P = RandomSpd(&rng, sigmas);
  NavState s;
  s.q_w_b = RandomQuaternion(&rng);
  s.p_w_b = RandomVector(&rng, 10.0);
  ChainProblem problem;
  problem.initial = {s};
  problem.factors.push_back(
      {FactorKind::kStatePrior, [s, P] { return StatePriorFactor::Create(s, P); }, AllSlots(0)});
  const auto graph = BuildGraph(problem);
  StateCovariance newest;
  ASSERT_TRUE(graph->NewestCovariance(&newest));
  ExpectCovarianceNear(newest, P, 1e-9);
  std::vector<StateCovariance> all;
  ASSERT_TRUE(graph->AllCovariances(&all));
  ASSERT_EQ(all.size(), 1u);
  ExpectCovarianceNear(all[0], P, 1e-9);
  const Mat15 reference = DenseInformation(problem.initial, problem.factors).inverse();
  ExpectCovarianceNear(reference, P, 1e-9);
}

TEST(NavGraphTest, MarginalisationIsExactForALinearGaussianChain) {
  const int K = 9, kMarginalised = 5;
  const ChainProblem problem = LinearChain(K, 11);

  // Full graph: every keyframe, one solve.
  const auto full = BuildGraph(problem);
  const ceres::Solver::Summary summary = full->Solve(TightSolver());
  ASSERT_TRUE(summary.IsSolutionUsable()) << summary.BriefReport();
  const std::vector<NavState> full_states = GraphStates(*full);

  // The estimates moved a lot from the initial guess (otherwise the comparison is empty).
  ASSERT_GT((full_states[K - 1].p_w_b - problem.initial[K - 1].p_w_b).norm(), 0.5);

  // Window: marginalise the oldest keyframes at the initial guess, one by one, then solve.
  const auto window = BuildGraph(problem);
  for (int k = 0; k < kMarginalised; ++k) window->MarginalizeOldest(false);
  ASSERT_EQ(window->num_keyframes(), static_cast<size_t>(K - kMarginalised));
  EXPECT_EQ(window->oldest().id, kMarginalised);
  EXPECT_EQ(window->factor_ids(FactorKind::kMarginalPrior).size(), 1u);
  window->Solve(TightSolver());
  for (int k = kMarginalised; k < K; ++k) {
    SCOPED_TRACE("keyframe " + std::to_string(k));
    ExpectStatesEqual(window->keyframe(k).state(), full_states[k], 1e-8);
  }

  // Covariances: dense inverse of the full information at the full solution.
  const Eigen::MatrixXd H = DenseInformation(full_states, problem.factors);
  const Eigen::MatrixXd Sigma = H.inverse();
  auto block = [&Sigma](int k) -> Mat15 { return Sigma.block<15, 15>(15 * k, 15 * k); };

  StateCovariance newest;
  ASSERT_TRUE(window->NewestCovariance(&newest));
  ExpectCovarianceNear(newest, block(K - 1), 1e-6);
  std::vector<StateCovariance> window_all;
  ASSERT_TRUE(window->AllCovariances(&window_all));
  ASSERT_EQ(window_all.size(), static_cast<size_t>(K - kMarginalised));
  for (int k = kMarginalised; k < K; ++k) {
    SCOPED_TRACE("window keyframe " + std::to_string(k));
    ExpectCovarianceNear(window_all[k - kMarginalised], block(k), 1e-6);
  }

  std::vector<StateCovariance> full_all;
  ASSERT_TRUE(full->AllCovariances(&full_all));
  ASSERT_EQ(full_all.size(), static_cast<size_t>(K));
  for (int k = 0; k < K; ++k) {
    SCOPED_TRACE("full keyframe " + std::to_string(k));
    ExpectCovarianceNear(full_all[k], block(k), 1e-7);
  }
  StateCovariance full_newest;
  ASSERT_TRUE(full->NewestCovariance(&full_newest));
  ExpectCovarianceNear(full_newest, block(K - 1), 1e-7);
}

// The covariance recursion in segments (each redone from its checkpoint on the way back) gives
// the dense inverse's blocks whatever the segment length: every keyframe its own segment, short
// segments with a last one cut short, exactly one, and one longer than the chain; in the
// information form and in the square-root form alike.
TEST(NavGraphTest, CovariancesInSegmentsAreTheDenseInverse) {
  const int K = 23;
  const ChainProblem problem = LinearChain(K, 17);
  const auto graph = BuildGraph(problem);
  ASSERT_TRUE(graph->Solve(TightSolver()).IsSolutionUsable());
  const Eigen::MatrixXd Sigma = DenseInformation(GraphStates(*graph), problem.factors).inverse();
  for (const auto form :
       {NavGraph::CovarianceForm::kInformation, NavGraph::CovarianceForm::kSquareRoot})
    for (const size_t segment : {1u, 2u, 5u, 23u, 4096u}) {
      SCOPED_TRACE(
          "segment " + std::to_string(segment) +
          (form == NavGraph::CovarianceForm::kInformation ? ", information" : ", square root"));
      graph->set_covariance_form(form);
      graph->set_covariance_segment(segment);
      std::vector<StateCovariance> all;
      ASSERT_TRUE(graph->AllCovariances(&all));
      ASSERT_EQ(all.size(), static_cast<size_t>(K));
      for (int k = 0; k < K; ++k) {
        SCOPED_TRACE("keyframe " + std::to_string(k));
        ExpectCovarianceNear(all[k], Sigma.block<15, 15>(15 * k, 15 * k), 1e-7);
      }
    }
}

// Marginalising after solves (the way the window does it) is just as exact for a linear problem,
// with and without first-estimate Jacobians.
TEST(NavGraphTest, InterleavedSolveAndMarginaliseMatchesTheFullSolution) {
  const int K = 9, kMarginalised = 6;
  const ChainProblem problem = LinearChain(K, 12);
  const auto full = BuildGraph(problem);
  full->Solve(TightSolver());
  const std::vector<NavState> full_states = GraphStates(*full);
  for (bool fej : {false, true}) {
    SCOPED_TRACE(fej ? "FEJ" : "no FEJ");
    const auto window = BuildGraph(problem);
    for (int k = 0; k < kMarginalised; ++k) {
      window->Solve(TightSolver());
      window->MarginalizeOldest(fej);
    }
    window->Solve(TightSolver());
    for (int k = kMarginalised; k < K; ++k) {
      SCOPED_TRACE("keyframe " + std::to_string(k));
      ExpectStatesEqual(window->keyframe(k).state(), full_states[k], 1e-8);
    }
  }
}

// SolveChain's `decide` on a linear chain from a start metres off: the first step takes nearly
// all of the cost away and the solve converges two steps later, so no accepted step lowers the
// cost by less than kDecideBelowRelativeDecrease of it, and the call at the iterate where the
// solve would stop as converged is the gate's only chance. The gate takes out a fix 20 m off:
// the solve must end where the chain without that fix does, at an iterate the gate has seen.
TEST(NavGraphTest, ChainGateDecidesAtTheConvergedIterate) {
  const int K = 30;
  const ChainProblem problem = LinearChain(K, 17);
  const auto reference = BuildGraph(problem);
  CeresConfig config;
  config.linear_solver = "chain";
  config.max_time_s = 0.0;
  ASSERT_EQ(reference->SolveChain(config).termination_type, ceres::CONVERGENCE);

  const auto graph = BuildGraph(problem);
  const KeyframeId at = 11;
  const Eigen::Vector3d z = graph->keyframe(at).state().p_w_b + Eigen::Vector3d(20.0, -8.0, 0.0);
  const FactorId outlier = graph->AddFactor(
      FactorKind::kGnssPosition,
      GnssPositionFactor::Create(z, Eigen::Vector3d(0.3, 0.3, 0.6), Eigen::Vector3d::Zero(), 0.0),
      nullptr, {{at, Slot::kQ}, {at, Slot::kP}, {at, Slot::kV}, {at, Slot::kGb}});
  int calls = 0;
  bool removed = false;
  std::vector<NavState> seen;  // the states at the gate's last call
  const ceres::Solver::Summary summary = graph->SolveChain(config, [&] {
    ++calls;
    seen = GraphStates(*graph);
    if (removed) return 0;
    graph->RemoveFactor(outlier);
    removed = true;
    return 1;
  });
  ASSERT_EQ(summary.termination_type, ceres::CONVERGENCE) << summary.message;
  ASSERT_TRUE(removed) << "the gate was never called";
  EXPECT_GE(calls, 2);  // the second call sees the solution without the fix and changes nothing
  const std::vector<NavState> final_states = GraphStates(*graph);
  const std::vector<NavState> expected = GraphStates(*reference);
  for (int k = 0; k < K; ++k) {
    SCOPED_TRACE("keyframe " + std::to_string(k));
    ExpectStatesEqual(final_states[k], seen[k], 0.0);  // the solve ended where the gate looked
    // Both solves stop at the default tolerances, from different paths.
    ExpectStatesEqual(final_states[k], expected[k], 1e-4);
  }
  // Left in, the fix would have moved its keyframe by metres.
  EXPECT_LT((final_states[at].p_w_b - expected[at].p_w_b).norm(), 1e-4);
}

// ----------------------------------------------------------------------------------------------
// A real IMU chain (ImuFactor with a rotated, offset IMU; bias random walk; GNSS with lever arm
// and dt; dual-antenna heading): nonlinear, but covariances at one linearisation point are exact.

struct ImuChain {
  ChainProblem problem;
  ImuConfig imu;
};

/// A navigation-grade IMU (ring-laser class: the sim's preset): its bias random walk gives
/// bias information of 1e17-1e20 per 0.1 s interval.
ImuNoise NavigationGradeNoise() {
  ImuNoise n;
  n.gyro_noise_density_rad_s_sqrt_hz = 5.82e-7;
  n.accel_noise_density_m_s2_sqrt_hz = 1.0e-4;
  n.gyro_bias_random_walk_rad_s2_sqrt_hz = 2.42e-10;
  n.accel_bias_random_walk_m_s3_sqrt_hz = 1.63e-6;
  return n;
}

ImuChain MakeImuChain(int num_keyframes,
                      unsigned seed,
                      double dt = 0.2,
                      const ImuNoise* noise = nullptr) {
  std::mt19937 rng(seed);
  const AnalyticTrajectory traj;
  ImuChain chain;
  chain.imu = test::RotatedOffsetImu();
  if (noise != nullptr) chain.imu.noise = *noise;
  const ImuConfig imu = chain.imu;
  const Eigen::Vector3d lever(-1.5, 0.2, 2.8), baseline(1.0, 0.0, 0.0);
  for (int k = 0; k < num_keyframes; ++k) {
    const double t = 1.0 + k * dt;
    NavState truth = traj.BodyState(t, imu, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
    truth.t_ns = SecondsToNs(t);
    // Linearisation point: near, not at, the truth.
    NavState x = truth;
    x.q_w_b = ExpQ<double>(RandomVector(&rng, 0.01)) * truth.q_w_b;
    x.p_w_b += RandomVector(&rng, 0.2);
    x.v_w += RandomVector(&rng, 0.05);
    x.bg += RandomVector(&rng, 1e-4);
    x.ba += RandomVector(&rng, 1e-2);
    chain.problem.initial.push_back(x);
    if (k == 0) {
      Eigen::Matrix<double, 15, 1> sigmas;
      sigmas << 0.01, 0.01, 0.05, 0.5, 0.5, 1.0, 0.2, 0.2, 0.2, 1e-3, 1e-3, 1e-3, 0.05, 0.05, 0.05;
      if (noise != nullptr) sigmas.tail<6>() << 1e-7, 1e-7, 1e-7, 2.5e-4, 2.5e-4, 2.5e-4;
      const Mat15 P0 = RandomSpd(&rng, sigmas);
      chain.problem.factors.push_back({FactorKind::kStatePrior,
                                       [truth, P0] { return StatePriorFactor::Create(truth, P0); },
                                       AllSlots(0)});
    } else {
      const double t0 = t - dt;
      const auto steps = test::IdealImuSteps(traj, t0, t, 200.0);
      auto pim = std::make_shared<const ImuPreintegration>(
          test::Preintegrate(steps, imu.noise, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()));
      const Eigen::Vector3d g0 = traj.gyro(t0), g1 = traj.gyro(t);
      const ImuEarthTerms earth = traj.EarthTerms(t0);
      chain.problem.factors.push_back(
          {FactorKind::kImu,
           [pim, imu, g0, g1, earth] { return ImuFactor::Create(*pim, imu, g0, g1, earth); },
           {{k - 1, Slot::kQ},
            {k - 1, Slot::kP},
            {k - 1, Slot::kV},
            {k - 1, Slot::kBg},
            {k - 1, Slot::kBa},
            {k, Slot::kQ},
            {k, Slot::kP},
            {k, Slot::kV}}});
      const ImuNoise noise = imu.noise;
      chain.problem.factors.push_back(
          {FactorKind::kBiasRandomWalk,
           [noise, dt] { return std::make_unique<BiasRandomWalkFactor>(noise, dt); },
           {{k - 1, Slot::kBg}, {k - 1, Slot::kBa}, {k, Slot::kBg}, {k, Slot::kBa}}});
    }
    if (k % 2 == 1) {
      const double fix_dt = 0.03;
      const Eigen::Vector3d z =
          truth.p_w_b + truth.v_w * fix_dt + truth.q_w_b * lever + RandomVector(&rng, 0.3);
      const Eigen::Vector3d sigma(0.3, 0.3, 0.5);
      chain.problem.factors.push_back(
          {FactorKind::kGnssPosition,
           [z, sigma, lever, fix_dt] {
             return GnssPositionFactor::Create(z, sigma, lever, fix_dt);
           },
           {{k, Slot::kQ}, {k, Slot::kP}, {k, Slot::kV}, {k, Slot::kGb}}});
    }
    if (k % 3 == 2) {
      const Eigen::Vector3d u = truth.q_w_b * baseline;
      const double heading = std::atan2(u.x(), u.y()) + 0.002;
      chain.problem.factors.push_back({FactorKind::kGnssHeading,
                                       [heading, baseline] {
                                         return GnssHeadingFactor::Create(
                                             heading, 0.005, baseline, Eigen::Matrix3d::Identity());
                                       },
                                       {{k, Slot::kQ}}});
    }
  }
  return chain;
}

TEST(NavGraphTest, ChainCovariancesMatchTheDenseInverse) {
  const int K = 7;
  const ImuChain chain = MakeImuChain(K, 21);
  const auto graph = BuildGraph(chain.problem);
  const Eigen::MatrixXd Sigma =
      DenseInformation(chain.problem.initial, chain.problem.factors).inverse();
  for (const auto form :
       {NavGraph::CovarianceForm::kInformation, NavGraph::CovarianceForm::kSquareRoot}) {
    graph->set_covariance_form(form);
    std::vector<StateCovariance> all;
    ASSERT_TRUE(graph->AllCovariances(&all));
    ASSERT_EQ(all.size(), static_cast<size_t>(K));
    for (int k = 0; k < K; ++k) {
      SCOPED_TRACE("keyframe " + std::to_string(k));
      ExpectCovarianceNear(all[k], Sigma.block<15, 15>(15 * k, 15 * k), 1e-6);
    }
  }
  StateCovariance newest;
  ASSERT_TRUE(graph->NewestCovariance(&newest));
  ExpectCovarianceNear(newest, Sigma.block<15, 15>(15 * (K - 1), 15 * (K - 1)), 1e-6);
}

TEST(NavGraphTest, MarginalisedChainKeepsTheMarginalCovariances) {
  // Marginalised at the same linearisation point (nothing moves), the window's covariances are
  // the marginals of the full problem exactly, rotation columns included.
  const int K = 7, kMarginalised = 4;
  const ImuChain chain = MakeImuChain(K, 22);
  const Eigen::MatrixXd Sigma =
      DenseInformation(chain.problem.initial, chain.problem.factors).inverse();
  for (bool fej : {false, true}) {
    SCOPED_TRACE(fej ? "FEJ" : "no FEJ");
    const auto graph = BuildGraph(chain.problem);
    for (int k = 0; k < kMarginalised; ++k) graph->MarginalizeOldest(fej);
    std::vector<StateCovariance> all;
    ASSERT_TRUE(graph->AllCovariances(&all));
    ASSERT_EQ(all.size(), static_cast<size_t>(K - kMarginalised));
    for (int k = kMarginalised; k < K; ++k) {
      SCOPED_TRACE("keyframe " + std::to_string(k));
      ExpectCovarianceNear(all[k - kMarginalised], Sigma.block<15, 15>(15 * k, 15 * k), 1e-6);
    }
    StateCovariance newest;
    ASSERT_TRUE(graph->NewestCovariance(&newest));
    ExpectCovarianceNear(newest, Sigma.block<15, 15>(15 * (K - 1), 15 * (K - 1)), 1e-6);
  }
}

// Keyframes are found by position (ids are consecutive): an id marginalised away or never added
// is refused, not read from a neighbour's slot.
TEST(NavGraphTest, KeyframesOutsideTheGraphAreRefused) {
  const ImuChain chain = MakeImuChain(5, 22);
  const auto graph = BuildGraph(chain.problem);
  graph->MarginalizeOldest(false);
  EXPECT_THROW(graph->keyframe(0), std::out_of_range);
  EXPECT_THROW(graph->keyframe(5), std::out_of_range);
  EXPECT_EQ(graph->keyframe(1).id, 1);
  EXPECT_EQ(graph->keyframe(4).id, 4);
  const FactorSpec& f = chain.problem.factors.back();
  std::vector<BlockRef> gone = f.blocks;
  for (BlockRef& b : gone) b.keyframe = 0;
  EXPECT_THROW(graph->AddFactor(f.kind, f.make(), nullptr, gone), std::out_of_range);
}

// The same with a navigation-grade IMU at 10 Hz keyframes: bias information of 1e20 next to
// position information of 1e2. Marginalisation and the covariance recursions form Schur
// complements and inverses of such matrices; in raw units double precision loses the weak
// directions (a Schur complement of 1e20-scale entries keeps ~1e4 of absolute error). Checked
// against a long-double reference computed from Ceres' own Jacobian.
// The prior that marginalising keyframe 0 leaves on keyframe 1 against the exact one: the
// marginal covariance of keyframe 1 given the factors that touched keyframe 0, computed in long
// double from Ceres' Jacobian by a QR of its columns [0 | 1]. The prior is formed as a QR of the
// stacked whitened Jacobian (square-root marginalisation), whose errors scale with the
// conditioning of J; the normal equations square it (2.8e12 here after Jacobi scaling), and an
// eigenvalue cut relative to the largest then dropped real information.
TEST(NavGraphTest, NavigationGradeMarginalPriorIsTheExactSchurComplement) {
  const int K = 4;
  const ImuNoise nav = NavigationGradeNoise();
  const ImuChain chain = MakeImuChain(K, 25, 0.1, &nav);
  std::vector<FactorSpec> touching0;
  for (const FactorSpec& f : chain.problem.factors) {
    if (std::any_of(f.blocks.begin(), f.blocks.end(),
                    [](const BlockRef& b) { return b.keyframe == 0; })) {
      touching0.push_back(f);
    }
  }
  ASSERT_GE(touching0.size(), 3u);  // prior, IMU, bias random walk (and perhaps a fix)
  using MatL = Eigen::Matrix<long double, Eigen::Dynamic, Eigen::Dynamic>;
  const MatL J = DenseJacobian(chain.problem.initial, touching0).leftCols(30).cast<long double>();
  const Eigen::HouseholderQR<MatL> qr(J);
  const MatL R11 = qr.matrixQR().block(15, 15, 15, 15).template triangularView<Eigen::Upper>();
  auto covariance_of = [](const MatL& R) {  // (R^T R)^-1 for a square-root information R
    const Eigen::Matrix<long double, Eigen::Dynamic, 1> d = R.colwise().norm().transpose();
    const Eigen::HouseholderQR<MatL> q(R * d.cwiseInverse().asDiagonal());
    const long n = R.cols();
    const MatL Ri =
        q.matrixQR().topRows(n).template triangularView<Eigen::Upper>().solve(MatL::Identity(n, n));
    return Mat15(
        (d.cwiseInverse().asDiagonal() * Ri * Ri.transpose() * d.cwiseInverse().asDiagonal())
            .cast<double>());
  };
  const Mat15 reference = covariance_of(R11);
  for (bool fej : {false, true}) {
    SCOPED_TRACE(fej ? "FEJ" : "no FEJ");
    const auto graph = BuildGraph(chain.problem);
    graph->MarginalizeOldest(fej);
    const std::vector<FactorId> priors = graph->factor_ids(FactorKind::kMarginalPrior);
    ASSERT_EQ(priors.size(), 1u);
    // The prior's tangent Jacobian at keyframe 1 (its blocks are q, p, v, bg, ba).
    const Keyframe& kf1 = graph->keyframe(1);
    const auto* prior = dynamic_cast<const LinearPriorFactor*>(&graph->cost_function(priors[0]));
    ASSERT_NE(prior, nullptr);
    std::vector<const double*> values;
    for (Slot slot : {Slot::kQ, Slot::kP, Slot::kV, Slot::kBg, Slot::kBa}) {
      values.push_back(kf1.block(slot));
    }
    LinearizedResidual lin;
    ASSERT_TRUE(LinearizeResidual(*prior, nullptr, values, values, &lin));
    Eigen::MatrixXd Jp(lin.residual.size(), 15);
    for (int k = 0; k < 5; ++k) Jp.middleCols(3 * k, 3) = lin.jacobians[k];
    ExpectCovarianceNear(covariance_of(Jp.cast<long double>()), reference, 1e-9);
  }
}

// Covariances of a navigation-grade chain, marginalised or not, against the long-double dense
// reference. The information (normal-equation) form's conditioning (2.8e12 after Jacobi
// scaling) bounds what double precision can give it: about 1e-4 of each standard deviation, far
// below anything a gate or a NEES can see. The square-root form (AllCovariances' default since
// stop 81, and NewestCovariance's) works with the Jacobian's conditioning and agrees to 1e-10,
// marginalised (MarginalizeOldest's QR) or not.
TEST(NavGraphTest, NavigationGradeMarginalisationMatchesALongDoubleReference) {
  const int K = 8, kMarginalised = 5;
  const ImuNoise nav = NavigationGradeNoise();
  const ImuChain chain = MakeImuChain(K, 24, 0.1, &nav);
  const Eigen::MatrixXd Sigma = LongDoubleCovariance(chain.problem.initial, chain.problem.factors);
  const auto full = BuildGraph(chain.problem);
  std::vector<StateCovariance> all;
  for (const auto form :
       {NavGraph::CovarianceForm::kSquareRoot, NavGraph::CovarianceForm::kInformation}) {
    const bool square_root = form == NavGraph::CovarianceForm::kSquareRoot;
    full->set_covariance_form(form);
    ASSERT_TRUE(full->AllCovariances(&all));
    for (int k = 0; k < K; ++k) {
      SCOPED_TRACE(std::string(square_root ? "square-root" : "information") +
                   " form, all covariances, keyframe " + std::to_string(k));
      ExpectCovarianceNear(all[k], Sigma.block<15, 15>(15 * k, 15 * k), square_root ? 1e-8 : 3e-4);
    }
  }
  for (bool fej : {false, true}) {
    SCOPED_TRACE(fej ? "FEJ" : "no FEJ");
    const auto graph = BuildGraph(chain.problem);
    for (int k = 0; k < kMarginalised; ++k) graph->MarginalizeOldest(fej);
    ASSERT_TRUE(graph->AllCovariances(&all));
    for (int k = kMarginalised; k < K; ++k) {
      SCOPED_TRACE("keyframe " + std::to_string(k));
      ExpectCovarianceNear(all[k - kMarginalised], Sigma.block<15, 15>(15 * k, 15 * k), 1e-8);
    }
    StateCovariance newest;
    ASSERT_TRUE(graph->NewestCovariance(&newest));
    ExpectCovarianceNear(newest, Sigma.block<15, 15>(15 * (K - 1), 15 * (K - 1)), 1e-8);
  }
}

// PropagateCovariance takes the graph's covariance type: deduce it, so that the test also holds
// when the graph carries extra per-keyframe states beyond the 15 of nav_state.h (the extra ones
// get unit placeholders here; the 15x15 block is compared).
template <typename T>
struct CovarianceArg;
template <typename C>
struct CovarianceArg<bool (NavGraph::*)(KeyframeId, KeyframeId, const C&, C*) const> {
  using type = C;
};
using PropagateCov = CovarianceArg<decltype(&NavGraph::PropagateCovariance)>::type;

bool Propagate(
    const NavGraph& graph, KeyframeId prev, KeyframeId next, const Mat15& P, Mat15* out) {
  PropagateCov prev_cov = PropagateCov::Identity();
  prev_cov.template topLeftCorner<15, 15>() = P;
  PropagateCov next_cov;
  if (!graph.PropagateCovariance(prev, next, prev_cov, &next_cov)) return false;
  *out = next_cov.template topLeftCorner<15, 15>();
  return true;
}

TEST(NavGraphTest, PropagateCovarianceIsTheTwoKeyframeMarginal) {
  const ImuChain chain = MakeImuChain(2, 23);
  // Keyframe 0 at its prior's mean, so the prior's information is exactly P0^-1.
  ChainProblem problem;
  problem.initial = chain.problem.initial;
  std::mt19937 rng(5);
  Eigen::Matrix<double, 15, 1> sigmas;
  sigmas << 0.02, 0.01, 0.08, 0.4, 0.6, 1.0, 0.1, 0.3, 0.2, 2e-3, 1e-3, 1e-3, 0.05, 0.03, 0.05;
  const Mat15 P0 = RandomSpd(&rng, sigmas);
  const NavState s0 = problem.initial[0];
  problem.factors.push_back({FactorKind::kStatePrior,
                             [s0, P0] { return StatePriorFactor::Create(s0, P0); }, AllSlots(0)});
  for (const FactorSpec& f : chain.problem.factors) {
    if (f.kind == FactorKind::kImu || f.kind == FactorKind::kBiasRandomWalk) {
      problem.factors.push_back(f);
    }
  }
  ASSERT_EQ(problem.factors.size(), 3u);
  const auto graph = BuildGraph(problem);
  const Eigen::MatrixXd Sigma = DenseInformation(problem.initial, problem.factors).inverse();
  const Mat15 reference = Sigma.block<15, 15>(15, 15);
  Mat15 propagated;
  ASSERT_TRUE(Propagate(*graph, 0, 1, P0, &propagated));
  ExpectCovarianceNear(propagated, reference, 1e-6);
  // The IMU interval adds uncertainty: the position of keyframe 1 is less certain than of 0.
  const double trace1 = propagated.block<3, 3>(kPos, kPos).trace();
  const double trace0 = P0.block<3, 3>(kPos, kPos).trace();
  EXPECT_GT(trace1, trace0);
  StateCovariance newest;
  ASSERT_TRUE(graph->NewestCovariance(&newest));
  ExpectCovarianceNear(newest, reference, 1e-6);

  // With a fix on keyframe 1 too the rows outnumber its tangent (the least-squares path, not the
  // square one above): still the two-keyframe marginal.
  const Eigen::Vector3d z = problem.initial[1].p_w_b + Eigen::Vector3d(0.2, -0.1, 0.3);
  problem.factors.push_back({FactorKind::kGnssPosition,
                             [z] {
                               return GnssPositionFactor::Create(z, Eigen::Vector3d(0.3, 0.4, 0.6),
                                                                 Eigen::Vector3d(0.5, 0.2, 1.0),
                                                                 0.0);
                             },
                             {{1, Slot::kQ}, {1, Slot::kP}, {1, Slot::kV}, {1, Slot::kGb}}});
  const auto with_fix = BuildGraph(problem);
  const Eigen::MatrixXd Sigma_fix = DenseInformation(problem.initial, problem.factors).inverse();
  ASSERT_TRUE(Propagate(*with_fix, 0, 1, P0, &propagated));
  ExpectCovarianceNear(propagated, Sigma_fix.block<15, 15>(15, 15), 1e-6);
  const double trace_fix = propagated.block<3, 3>(kPos, kPos).trace();
  EXPECT_LT(trace_fix, trace1);  // the fix narrowed it
}

// A consumer-grade IMU without any fix for 60 s: the position's variance grows to ~1e4 m^2 while
// each 0.1 s interval pins the relative position to ~1e-4 m^2. In information form the two
// keyframes' joint information spans twelve orders (double cancels all but four digits, and a
// real run came out with negative variances 45 s into an outage); PropagateCovariance works in
// covariance form. Reference: the Kalman prediction of each interval in long double, from Ceres'
// Jacobians (a different route: no QR, no Cholesky, three more digits).
TEST(NavGraphTest, CovariancesStayPositiveThroughALongOutage) {
  ImuNoise consumer;  // the simulator's consumer grade (EuRoC's ADIS16448 densities)
  consumer.gyro_noise_density_rad_s_sqrt_hz = 1.6968e-4;
  consumer.accel_noise_density_m_s2_sqrt_hz = 2.0e-3;
  consumer.gyro_bias_random_walk_rad_s2_sqrt_hz = 1.9393e-5;
  consumer.accel_bias_random_walk_m_s3_sqrt_hz = 3.0e-3;
  const int K = test::Workload(601, 201);
  const ImuChain chain = MakeImuChain(K, 41, 0.1, &consumer);
  ChainProblem problem;
  problem.initial = chain.problem.initial;
  std::vector<std::vector<FactorSpec>> interval(K);  // the factors between k-1 and k
  for (const FactorSpec& f : chain.problem.factors) {
    if (f.kind != FactorKind::kImu && f.kind != FactorKind::kBiasRandomWalk) continue;
    problem.factors.push_back(f);
    FactorSpec local = f;
    const int k = std::max_element(f.blocks.begin(), f.blocks.end(), [](auto& a, auto& b) {
                    return a.keyframe < b.keyframe;
                  })->keyframe;
    for (BlockRef& b : local.blocks) b.keyframe -= k - 1;
    interval[k].push_back(local);
  }
  const auto graph = BuildGraph(problem);
  using MatL = Eigen::Matrix<long double, 15, 15>;
  // A start known as after a GNSS fix: attitude 3 mrad, position 0.5 m, velocity 0.1 m/s.
  Eigen::Matrix<double, 15, 1> sigmas;
  sigmas << 3e-3, 3e-3, 1e-2, 0.5, 0.5, 0.8, 0.1, 0.1, 0.1, 1e-3, 1e-3, 1e-3, 0.05, 0.05, 0.05;
  std::mt19937 rng(8);
  const Mat15 P0 = RandomSpd(&rng, sigmas);
  Mat15 P = P0;
  MatL P_ref = P.cast<long double>();
  double worst_eig = 1.0;
  std::vector<std::pair<int, Mat15>> predicted;  // the reference every 100 keyframes
  for (int k = 1; k < K; ++k) {
    Mat15 next;
    ASSERT_TRUE(Propagate(*graph, k - 1, k, P, &next)) << "keyframe " << k;
    P = next;
    // Reference, long double: the interval's 15 whitened rows r = J_p dx_p + J_n dx_n + e (IMU
    // and bias random walk) with J_n square and invertible give dx_n = -J_n^-1 (J_p dx_p - r + e):
    // P_n = J_n^-1 (I + J_p P J_p^T) J_n^-T, the Kalman prediction with an implicit transition.
    const Eigen::Matrix<long double, Eigen::Dynamic, Eigen::Dynamic> J =
        DenseJacobian({problem.initial[k - 1], problem.initial[k]}, interval[k])
            .cast<long double>();
    ASSERT_EQ(J.rows(), 15);
    const MatL Jp = J.leftCols(15), X = MatL(J.rightCols(15)).fullPivLu().inverse();
    P_ref = X * (MatL::Identity() + Jp * P_ref * Jp.transpose()) * X.transpose();
    // Positive definite at every step (its correlation matrix's smallest eigenvalue).
    const Eigen::Matrix<double, 15, 1> d = P.diagonal().cwiseSqrt();
    ASSERT_TRUE((P.diagonal().array() > 0.0).all()) << "keyframe " << k << "\n" << P.diagonal();
    const Mat15 C = d.cwiseInverse().asDiagonal() * P * d.cwiseInverse().asDiagonal();
    worst_eig = std::min(worst_eig, Eigen::SelfAdjointEigenSolver<Mat15>(C).eigenvalues()(0));
    if (k % 100 == 0 || k == K - 1) {
      SCOPED_TRACE("keyframe " + std::to_string(k));
      ExpectCovarianceNear(P, P_ref.cast<double>(), 1e-8);
      predicted.emplace_back(k, P_ref.cast<double>());
    }
  }
  EXPECT_GT(worst_eig, 0.0);
  // The whole chain's newest marginal is the same covariance (square-root elimination: the
  // information-form recursion it replaced cancels here as the propagation did).
  // Keyframe 0 gets the start's covariance as a prior at its linearisation point (information
  // exactly P0^-1).
  ChainProblem whole = problem;
  const NavState s0 = problem.initial[0];
  whole.factors.push_back({FactorKind::kStatePrior,
                           [s0, P0] { return StatePriorFactor::Create(s0, P0); }, AllSlots(0)});
  StateCovariance newest;
  const auto whole_graph = BuildGraph(whole);
  ASSERT_TRUE(whole_graph->NewestCovariance(&newest));
  ExpectCovarianceNear(newest, P_ref.cast<double>(), 1e-8);
  // So are the batch's (AllCovariances, the default square-root form): with nothing after the
  // start but the IMU, every keyframe's smoothed marginal is its prediction. The information
  // form's pivots all stay positive here while its subtraction cancels (stop 81 found its
  // newest vertical variance 31x the reference's, full workload): printed, not relied on.
  std::vector<StateCovariance> all;
  ASSERT_TRUE(whole_graph->AllCovariances(&all));
  ASSERT_EQ(all.size(), static_cast<size_t>(K));
  for (const auto& [k, reference] : predicted) {
    SCOPED_TRACE("AllCovariances, keyframe " + std::to_string(k));
    ExpectCovarianceNear(all[static_cast<size_t>(k)], reference, 1e-8);
  }
  whole_graph->set_covariance_form(NavGraph::CovarianceForm::kInformation);
  ASSERT_TRUE(whole_graph->AllCovariances(&all));
  const double ratio = all.back()(kPos + 2, kPos + 2) / P_ref(kPos + 2, kPos + 2);
  std::printf("information form: the newest up variance %.3g x the reference's\n", ratio);
  // The regime the test is for: the position's variance grew past 1e3 m^2 (full workload).
  const double position_variance = P.block<3, 3>(kPos, kPos).trace();
  if (test::kFullWorkload) {
    EXPECT_GT(position_variance, 1e3);
  }
}

// ----------------------------------------------------------------------------------------------
// First-estimate Jacobians.

/// 0.5 |r|^2 of the (single) marginal prior of a graph: invariant to how the prior factors H.
double PriorCost(const NavGraph& graph) {
  const std::vector<FactorId> ids = graph.factor_ids(FactorKind::kMarginalPrior);
  EXPECT_EQ(ids.size(), 1u);
  if (ids.empty()) return NAN;
  return 0.5 * graph.FactorResidual(ids[0]).squaredNorm();
}

/// Moves a keyframe along p, v and ba only, the directions in which every factor of the IMU
/// chain is affine (so a first-order shift of the residual is exact).
void MoveAffine(Keyframe* kf, double scale) {
  Eigen::Map<Eigen::Vector3d>(kf->p) += scale * Eigen::Vector3d(0.7, -0.4, 0.3);
  Eigen::Map<Eigen::Vector3d>(kf->v) += scale * Eigen::Vector3d(-0.3, 0.5, 0.1);
  Eigen::Map<Eigen::Vector3d>(kf->ba) += scale * Eigen::Vector3d(0.02, -0.01, 0.03);
}

/// Sets the same states on the kept keyframes of two graphs, probing their priors there.
void ProbeSameState(const std::vector<Keyframe*>& a,
                    const std::vector<Keyframe*>& b,
                    int k,
                    const Eigen::Vector3d& rotation,
                    double shift) {
  NavState s = a[k]->state();
  s.q_w_b = ExpQ<double>(rotation) * s.q_w_b;
  s.p_w_b += Eigen::Vector3d::Constant(shift);
  s.v_w -= Eigen::Vector3d::Constant(0.5 * shift);
  s.bg += Eigen::Vector3d::Constant(1e-4 * shift);
  a[k]->set_state(s);
  b[k]->set_state(s);
}

TEST(NavGraphTest, FejAndPlainMarginalisationAgreeWhenNothingMoves) {
  const int K = 7;
  const ImuChain chain = MakeImuChain(K, 31);
  std::vector<Keyframe*> kf_fej, kf_plain;
  const auto fej = BuildGraph(chain.problem, &kf_fej);
  const auto plain = BuildGraph(chain.problem, &kf_plain);
  for (int k = 0; k < 3; ++k) {
    fej->MarginalizeOldest(true);
    plain->MarginalizeOldest(false);
    const double c_fej = PriorCost(*fej), c_plain = PriorCost(*plain);
    EXPECT_NEAR(c_fej, c_plain, 1e-9 * std::max(1.0, c_plain)) << "after " << k + 1;
  }
  // Same quadratic as a function of the kept keyframe (probe a few states, rotation included).
  for (double shift : {0.1, -0.3, 0.7}) {
    ProbeSameState(kf_fej, kf_plain, 3, Eigen::Vector3d(0.01, -0.02, 0.03) * shift, shift);
    const double c_fej = PriorCost(*fej), c_plain = PriorCost(*plain);
    EXPECT_GT(c_plain, 1.0);  // the probe is informative
    EXPECT_NEAR(c_fej, c_plain, 1e-9 * c_plain) << "shift " << shift;
  }
  std::vector<StateCovariance> a, b;
  ASSERT_TRUE(fej->AllCovariances(&a));
  ASSERT_TRUE(plain->AllCovariances(&b));
  ASSERT_EQ(a.size(), b.size());
  for (size_t k = 0; k < a.size(); ++k) ExpectCovarianceNear(a[k], b[k], 1e-9);
}

// With FEJ the priors are linearised at the first estimates: moving a state after it got its
// first estimate (as a solve does) must not change the priors that marginalisation produces, and
// the first estimate itself must stay what it was. Without FEJ they change (the control).
TEST(NavGraphTest, FejPriorKeepsTheFirstEstimate) {
  const int K = 7;
  const ImuChain chain = MakeImuChain(K, 32);
  std::map<bool, double> change;  // fej -> relative change of the prior cost
  for (bool use_fej : {true, false}) {
    SCOPED_TRACE(use_fej ? "FEJ" : "no FEJ");
    std::vector<Keyframe*> kf_moved, kf_still;
    const auto moved = BuildGraph(chain.problem, &kf_moved);
    const auto still = BuildGraph(chain.problem, &kf_still);
    moved->MarginalizeOldest(use_fej);
    still->MarginalizeOldest(use_fej);
    // Keyframe 1 now has its first estimate.
    ASSERT_TRUE(kf_moved[1]->has_first_estimate);
    double fe1[16];
    std::copy_n(kf_moved[1]->fe, 16, fe1);
    EXPECT_EQ(Eigen::Map<const Eigen::Vector3d>(fe1 + 4), chain.problem.initial[1].p_w_b);
    // A "solve" moves keyframe 1 (which has its first estimate) in one graph only; marginalise.
    MoveAffine(kf_moved[1], 1.0);
    moved->MarginalizeOldest(use_fej);
    still->MarginalizeOldest(use_fej);
    // Again: keyframe 2 got its first estimate (unmoved), now it moves; marginalise it.
    ASSERT_TRUE(kf_moved[2]->has_first_estimate);
    MoveAffine(kf_moved[2], -0.8);
    const NavState first2 = chain.problem.initial[2];
    EXPECT_EQ(Eigen::Map<const Eigen::Vector3d>(kf_moved[2]->fe + 4), first2.p_w_b);
    EXPECT_EQ(Eigen::Map<const Eigen::Vector3d>(kf_moved[2]->fe + 7), first2.v_w);
    EXPECT_EQ(Eigen::Map<const Eigen::Vector3d>(kf_moved[2]->fe + 13), first2.ba);
    moved->MarginalizeOldest(use_fej);
    still->MarginalizeOldest(use_fej);
    // Compare the priors on keyframe 3 as functions of its state.
    double worst = 0.0;
    for (double shift : {0.0, 0.2, -0.6}) {
      ProbeSameState(kf_moved, kf_still, 3, Eigen::Vector3d(-0.02, 0.01, 0.015) * shift, shift);
      const double a = PriorCost(*moved), b = PriorCost(*still);
      worst = std::max(worst, std::abs(a - b) / std::max(1.0, b));
    }
    change[use_fej] = worst;
  }
  EXPECT_LE(change[true], 1e-8) << "FEJ prior depends on where the states moved";
  EXPECT_GT(change[false], 1e-3) << "control: without FEJ the moves should show";
}

TEST(NavGraphTest, MarginalizeNeedsTwoKeyframes) {
  ChainProblem problem = LinearChain(1, 4);
  const auto graph = BuildGraph(problem);
  EXPECT_THROW(graph->MarginalizeOldest(false), std::logic_error);
}

// ----------------------------------------------------------------------------------------------
// SlidingWindowEstimator on 60 s of the harbour scenario.

struct WindowRunResult {
  Dataset data;
  std::vector<EstimateRecord> outputs;
  std::vector<FixRecord> decisions;
  GnssStats gnss;
  size_t max_keyframes = 0;
  TimeNs injected_t_ns = 0;
};

// The harbour in the world of the estimator's model (solver_test_data.h), without its events.
Dataset ShortHarbour(double duration_s) {
  sim::ScenarioConfig scenario = test::MatchedScenario("harbour");
  scenario.duration_s = duration_s;
  scenario.gnss.jumps.clear();
  scenario.gnss.outages.clear();
  return sim::Simulate(scenario, 5);
}

/// Runs the window over the data in time order (as RunWindow does), with one GNSS fix at
/// `inject_at_s` displaced by `offset_m` (none if offset is zero).
WindowRunResult RunWindowOn(const Dataset& data_in,
                            const EstimatorConfig& config,
                            double inject_at_s,
                            const Eigen::Vector3d& offset_m) {
  WindowRunResult out;
  out.data = data_in;
  std::vector<GnssFix>& fixes = out.data.gnss_fixes;
  if (offset_m.norm() > 0.0) {
    auto it = std::lower_bound(fixes.begin(), fixes.end(), SecondsToNs(inject_at_s),
                               [](const GnssFix& f, TimeNs t) { return f.t_ns < t; });
    EXPECT_NE(it, fixes.end());
    it->p_w += offset_m;
    out.injected_t_ns = it->t_ns;
  }
  SlidingWindowEstimator estimator(config, out.data.imu, out.data.gnss, out.data.Earth());
  size_t g = 0;
  for (const ImuSample& s : out.data.imu_samples) {
    while (g < fixes.size() && fixes[g].t_ns < s.t_ns) estimator.AddGnss(fixes[g++]);
    estimator.AddImu(s);
    out.max_keyframes = std::max(out.max_keyframes, estimator.graph().num_keyframes());
  }
  out.outputs = estimator.outputs();
  out.decisions = estimator.fix_decisions();
  out.gnss = estimator.gnss_stats();
  // Out-of-order input is a caller error.
  ImuSample late = out.data.imu_samples.back();
  late.t_ns -= SecondsToNs(1.0);
  EXPECT_THROW(estimator.AddImu(late), std::invalid_argument);
  EXPECT_GT(g, 0u);
  if (g > 0) {
    GnssFix late_fix = fixes[g - 1];
    late_fix.t_ns -= SecondsToNs(1.0);
    EXPECT_THROW(estimator.AddGnss(late_fix), std::invalid_argument);
  }
  return out;
}

std::optional<NavState> TruthAt(const Dataset& data, TimeNs t) {
  NavState s;
  if (!test::TruthStateAt(data, t, &s)) return std::nullopt;
  return s;
}

class SlidingWindowTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    data_ = new Dataset(ShortHarbour(60.0));
    run_ = new WindowRunResult(
        RunWindowOn(*data_, EstimatorConfig(), kInjectAt, Eigen::Vector3d(50.0, 0.0, 0.0)));
  }
  static void TearDownTestSuite() {
    delete run_;
    delete data_;
  }
  static constexpr double kInjectAt = 40.0;
  static Dataset* data_;
  static WindowRunResult* run_;
};
Dataset* SlidingWindowTest::data_ = nullptr;
WindowRunResult* SlidingWindowTest::run_ = nullptr;

TEST_F(SlidingWindowTest, InitialisesFromCourseOverGround) {
  ASSERT_FALSE(run_->outputs.empty());
  const NavState& first = run_->outputs.front().state;
  // The first fix is the anchor; the state starts at the first IMU sample at or after it.
  EXPECT_GE(first.t_ns, run_->data.gnss_fixes.front().t_ns);
  EXPECT_LE(first.t_ns, run_->data.gnss_fixes.front().t_ns + SecondsToNs(0.005));
  const std::optional<NavState> truth = TruthAt(run_->data, first.t_ns);
  ASSERT_TRUE(truth);
  // Heading 60 deg from the scenario; no current, so course over ground = heading.
  const double heading_err = std::abs(
      WrapAngle(HeadingDeg(first.q_w_b) * M_PI / 180.0 - HeadingDeg(truth->q_w_b) * M_PI / 180.0));
  EXPECT_LT(heading_err * 180.0 / M_PI, 4.0) << HeadingDeg(first.q_w_b);
  EXPECT_NEAR(HeadingDeg(truth->q_w_b), 60.0, 1.0);
  EXPECT_LT((first.p_w_b - truth->p_w_b).head<2>().norm(), 2.0);
  EXPECT_LT((first.v_w - truth->v_w).norm(), 1.0);
  // Roll and pitch from the accelerometer average: within a degree.
  const Eigen::Vector3d up_err = (first.q_w_b.conjugate() * Eigen::Vector3d::UnitZ()) -
                                 (truth->q_w_b.conjugate() * Eigen::Vector3d::UnitZ());
  EXPECT_LT(up_err.norm(), 1.0 * M_PI / 180.0);
}

TEST_F(SlidingWindowTest, OneRecordPerKeyframeAtTenHertz) {
  const auto& out = run_->outputs;
  ASSERT_GT(out.size(), 10u);
  const double span_s = NsToSeconds(out.back().state.t_ns - out.front().state.t_ns);
  EXPECT_NEAR(static_cast<double>(out.size()), span_s * 10.0 + 1.0, 1.0);
  EXPECT_GT(span_s, 55.0);
  for (size_t k = 1; k < out.size(); ++k) {
    ASSERT_EQ(out[k].state.t_ns - out[k - 1].state.t_ns, SecondsToNs(0.1)) << "record " << k;
  }
}

TEST_F(SlidingWindowTest, CovariancesAreSymmetricPositiveDefinite) {
  int count = 0;
  for (const EstimateRecord& r : run_->outputs) {
    ASSERT_TRUE(r.has_covariance);
    const StateCovariance& P = r.covariance;
    ASSERT_TRUE(P.allFinite());
    const double asym = (P - P.transpose()).cwiseAbs().maxCoeff();
    // Relative to the diagonal scale of each entry.
    for (int i = 0; i < 15; ++i) {
      for (int j = 0; j < 15; ++j) {
        ASSERT_LE(std::abs(P(i, j) - P(j, i)), 1e-9 * std::sqrt(P(i, i) * P(j, j)))
            << "asymmetric at t=" << NsToSeconds(r.state.t_ns) << " max " << asym;
      }
    }
    const Eigen::SelfAdjointEigenSolver<StateCovariance> eig(0.5 * (P + P.transpose()));
    ASSERT_GT(eig.eigenvalues().minCoeff(), 0.0) << "t=" << NsToSeconds(r.state.t_ns);
    ++count;
  }
  EXPECT_EQ(count, static_cast<int>(run_->outputs.size()));
}

TEST_F(SlidingWindowTest, EstimatesTrackTheTruthWithConsistentCovariances) {
  double sum_h2 = 0.0, max_heading_err_deg = 0.0;
  std::vector<double> nees;
  int n = 0;
  for (const EstimateRecord& r : run_->outputs) {
    if (r.state.t_ns < SecondsToNs(15.0)) continue;  // let the heading settle
    const std::optional<NavState> truth = TruthAt(run_->data, r.state.t_ns);
    ASSERT_TRUE(truth);
    const Eigen::Vector3d dp = r.state.p_w_b - truth->p_w_b;
    sum_h2 += dp.head<2>().squaredNorm();
    nees.push_back(dp.dot(r.covariance.block<3, 3>(kPos, kPos).ldlt().solve(dp)));
    // Heading: within 3 sigma of its own covariance everywhere; tight once the first turn
    // (30-60 s) has made it observable.
    const double heading_err_deg =
        std::abs(WrapAngle((HeadingDeg(r.state.q_w_b) - HeadingDeg(truth->q_w_b)) * M_PI / 180.0)) *
        180.0 / M_PI;
    EXPECT_LE(heading_err_deg, 3.0 * HeadingSigmaDeg(r.covariance))
        << "t=" << NsToSeconds(r.state.t_ns);
    if (r.state.t_ns > SecondsToNs(45.0)) {
      max_heading_err_deg = std::max(max_heading_err_deg, heading_err_deg);
    }
    ++n;
  }
  ASSERT_GT(n, 400);
  const double rmse_h = std::sqrt(sum_h2 / n);
  EXPECT_LT(rmse_h, 1.0) << "horizontal RMSE, m";
  EXPECT_LT(max_heading_err_deg, 2.0);
  // The first minute is dominated by the deliberately loose initial prior (twice the fix sigma,
  // 1 m/s, 5 deg): the NEES is below 3 there, and is tested on a longer run below.
  for (double v : nees) EXPECT_LT(v, ChiSquareQuantile(0.9999, 3.0));
}

// Position NEES after the start-up: 3 for a consistent estimator, inside the 99 % bounds of the
// number of independent epochs the run is worth (its errors are correlated over tens of seconds:
// EffectiveSampleSize; the plain bounds of 2400 epochs would be [2.8, 3.2]). Four minutes of the
// matched harbour without events, scored from 60 s.
TEST(SlidingWindowConsistency, PositionNeesOfOneRunIsInsideItsCorrelatedBounds) {
  for (std::uint64_t seed : {5, 6}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    sim::ScenarioConfig scenario = test::MatchedScenario("harbour");
    scenario.duration_s = 300.0;
    scenario.gnss.jumps.clear();
    scenario.gnss.outages.clear();
    const Dataset data = sim::Simulate(scenario, seed);
    const WindowRunResult run = RunWindowOn(data, EstimatorConfig(), 0.0, Eigen::Vector3d::Zero());
    std::vector<double> nees;
    for (const EstimateRecord& r : run.outputs) {
      if (r.state.t_ns < SecondsToNs(60.0)) continue;
      const std::optional<NavState> truth = TruthAt(data, r.state.t_ns);
      ASSERT_TRUE(truth);
      const Eigen::Vector3d dp = r.state.p_w_b - truth->p_w_b;
      nees.push_back(dp.dot(r.covariance.block<3, 3>(kPos, kPos).ldlt().solve(dp)));
    }
    ASSERT_GT(nees.size(), 2000u);
    double anees = 0.0;
    for (double v : nees) anees += v / static_cast<double>(nees.size());
    const double n_eff = EffectiveSampleSize(nees);
    const auto bounds = AneesBounds(3, n_eff, 0.99);
    EXPECT_GT(anees, bounds.first) << "effective epochs " << n_eff;
    EXPECT_LT(anees, bounds.second) << "effective epochs " << n_eff;
    // Still a test: a covariance 2.5x too large or 2x too small falls outside.
    EXPECT_GT(bounds.first, 3.0 / 2.5);
    EXPECT_LT(bounds.second, 3.0 * 2.0);
    std::printf("seed %d: ANEES %.2f, bounds [%.2f, %.2f] for %.0f effective epochs of %zu\n",
                static_cast<int>(seed), anees, bounds.first, bounds.second, n_eff, nees.size());
  }
}

TEST_F(SlidingWindowTest, GateRejectsAFixDisplacedByFiftyMetres) {
  ASSERT_GT(run_->injected_t_ns, 0);
  bool found = false;
  for (const FixRecord& rec : run_->decisions) {
    const TimeNs t = rec.t_ns;
    const FixDecision decision = rec.position;
    if (t == run_->injected_t_ns) {
      EXPECT_EQ(decision, FixDecision::kRejectedByGate);
      found = true;
    } else if (t > SecondsToNs(10.0)) {
      // Clean fixes: none rejected (no current, drift well inside the receiver's sigmas).
      EXPECT_TRUE(decision == FixDecision::kAccepted) << "fix at " << NsToSeconds(t);
    }
  }
  EXPECT_TRUE(found);
  EXPECT_EQ(run_->gnss.rejected, 1);
  EXPECT_EQ(run_->gnss.reacquired, 0);
  // The estimate around the outlier is not dragged towards it.
  for (const EstimateRecord& r : run_->outputs) {
    const double dt = NsToSeconds(r.state.t_ns - run_->injected_t_ns);
    if (dt < -1.0 || dt > 3.0) continue;
    const std::optional<NavState> truth = TruthAt(run_->data, r.state.t_ns);
    ASSERT_TRUE(truth);
    EXPECT_LT((r.state.p_w_b - truth->p_w_b).head<2>().norm(), 1.5)
        << "t=" << NsToSeconds(r.state.t_ns);
  }
}

TEST_F(SlidingWindowTest, WithoutTheGateTheDisplacedFixIsAccepted) {
  // Control for the test above: the same data with the gate off.
  EstimatorConfig config;
  config.gnss_gate_probability = 0.0;
  const Dataset shorter = [] {
    Dataset d = *data_;
    while (!d.imu_samples.empty() && d.imu_samples.back().t_ns > SecondsToNs(kInjectAt + 2.0)) {
      d.imu_samples.pop_back();
    }
    return d;
  }();
  const WindowRunResult run = RunWindowOn(shorter, config, kInjectAt, Eigen::Vector3d(50, 0, 0));
  bool found = false;
  for (const FixRecord& rec : run.decisions) {
    const TimeNs t = rec.t_ns;
    const FixDecision decision = rec.position;
    if (t != run.injected_t_ns) continue;
    found = true;
    EXPECT_EQ(decision, FixDecision::kAccepted);
  }
  EXPECT_TRUE(found);
  EXPECT_EQ(run.gnss.rejected, 0);
}

TEST_F(SlidingWindowTest, WindowKeepsAtMostWindowKeyframes) {
  EXPECT_EQ(run_->max_keyframes, static_cast<size_t>(EstimatorConfig().window_keyframes));
  EstimatorConfig small;
  small.window_keyframes = 5;
  Dataset d = *data_;
  d.imu_samples.resize(std::min<size_t>(d.imu_samples.size(), 200 * 12));
  const WindowRunResult run = RunWindowOn(d, small, 0.0, Eigen::Vector3d::Zero());
  EXPECT_EQ(run.max_keyframes, 5u);
  EXPECT_GT(run.outputs.size(), 50u);
}

// Dual-antenna heading initialisation: the receiver measures the heading of the baseline, so
// the body heading is that plus the baseline's angle in the body (counter-clockwise from x, since
// y points to port). A forward baseline hides a sign error; a port or diagonal one does not.
TEST(SlidingWindowInitTest, InitialisesFromDualAntennaHeadingForAnyBaseline) {
  for (const Eigen::Vector3d& baseline :
       {Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 0), Eigen::Vector3d(1, -1, 0)}) {
    SCOPED_TRACE("baseline " + std::to_string(baseline.x()) + " " + std::to_string(baseline.y()));
    sim::ScenarioConfig scenario =
        sim::LoadScenario(std::string(SKERRY_SOURCE_DIR) + "/config/scenarios/harbour.yaml");
    scenario.duration_s = 8.0;
    scenario.gnss.jumps.clear();
    scenario.gnss.outages.clear();
    scenario.gnss.dual_antenna_enabled = true;
    scenario.gnss.heading_sigma_deg = 0.1;
    scenario.gnss.baseline_b = baseline.normalized();
    const Dataset data = sim::Simulate(scenario, 9);
    ASSERT_TRUE(data.gnss_fixes.front().has_heading);
    EstimatorConfig config;
    config.init.mode = "heading";
    const WindowRunResult run = RunWindowOn(data, config, 0.0, Eigen::Vector3d::Zero());
    ASSERT_FALSE(run.outputs.empty());
    const NavState& first = run.outputs.front().state;
    const std::optional<NavState> truth = TruthAt(data, first.t_ns);
    ASSERT_TRUE(truth);
    const double err_deg =
        std::abs(WrapAngle((HeadingDeg(first.q_w_b) - HeadingDeg(truth->q_w_b)) * M_PI / 180.0)) *
        180.0 / M_PI;
    EXPECT_LT(err_deg, 1.0) << "initial heading " << HeadingDeg(first.q_w_b) << " deg, truth "
                            << HeadingDeg(truth->q_w_b) << " deg";
  }
}

TEST_F(SlidingWindowTest, EqualImuTimeIsRejected) {
  SlidingWindowEstimator estimator(EstimatorConfig(), data_->imu, data_->gnss, data_->Earth());
  estimator.AddImu(data_->imu_samples[0]);
  EXPECT_THROW(estimator.AddImu(data_->imu_samples[0]), std::invalid_argument);
}

}  // namespace
}  // namespace skerry
