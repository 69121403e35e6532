// Perturb, solve, recover: each factor in a small ceres::Problem must pull a perturbed state back
// to the truth (or to the closed-form minimiser).

#include <ceres/autodiff_cost_function.h>
#include <ceres/manifold.h>
#include <ceres/problem.h>
#include <ceres/solver.h>
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <vector>

#include "factors/test_utils.h"
#include "skerry/factors/bias_random_walk_factor.h"
#include "skerry/factors/gnss_drift_factor.h"
#include "skerry/factors/gnss_drift_step_factor.h"
#include "skerry/factors/gnss_heading_factor.h"
#include "skerry/factors/gnss_position_factor.h"
#include "skerry/factors/imu_factor.h"
#include "skerry/factors/linear_prior_factor.h"
#include "skerry/factors/pose_fix_factor.h"
#include "skerry/factors/state_prior_factor.h"

namespace skerry {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

// Parameter blocks of one NavState, owned by the test.
struct StateBlocks {
  explicit StateBlocks(const NavState& s)
      : q(s.q_w_b.coeffs()), p(s.p_w_b), v(s.v_w), bg(s.bg), ba(s.ba) {}
  Eigen::Vector4d q;
  Eigen::Vector3d p, v, bg, ba;
  Eigen::Quaterniond quat() const { return Eigen::Quaterniond(q.data()); }
  void AddTo(ceres::Problem* problem, ceres::Manifold* quaternion_manifold) {
    problem->AddParameterBlock(q.data(), 4, quaternion_manifold);
    for (double* b : {p.data(), v.data(), bg.data(), ba.data()}) problem->AddParameterBlock(b, 3);
  }
  void SetConstant(ceres::Problem* problem) {
    for (double* b : {q.data(), p.data(), v.data(), bg.data(), ba.data()}) {
      problem->SetParameterBlockConstant(b);
    }
  }
};

ceres::Solver::Summary SolveTight(ceres::Problem* problem) {
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::DENSE_QR;
  options.max_num_iterations = 100;
  options.function_tolerance = 1e-16;
  options.gradient_tolerance = 1e-16;
  options.parameter_tolerance = 1e-14;
  ceres::Solver::Summary summary;
  ceres::Solve(options, problem, &summary);
  EXPECT_TRUE(summary.IsSolutionUsable()) << summary.FullReport();
  return summary;
}

// Ownership: Problem takes the cost functions (default options) and we keep the manifold alive.
class RecoverTest : public ::testing::Test {
 protected:
  ceres::EigenQuaternionManifold quaternion_manifold_;
  ceres::Problem::Options ProblemOptions() const {
    ceres::Problem::Options o;
    o.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    return o;
  }
  // The attitude, position and velocity blocks in `problem`, held constant (the drift tests).
  void AddConstantNavBlocks(ceres::Problem* problem,
                            Eigen::Vector4d* q,
                            Eigen::Vector3d* p,
                            Eigen::Vector3d* v) {
    problem->AddParameterBlock(q->data(), 4, &quaternion_manifold_);
    problem->AddParameterBlock(p->data(), 3);
    problem->AddParameterBlock(v->data(), 3);
    for (double* block : {q->data(), p->data(), v->data()})
      problem->SetParameterBlockConstant(block);
  }
};

// n epochs dt apart of a Gauss-Markov drift with `params`, started in its stationary
// distribution, from a fixed seed.
std::vector<Eigen::Vector3d> GaussMarkovDrift(const GnssDriftParams& params,
                                              double dt,
                                              int n,
                                              unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal;
  const double phi = std::exp(-dt / params.tau_s);
  const Eigen::Vector3d sigma = params.StationarySigma();
  std::vector<Eigen::Vector3d> drift(n);
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d w(normal(rng), normal(rng), normal(rng));
    drift[k] = k == 0 ? Eigen::Vector3d(sigma.cwiseProduct(w))
                      : Eigen::Vector3d(phi * drift[k - 1] +
                                        std::sqrt(1.0 - phi * phi) * sigma.cwiseProduct(w));
  }
  return drift;
}

// --- IMU ----------------------------------------------------------------------------------------

// On the round Earth, 25 km from the origin, so the Earth's terms are exercised too.
struct ImuScenario {
  test::AnalyticTrajectory traj{EarthModel(GeoOrigin{54.2, 7.7, 40.0}),
                                Eigen::Vector3d(-20000.0, 15000.0, -49.0)};
  ImuConfig imu = test::RotatedOffsetImu();
  Eigen::Vector3d bg{0.003, -0.002, 0.004};
  Eigen::Vector3d ba{0.05, -0.08, 0.1};
  double t0 = 4.0, t1 = 5.0;
  std::shared_ptr<ImuPreintegration> Pim(const Eigen::Vector3d& bg_lin,
                                         const Eigen::Vector3d& ba_lin) const {
    return std::make_shared<ImuPreintegration>(test::Preintegrate(
        test::IdealImuSteps(traj, t0, t1, 1000.0, bg, ba), imu.noise, bg_lin, ba_lin));
  }
  std::unique_ptr<ceres::CostFunction> Factor(const Eigen::Vector3d& bg_lin,
                                              const Eigen::Vector3d& ba_lin) const {
    return ImuFactor::Create(*Pim(bg_lin, ba_lin), imu, traj.gyro(t0) + bg, traj.gyro(t1) + bg,
                             traj.EarthTerms(t0));
  }
};

void AddImuFactor(ceres::Problem* problem,
                  std::unique_ptr<ceres::CostFunction> cost,
                  StateBlocks* i,
                  StateBlocks* j) {
  problem->AddResidualBlock(cost.release(), nullptr,
                            {i->q.data(), i->p.data(), i->v.data(), i->bg.data(), i->ba.data(),
                             j->q.data(), j->p.data(), j->v.data()});
}

// State i fixed at the truth; state j perturbed by 8 deg, 3 m, 1 m/s. The IMU factor alone
// (9 residuals, 9 unknowns) must bring j back to the truth up to the integration error of
// 1 kHz preintegration (MatchesAnalyticTrajectory: ~1e-8 rad, ~1e-3 m/s, ~5e-4 m), and exactly
// (1e-8) to PredictBodyState, the closed-form zero of the residual.
// Holds roll and pitch at those of q_ref: r = the horizontal components of the world-frame
// rotation error Log(q q_ref^-1), scaled by 1e4.
struct TiltPrior {
  explicit TiltPrior(const Eigen::Quaterniond& q_ref) : q_ref_(q_ref) {}
  template <typename T>
  bool operator()(const T* q_ptr, T* r) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q(q_ptr);
    const Eigen::Quaternion<T> d = q * q_ref_.conjugate().cast<T>();
    r[0] = T(1e4) * d.x();
    r[1] = T(1e4) * d.y();
    return true;
  }
  Eigen::Quaterniond q_ref_;
};

TEST_F(RecoverTest, ImuFactorRecoversPerturbedStateJ) {
  const ImuScenario sc;
  const NavState si = sc.traj.BodyState(sc.t0, sc.imu, sc.bg, sc.ba);
  const NavState sj = sc.traj.BodyState(sc.t1, sc.imu, sc.bg, sc.ba);
  StateBlocks bi(si), bj(sj);
  bj.q = (ExpQ<double>(Eigen::Vector3d(5.0, -4.0, 4.0) * kDeg) * sj.q_w_b).coeffs();
  bj.p += Eigen::Vector3d(3.0, -2.0, 1.0);
  bj.v += Eigen::Vector3d(-1.0, 0.5, 0.3);

  ceres::Problem problem(ProblemOptions());
  bi.AddTo(&problem, &quaternion_manifold_);
  bj.AddTo(&problem, &quaternion_manifold_);
  bi.SetConstant(&problem);
  AddImuFactor(&problem, sc.Factor(sc.bg, sc.ba), &bi, &bj);
  const ceres::Solver::Summary summary = SolveTight(&problem);

  EXPECT_LT(test::AngleBetween(bj.quat(), sj.q_w_b), 1e-7) << summary.BriefReport();
  EXPECT_LT((bj.p - sj.p_w_b).norm(), 1e-3);
  EXPECT_LT((bj.v - sj.v_w).norm(), 2e-3);

  Eigen::Quaterniond q_pred;
  Eigen::Vector3d p_pred, v_pred;
  PredictBodyState(*sc.Pim(sc.bg, sc.ba), sc.imu, sc.traj.EarthTerms(sc.t0),
                   sc.traj.gyro(sc.t0) + sc.bg, sc.traj.gyro(sc.t1) + sc.bg, si.q_w_b, si.p_w_b,
                   si.v_w, si.bg, si.ba, &q_pred, &p_pred, &v_pred);
  EXPECT_LT(test::AngleBetween(bj.quat(), q_pred), 1e-9);
  EXPECT_LT((bj.p - p_pred).norm(), 1e-8);
  EXPECT_LT((bj.v - v_pred).norm(), 1e-8);
}

// The mirror case: j fixed, i perturbed (the residual's Jacobians w.r.t. i drive the solve).
TEST_F(RecoverTest, ImuFactorRecoversPerturbedStateI) {
  const ImuScenario sc;
  const NavState si = sc.traj.BodyState(sc.t0, sc.imu, sc.bg, sc.ba);
  const NavState sj = sc.traj.BodyState(sc.t1, sc.imu, sc.bg, sc.ba);
  StateBlocks bi(si), bj(sj);
  bi.q = (ExpQ<double>(Eigen::Vector3d(-3.0, 6.0, -5.0) * kDeg) * si.q_w_b).coeffs();
  bi.p += Eigen::Vector3d(-2.0, 2.5, -1.0);
  bi.v += Eigen::Vector3d(0.7, -0.4, 0.2);
  ceres::Problem problem(ProblemOptions());
  bi.AddTo(&problem, &quaternion_manifold_);
  bj.AddTo(&problem, &quaternion_manifold_);
  bj.SetConstant(&problem);
  problem.SetParameterBlockConstant(bi.bg.data());
  problem.SetParameterBlockConstant(bi.ba.data());
  AddImuFactor(&problem, sc.Factor(sc.bg, sc.ba), &bi, &bj);
  SolveTight(&problem);
  EXPECT_LT(test::AngleBetween(bi.quat(), si.q_w_b), 1e-7);
  EXPECT_LT((bi.p - si.p_w_b).norm(), 2e-3);
  EXPECT_LT((bi.v - si.v_w).norm(), 2e-3);
}

// Both states fixed at the truth; biases unknown (started at zero, preintegration linearised at
// zero). The IMU factor observes them through the first-order bias correction: bg through dR,
// ba through dv and dp. Tolerances: second-order terms of the correction (|b|^2 ~ 1e-5) plus
// the 1 kHz integration error spread over the 1 s interval (~1e-3 m/s -> ~2e-3 m/s^2 on ba).
TEST_F(RecoverTest, ImuFactorRecoversBiasesFromTrueStates) {
  const ImuScenario sc;
  NavState si = sc.traj.BodyState(sc.t0, sc.imu, sc.bg, sc.ba);
  const NavState sj = sc.traj.BodyState(sc.t1, sc.imu, sc.bg, sc.ba);
  si.bg.setZero();
  si.ba.setZero();
  StateBlocks bi(si), bj(sj);
  ceres::Problem problem(ProblemOptions());
  bi.AddTo(&problem, &quaternion_manifold_);
  bj.AddTo(&problem, &quaternion_manifold_);
  for (double* b : {bi.q.data(), bi.p.data(), bi.v.data(), bj.q.data(), bj.p.data(), bj.v.data()}) {
    problem.SetParameterBlockConstant(b);
  }
  AddImuFactor(&problem, sc.Factor(Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()), &bi, &bj);
  SolveTight(&problem);
  EXPECT_LT((bi.bg - sc.bg).norm(), 5e-5) << bi.bg.transpose();
  EXPECT_LT((bi.ba - sc.ba).norm(), 2e-3) << bi.ba.transpose();
}

// --- GNSS position --------------------------------------------------------------------------

// One keyframe, attitude known (held constant: position fixes alone do not observe it), fixes at
// three epochs around the keyframe with a 2 m lever arm. Noise-free fixes from the truth ->
// p and v recovered exactly from a 4 m / 1 m/s perturbation.
TEST_F(RecoverTest, GnssPositionRecoversPositionAndVelocity) {
  const test::AnalyticTrajectory traj;
  const ImuConfig imu = test::RotatedOffsetImu();
  const Eigen::Vector3d lever_b(1.5, -0.3, 2.0), sigma(0.3, 0.3, 0.8);
  const double t_k = 2.0;
  const NavState s = traj.BodyState(t_k, imu, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  StateBlocks b(s);
  b.p += Eigen::Vector3d(4.0, -3.0, 2.0);
  b.v += Eigen::Vector3d(1.0, -0.5, 0.5);
  ceres::Problem problem(ProblemOptions());
  b.AddTo(&problem, &quaternion_manifold_);
  problem.SetParameterBlockConstant(b.q.data());
  // No drift here: the GNSS bias block is constant zero (as in a graph without the drift model).
  Eigen::Vector3d gb = Eigen::Vector3d::Zero();
  problem.AddParameterBlock(gb.data(), 3);
  problem.SetParameterBlockConstant(gb.data());
  // The factor's model is constant velocity over dt: generate the fixes with that model so the
  // recovery is exact; the attitude at the keyframe carries the lever arm.
  for (double dt : {-0.1, 0.0, 0.08}) {
    const Eigen::Vector3d z = s.p_w_b + s.v_w * dt + s.q_w_b * lever_b;
    problem.AddResidualBlock(GnssPositionFactor::Create(z, sigma, lever_b, dt).release(), nullptr,
                             {b.q.data(), b.p.data(), b.v.data(), gb.data()});
  }
  SolveTight(&problem);
  EXPECT_LT((b.p - s.p_w_b).norm(), 1e-8);
  EXPECT_LT((b.v - s.v_w).norm(), 1e-7);
}

// --- GNSS drift -----------------------------------------------------------------------------

// A chain of GNSS bias states over 60 s, the position known: fixes z_k = p + b_k (+ the lever
// arm) with b_k a Gauss-Markov drift, linked by GnssDriftFactor and anchored by the stationary
// prior. Starting from zero bias, the solve recovers the drift at every epoch (the fixes are
// noise-free and far more precise than the drift model, so the bias follows them).
TEST_F(RecoverTest, GnssDriftRecoversBiasFromFixes) {
  GnssDriftParams params;
  params.tau_s = 30.0;
  const double dt = 1.0;
  const int n = 60;
  const Eigen::Vector3d lever_b(0.5, 0.0, 1.5), sigma_fix(0.001, 0.001, 0.002);
  const Eigen::Quaterniond q_true(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()));
  const Eigen::Vector3d p_true(10.0, -5.0, 1.0), v_true = Eigen::Vector3d::Zero();
  const std::vector<Eigen::Vector3d> truth = GaussMarkovDrift(params, dt, n, 11);
  Eigen::Vector4d q = q_true.coeffs();
  Eigen::Vector3d p = p_true, v = v_true;
  std::vector<Eigen::Vector3d> gb(n, Eigen::Vector3d::Zero());
  ceres::Problem problem(ProblemOptions());
  AddConstantNavBlocks(&problem, &q, &p, &v);
  problem.AddResidualBlock(new GnssDriftPriorFactor(params), nullptr, gb[0].data());
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d z = p_true + q_true * lever_b + truth[k];
    problem.AddResidualBlock(GnssPositionFactor::Create(z, sigma_fix, lever_b, 0.0).release(),
                             nullptr, {q.data(), p.data(), v.data(), gb[k].data()});
    if (k > 0) {
      problem.AddResidualBlock(new GnssDriftFactor(params, dt), nullptr, gb[k - 1].data(),
                               gb[k].data());
    }
  }
  SolveTight(&problem);
  for (int k = 0; k < n; ++k) {
    // The fixes carry sigma_fix; the drift model pulls by at most a fraction of it.
    EXPECT_LT((gb[k] - truth[k]).norm(), 2e-3) << k;
  }
}

// The same chain with the receiver jumping 14.5 m east between epochs 29 and 30 and back between
// 49 and 50 (a lost correction): with GnssDriftStepFactor at both transitions, each step
// measured 0.3 m off with a 0.5 m sigma, the drift is recovered at every epoch from a start at
// zero; with the plain transition there, the chain drags the epochs beside each step off.
TEST_F(RecoverTest, GnssDriftStepRecoversAJumpedReceiver) {
  GnssDriftParams params;
  params.tau_s = 30.0;
  const double dt = 1.0;
  const int n = 70, jump_at = 30, back_at = 50;
  const Eigen::Vector3d jump(14.5, 0.0, 0.0), sigma_fix(0.001, 0.001, 0.002);
  const Eigen::Vector3d p_true(10.0, -5.0, 1.0);
  std::vector<Eigen::Vector3d> truth = GaussMarkovDrift(params, dt, n, 12);
  for (int k = jump_at; k < back_at; ++k) truth[k] += jump;
  const Eigen::Vector3d measured_error(0.3, 0.0, 0.0);
  const Eigen::Matrix3d step_cov = 0.25 * Eigen::Matrix3d::Identity();
  auto solve = [&](bool with_steps) {
    Eigen::Vector4d q = Eigen::Quaterniond::Identity().coeffs();
    Eigen::Vector3d p = p_true, v = Eigen::Vector3d::Zero();
    std::vector<Eigen::Vector3d> gb(n, Eigen::Vector3d::Zero());
    ceres::Problem problem(ProblemOptions());
    AddConstantNavBlocks(&problem, &q, &p, &v);
    problem.AddResidualBlock(new GnssDriftPriorFactor(params), nullptr, gb[0].data());
    for (int k = 0; k < n; ++k) {
      problem.AddResidualBlock(
          GnssPositionFactor::Create(p_true + truth[k], sigma_fix, Eigen::Vector3d::Zero(), 0.0)
              .release(),
          nullptr, {q.data(), p.data(), v.data(), gb[k].data()});
      if (k == 0) continue;
      const bool step = with_steps && (k == jump_at || k == back_at);
      const Eigen::Vector3d s = (k == jump_at ? jump : Eigen::Vector3d(-jump)) + measured_error;
      ceres::CostFunction* transition =
          step ? static_cast<ceres::CostFunction*>(new GnssDriftStepFactor(params, dt, s, step_cov))
               : new GnssDriftFactor(params, dt);
      problem.AddResidualBlock(transition, nullptr, gb[k - 1].data(), gb[k].data());
    }
    SolveTight(&problem);
    double worst = 0.0;
    for (int k = 0; k < n; ++k) worst = std::max(worst, (gb[k] - truth[k]).norm());
    return worst;
  };
  EXPECT_LT(solve(true), 2e-3);
  EXPECT_GT(solve(false), 5e-3);
}

// Zero-mean isotropic prior on a position block.
struct PositionPrior {
  double sigma;
  template <typename T>
  bool operator()(const T* p, T* r) const {
    for (int i = 0; i < 3; ++i) r[i] = p[i] / T(sigma);
    return true;
  }
};

// With the position free as well, position and a constant bias are not separable from fixes
// alone: the drift prior decides. A single keyframe, a fix 0.2 m east of the truth, a tight
// position prior (sigma 0.05 m) -> the bias takes the share sigma_b^2 / (sigma_b^2 + sigma_p^2)
// of the offset (the fix itself noise-free).
TEST_F(RecoverTest, GnssDriftPriorSplitsOffsetByVariance) {
  const GnssDriftParams params;  // sigma_h 0.15 m
  Eigen::Vector4d q = Eigen::Quaterniond::Identity().coeffs();
  Eigen::Vector3d p = Eigen::Vector3d::Zero(), v = Eigen::Vector3d::Zero();
  Eigen::Vector3d gb = Eigen::Vector3d::Zero();
  ceres::Problem problem(ProblemOptions());
  problem.AddParameterBlock(q.data(), 4, &quaternion_manifold_);
  problem.SetParameterBlockConstant(q.data());
  problem.AddParameterBlock(v.data(), 3);
  problem.SetParameterBlockConstant(v.data());
  const double sigma_p = 0.05;
  problem.AddResidualBlock(
      new ceres::AutoDiffCostFunction<PositionPrior, 3, 3>(new PositionPrior{sigma_p}), nullptr,
      p.data());
  problem.AddResidualBlock(new GnssDriftPriorFactor(params), nullptr, gb.data());
  problem.AddResidualBlock(
      GnssPositionFactor::Create(Eigen::Vector3d(0.2, 0.0, 0.0), Eigen::Vector3d::Constant(1e-4),
                                 Eigen::Vector3d::Zero(), 0.0)
          .release(),
      nullptr, {q.data(), p.data(), v.data(), gb.data()});
  SolveTight(&problem);
  const double share = 0.15 * 0.15 / (0.15 * 0.15 + sigma_p * sigma_p);
  EXPECT_NEAR(gb.x(), 0.2 * share, 1e-6);
  EXPECT_NEAR(p.x() + gb.x(), 0.2, 1e-6);
}

// --- GNSS heading ---------------------------------------------------------------------------

// Tilt constraint for the heading test: the world up axis seen in the body, r = R^T e_z - u_b.
struct UpInBody {
  explicit UpInBody(const Eigen::Vector3d& up_b) : up_b_(up_b) {}
  template <typename T>
  bool operator()(const T* q_ptr, T* r_ptr) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q(q_ptr);
    Eigen::Map<Eigen::Matrix<T, 3, 1>> r(r_ptr);
    r = q.conjugate() * Eigen::Matrix<T, 3, 1>(T(0), T(0), T(1)) - up_b_.cast<T>();
    return true;
  }
  Eigen::Vector3d up_b_;
};

// Heading observes yaw only; a tilt constraint fixes roll/pitch. Starting 40 deg off in yaw (and
// 3 deg off in tilt), the pair recovers the full attitude.
TEST_F(RecoverTest, GnssHeadingRecoversYaw) {
  const Eigen::Vector3d baseline_b = Eigen::Vector3d(1.0, 0.2, 0.05).normalized();
  for (double yaw : {0.3, 2.9, -2.0}) {
    const Eigen::Quaterniond q_true(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) *
                                    Eigen::AngleAxisd(0.08, Eigen::Vector3d::UnitY()) *
                                    Eigen::AngleAxisd(-0.12, Eigen::Vector3d::UnitX()));
    // The receiver's heading is from the local north at the fix, here 0.3 deg turned from w's
    // north and tilted (a fix 30 km from the origin).
    const Eigen::Matrix3d R_n_w = ExpSO3(Eigen::Vector3d(0.004, -0.003, 0.3 * kDeg));
    const Eigen::Vector3d u = R_n_w * (q_true * baseline_b);
    const double heading = std::atan2(u.x(), u.y());  // clockwise from north
    Eigen::Vector4d q = (ExpQ<double>(Eigen::Vector3d(0.03, -0.04, 40.0 * kDeg)) * q_true).coeffs();
    ceres::Problem problem(ProblemOptions());
    problem.AddParameterBlock(q.data(), 4, &quaternion_manifold_);
    problem.AddResidualBlock(GnssHeadingFactor::Create(heading, 0.01, baseline_b, R_n_w).release(),
                             nullptr, q.data());
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<UpInBody, 3, 4>(
                                 new UpInBody(q_true.conjugate() * Eigen::Vector3d::UnitZ())),
                             nullptr, q.data());
    SolveTight(&problem);
    EXPECT_LT(test::AngleBetween(Eigen::Quaterniond(q.data()), q_true), 1e-8) << yaw;
  }
}

// --- State prior ----------------------------------------------------------------------------

// Pose fixes of a mast-top sensor taken from three true poses (noise-free): a perturbed pose
// (1 m, 5 deg yaw) is pulled back to the truth, and with the poses held at the truth a perturbed
// lever arm p_b_s (0.4 m) and mounting yaw (3 deg) are recovered too.
TEST_F(RecoverTest, PoseFixRecoversPoseAndExtrinsic) {
  const Eigen::Quaterniond q_b_s_true(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()));
  const Eigen::Vector3d p_b_s_true(0.5, 0.2, 4.0);
  std::vector<Eigen::Quaterniond> q_true;
  std::vector<Eigen::Vector3d> p_true;
  for (int k = 0; k < 3; ++k) {
    q_true.emplace_back(Eigen::AngleAxisd(0.7 * k, Eigen::Vector3d::UnitZ()) *
                        Eigen::AngleAxisd(0.05 * (k + 1), Eigen::Vector3d::UnitX()));
    p_true.emplace_back(10.0 * k, -5.0 * k, 0.3 * k);
  }
  auto fix_of = [&](int k) {
    PoseFix f;
    f.has_heading = true;
    f.has_up = k == 0;  // one 3-D fix, two horizontal
    f.p_w = p_true[k] + q_true[k] * p_b_s_true;
    const Eigen::Vector3d x = q_true[k] * (q_b_s_true * Eigen::Vector3d::UnitX());
    f.heading_deg = std::atan2(x.x(), x.y()) / kDeg;
    f.covariance = Eigen::Vector4d(0.25, 0.25, 1.0, std::pow(kDeg, 2)).asDiagonal();
    return f;
  };
  ceres::EigenQuaternionManifold manifold;  // the problems do not own it
  {
    // Pose from one fix.
    Eigen::Vector4d q =
        (Eigen::AngleAxisd(5 * kDeg, Eigen::Vector3d::UnitZ()) * q_true[0]).coeffs();
    Eigen::Vector3d p = p_true[0] + Eigen::Vector3d(0.6, -0.8, 0.0);
    Eigen::Vector4d qbs = q_b_s_true.coeffs();
    Eigen::Vector3d pbs = p_b_s_true;
    ceres::Problem problem(ProblemOptions());
    problem.AddResidualBlock(
        PoseFixFactor::Create(fix_of(0), Eigen::Matrix3d::Identity()).release(), nullptr, q.data(),
        p.data(), qbs.data(), pbs.data());
    problem.SetManifold(q.data(), &manifold);
    problem.SetManifold(qbs.data(), &manifold);
    problem.SetParameterBlockConstant(qbs.data());
    problem.SetParameterBlockConstant(pbs.data());
    // Roll and pitch are not observed by one fix: hold them by a tight tilt prior (the IMU's job).
    auto* tilt = new ceres::AutoDiffCostFunction<TiltPrior, 2, 4>(new TiltPrior(q_true[0]));
    problem.AddResidualBlock(tilt, nullptr, q.data());
    SolveTight(&problem);
    EXPECT_LT((p - p_true[0]).norm(), 1e-6);
    EXPECT_LT(Eigen::Quaterniond(q.data()).angularDistance(q_true[0]), 1e-8);
  }
  {
    // Extrinsic from three fixes at true poses.
    Eigen::Vector4d qbs =
        (Eigen::AngleAxisd(3 * kDeg, Eigen::Vector3d::UnitZ()) * q_b_s_true).coeffs();
    Eigen::Vector3d pbs = p_b_s_true + Eigen::Vector3d(0.3, -0.25, 0.1);
    std::vector<Eigen::Vector4d> q(3);
    std::vector<Eigen::Vector3d> p(3);
    ceres::Problem problem(ProblemOptions());
    for (int k = 0; k < 3; ++k) {
      q[k] = q_true[k].coeffs();
      p[k] = p_true[k];
      problem.AddResidualBlock(
          PoseFixFactor::Create(fix_of(k), Eigen::Matrix3d::Identity()).release(), nullptr,
          q[k].data(), p[k].data(), qbs.data(), pbs.data());
      problem.SetParameterBlockConstant(q[k].data());
      problem.SetParameterBlockConstant(p[k].data());
    }
    problem.SetManifold(qbs.data(), &manifold);
    SolveTight(&problem);
    EXPECT_LT((pbs - p_b_s_true).norm(), 1e-6);
    // The heading fixes observe the mounting yaw (roll and pitch of a mast sensor are not).
    const Eigen::Vector3d x_s = Eigen::Quaterniond(qbs.data()) * Eigen::Vector3d::UnitX();
    const Eigen::Vector3d x_true = q_b_s_true * Eigen::Vector3d::UnitX();
    EXPECT_NEAR(std::atan2(x_s.y(), x_s.x()), std::atan2(x_true.y(), x_true.x()), 1e-8);
  }
}

TEST_F(RecoverTest, StatePriorRecoversPrior) {
  std::mt19937 rng(5);
  NavState prior;
  prior.q_w_b = test::RandomQuaternion(&rng);
  prior.p_w_b = test::RandomVector(&rng, 20.0);
  prior.v_w = test::RandomVector(&rng, 2.0);
  prior.bg = test::RandomVector(&rng, 0.005);
  prior.ba = test::RandomVector(&rng, 0.05);
  const Eigen::Matrix<double, 15, 15> A = Eigen::Matrix<double, 15, 15>::Random();
  const StateCovariance cov = A * A.transpose() * 0.01 + StateCovariance::Identity() * 1e-4;
  StateBlocks b(prior);
  b.q = (ExpQ<double>(Eigen::Vector3d(0.5, -0.3, 0.8)) * prior.q_w_b).coeffs();
  b.p += Eigen::Vector3d(10.0, -5.0, 3.0);
  b.v += Eigen::Vector3d(1.0, 1.0, -1.0);
  b.bg += Eigen::Vector3d(0.01, -0.01, 0.02);
  b.ba += Eigen::Vector3d(0.3, -0.2, 0.1);
  ceres::Problem problem(ProblemOptions());
  b.AddTo(&problem, &quaternion_manifold_);
  problem.AddResidualBlock(StatePriorFactor::Create(prior, cov).release(), nullptr,
                           {b.q.data(), b.p.data(), b.v.data(), b.bg.data(), b.ba.data()});
  SolveTight(&problem);
  EXPECT_LT(test::AngleBetween(b.quat(), prior.q_w_b), 1e-9);
  EXPECT_LT((b.p - prior.p_w_b).norm(), 1e-8);
  EXPECT_LT((b.v - prior.v_w).norm(), 1e-8);
  EXPECT_LT((b.bg - prior.bg).norm(), 1e-10);
  EXPECT_LT((b.ba - prior.ba).norm(), 1e-9);
}

// --- Bias random walk -----------------------------------------------------------------------

TEST_F(RecoverTest, BiasRandomWalkPullsBiasJToBiasI) {
  Eigen::Vector3d bg_i(0.002, -0.001, 0.003), ba_i(0.05, 0.02, -0.04);
  Eigen::Vector3d bg_j(0.02, 0.01, -0.03), ba_j(-0.5, 0.3, 0.2);
  ceres::Problem problem(ProblemOptions());
  problem.AddResidualBlock(new BiasRandomWalkFactor(ImuNoise(), 0.5), nullptr,
                           {bg_i.data(), ba_i.data(), bg_j.data(), ba_j.data()});
  problem.SetParameterBlockConstant(bg_i.data());
  problem.SetParameterBlockConstant(ba_i.data());
  SolveTight(&problem);
  EXPECT_LT((bg_j - bg_i).norm(), 1e-12);
  EXPECT_LT((ba_j - ba_i).norm(), 1e-12);
}

// A weighted chain: with a prior on bias j, the random walk and the prior split the difference
// by their information (closed form for two scalar Gaussians, per axis).
TEST_F(RecoverTest, BiasRandomWalkWeightsByDensityAndDt) {
  ImuNoise noise;
  const double dt = 0.4;
  const double sigma_rw = noise.accel_bias_random_walk_m_s3_sqrt_hz * std::sqrt(dt);
  const double sigma_prior = 0.01;
  Eigen::Vector3d bg_i = Eigen::Vector3d::Zero(), ba_i = Eigen::Vector3d::Zero();
  Eigen::Vector3d bg_j = Eigen::Vector3d::Zero(), ba_j(1.0, 1.0, 1.0);
  const Eigen::Vector3d prior_ba_j(0.1, -0.2, 0.3);
  ceres::Problem problem(ProblemOptions());
  problem.AddResidualBlock(new BiasRandomWalkFactor(noise, dt), nullptr,
                           {bg_i.data(), ba_i.data(), bg_j.data(), ba_j.data()});
  NavState prior;
  prior.ba = prior_ba_j;
  StateCovariance cov = StateCovariance::Identity() * 1e6;
  cov.block<3, 3>(kBa, kBa) = Eigen::Matrix3d::Identity() * sigma_prior * sigma_prior;
  // Only the ba block of this prior is informative; the other blocks are free scratch states.
  StateBlocks scratch(prior);
  problem.AddResidualBlock(
      StatePriorFactor::Create(prior, cov).release(), nullptr,
      {scratch.q.data(), scratch.p.data(), scratch.v.data(), scratch.bg.data(), ba_j.data()});
  problem.SetManifold(scratch.q.data(), &quaternion_manifold_);
  problem.SetParameterBlockConstant(ba_i.data());
  problem.SetParameterBlockConstant(bg_i.data());
  SolveTight(&problem);
  const double w_rw = 1.0 / (sigma_rw * sigma_rw), w_prior = 1.0 / (sigma_prior * sigma_prior);
  const Eigen::Vector3d expected = (w_rw * ba_i + w_prior * prior_ba_j) / (w_rw + w_prior);
  EXPECT_LT((ba_j - expected).norm(), 1e-9) << ba_j.transpose() << " vs " << expected.transpose();
}

// --- Linear prior from the Schur complement --------------------------------------------------

class LinearPriorTest : public RecoverTest {
 protected:
  void SetUp() override {
    std::mt19937 rng(9);
    sizes_ = {4, 3, 3, 3, 3};
    for (int size : sizes_) {
      x0_.push_back(size == 4 ? Eigen::VectorXd(test::RandomQuaternion(&rng).coeffs())
                              : Eigen::VectorXd(test::RandomVector(&rng, 2.0)));
    }
    const Eigen::MatrixXd A = Eigen::MatrixXd::Random(15, 15);
    H_ = A * A.transpose() + 0.5 * Eigen::MatrixXd::Identity(15, 15);
    g_ = Eigen::VectorXd::Random(15);
  }
  std::vector<int> sizes_;
  std::vector<Eigen::VectorXd> x0_;
  Eigen::MatrixXd H_;
  Eigen::VectorXd g_;
};

TEST_F(LinearPriorTest, FromInformationReproducesHAndG) {
  const std::unique_ptr<LinearPriorFactor> prior =
      LinearPriorFactor::FromInformation(sizes_, x0_, H_, g_);
  ASSERT_NE(prior, nullptr);
  EXPECT_EQ(prior->J().rows(), 15);
  EXPECT_LT((prior->J().transpose() * prior->J() - H_).norm(), 1e-9 * H_.norm());
  EXPECT_LT((prior->J().transpose() * prior->r0() - g_).norm(), 1e-9 * g_.norm());
  EXPECT_EQ(prior->num_residuals(), 15);
  EXPECT_EQ(prior->parameter_block_sizes(), std::vector<int32_t>({4, 3, 3, 3, 3}));
}

// The minimiser of 1/2 |r0 + J dx|^2 is dx* = -H^-1 g in the tangent at x0: q* = Exp(dx_theta) q0.
TEST_F(LinearPriorTest, SolveReachesNewtonStep) {
  std::unique_ptr<LinearPriorFactor> prior =
      LinearPriorFactor::FromInformation(sizes_, x0_, H_, g_);
  ASSERT_NE(prior, nullptr);
  const Eigen::VectorXd dx = -H_.ldlt().solve(g_);
  ASSERT_GT(dx.norm(), 0.01);  // the minimiser really is away from x0

  // Start away from both x0 and the minimiser.
  std::vector<Eigen::VectorXd> x = x0_;
  x[0] =
      (ExpQ<double>(Eigen::Vector3d(0.2, -0.1, 0.3)) * Eigen::Quaterniond(x0_[0].data())).coeffs();
  for (size_t k = 1; k < x.size(); ++k) x[k] += Eigen::Vector3d(0.5, -0.5, 0.25);
  ceres::Problem problem(ProblemOptions());
  problem.AddParameterBlock(x[0].data(), 4, &quaternion_manifold_);
  std::vector<double*> ptrs;
  for (Eigen::VectorXd& v : x) ptrs.push_back(v.data());
  problem.AddResidualBlock(prior.release(), nullptr, ptrs);
  SolveTight(&problem);

  const Eigen::Quaterniond q_expected =
      ExpQ<double>(Eigen::Vector3d(dx.head<3>())) * Eigen::Quaterniond(x0_[0].data());
  EXPECT_LT(test::AngleBetween(Eigen::Quaterniond(x[0].data()), q_expected), 1e-9);
  for (size_t k = 1; k < x.size(); ++k) {
    const Eigen::VectorXd expected = x0_[k] + dx.segment(3 * k, 3);
    EXPECT_LT((x[k] - expected).norm(), 1e-9) << k;
  }
}

// A rank-deficient H (a gauge direction, as after marginalising with unobservable yaw) keeps only
// the informative directions and still reproduces H and g.
TEST_F(LinearPriorTest, FromInformationDropsNullSpace) {
  Eigen::VectorXd n = Eigen::VectorXd::Zero(15);
  n << 0.0, 0.0, 1.0, 0.3, -0.2, 0.0, 0.1, 0.1, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0;
  n.normalize();
  const Eigen::MatrixXd P = Eigen::MatrixXd::Identity(15, 15) - n * n.transpose();
  const Eigen::MatrixXd H = P * H_ * P;
  const Eigen::VectorXd g = P * g_;
  const std::unique_ptr<LinearPriorFactor> prior =
      LinearPriorFactor::FromInformation(sizes_, x0_, H, g, 1e-9);
  ASSERT_NE(prior, nullptr);
  EXPECT_EQ(prior->J().rows(), 14);
  EXPECT_LT((prior->J() * n).norm(), 1e-9);
  EXPECT_LT((prior->J().transpose() * prior->J() - H).norm(), 1e-9 * H.norm());
  EXPECT_LT((prior->J().transpose() * prior->r0() - g).norm(), 1e-9 * g.norm());
  // Nothing informative at all -> nullptr.
  EXPECT_EQ(LinearPriorFactor::FromInformation(sizes_, x0_, Eigen::MatrixXd::Zero(15, 15),
                                               Eigen::VectorXd::Zero(15)),
            nullptr);
}

// A prior from a covariance C weighs a tangent-space step d by the Mahalanobis distance:
// |r|^2 = d^T C^-1 d (a quaternion step as q = Exp(d_theta) q0, the factor's own (-)).
TEST_F(LinearPriorTest, FromCovarianceWhitensByTheCovariance) {
  const Eigen::MatrixXd C = H_.inverse();
  const std::unique_ptr<LinearPriorFactor> prior =
      LinearPriorFactor::FromCovariance(sizes_, x0_, C);
  ASSERT_NE(prior, nullptr);
  EXPECT_LT((prior->J().transpose() * prior->J() - H_).norm(), 1e-9 * H_.norm());
  Eigen::VectorXd d(15);
  d << 0.05, -0.02, 0.03, 0.4, -0.1, 0.2, 1.0, 0.5, -0.3, 0.01, 0.02, -0.01, 0.1, -0.2, 0.05;
  std::vector<Eigen::VectorXd> x = x0_;
  x[0] = (ExpQ<double>(Eigen::Vector3d(d.head<3>())) * Eigen::Quaterniond(x0_[0].data())).coeffs();
  for (size_t k = 1; k < x.size(); ++k) x[k] += d.segment(3 * k, 3);
  std::vector<const double*> ptrs;
  for (const Eigen::VectorXd& v : x) ptrs.push_back(v.data());
  Eigen::VectorXd r(15);
  ASSERT_TRUE(prior->Evaluate(ptrs.data(), r.data(), nullptr));
  const double expected = d.dot(C.ldlt().solve(d));
  EXPECT_NEAR(r.squaredNorm(), expected, 1e-9 * expected);
}

TEST_F(LinearPriorTest, FromCovarianceRefusesWhatIsNotACovariance) {
  Eigen::MatrixXd indefinite = H_.inverse();
  indefinite(4, 4) = -1.0;
  EXPECT_EQ(LinearPriorFactor::FromCovariance(sizes_, x0_, indefinite), nullptr);
  Eigen::MatrixXd nan = H_.inverse();
  nan(2, 7) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(LinearPriorFactor::FromCovariance(sizes_, x0_, nan), nullptr);
  EXPECT_EQ(LinearPriorFactor::FromCovariance(sizes_, x0_, Eigen::MatrixXd::Zero(15, 15)), nullptr);
  // The size is the blocks' tangent size: 15 here, not the ambient 16.
  EXPECT_THROW(LinearPriorFactor::FromCovariance(sizes_, x0_, Eigen::MatrixXd::Identity(16, 16)),
               std::invalid_argument);
}

}  // namespace
}  // namespace skerry
