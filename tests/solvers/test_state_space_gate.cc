// The state-space gate (innovation_gate.h, GateSpace::kState) against numbers: the projection
// against its closed form, the gate against the full-residual one where they must agree, and its
// chi-square statistics by Monte Carlo on a dense block with a misfit floor no state explains.

#include <ceres/sized_cost_function.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

#include "skerry/core/chi_square.h"
#include "skerry/solvers/innovation_gate.h"

namespace skerry {
namespace {

// r = A (p - p0) + floor on the keyframe's position: a linear block of any length.
class LinearPositionCost : public ceres::CostFunction {
 public:
  LinearPositionCost(Eigen::MatrixXd A, Eigen::Vector3d p0, Eigen::VectorXd floor)
      : A_(std::move(A)), p0_(std::move(p0)), floor_(std::move(floor)) {
    set_num_residuals(static_cast<int>(A_.rows()));
    mutable_parameter_block_sizes()->push_back(3);
  }
  bool Evaluate(double const* const* x, double* r, double** J) const override {
    const Eigen::Map<const Eigen::Vector3d> p(x[0]);
    Eigen::Map<Eigen::VectorXd>(r, num_residuals()) = A_ * (p - p0_) + floor_;
    if (J != nullptr && J[0] != nullptr) {
      Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(J[0], num_residuals(),
                                                                            3) = A_;
    }
    return true;
  }

 private:
  Eigen::MatrixXd A_;
  Eigen::Vector3d p0_;
  Eigen::VectorXd floor_;
};

GraphCovariance PositionCovariance(const Eigen::Matrix3d& Pp) {
  GraphCovariance P = GraphCovariance::Identity() * 1e-4;
  P.block<3, 3>(SlotTangentOffset(Slot::kP), SlotTangentOffset(Slot::kP)) = Pp;
  return P;
}

TEST(StateSpaceGate, ProjectionIsTheClosedForm) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n01;
  Eigen::MatrixXd J(40, 6);
  for (int i = 0; i < J.size(); ++i) J.data()[i] = n01(rng);
  J.col(4).setZero();  // a direction the block cannot see
  Eigen::VectorXd r(40);
  for (int i = 0; i < r.size(); ++i) r(i) = n01(rng);
  const StateSpaceProjection proj = ProjectOnState(r, J);
  ASSERT_EQ(proj.y.size(), 5);
  // |y|^2 = r^T J (J^T J)^+ J^T r, B B^T = J^T J.
  const Eigen::MatrixXd JtJ = J.transpose() * J;
  const Eigen::VectorXd g = J.transpose() * r;
  const double closed = g.dot(JtJ.completeOrthogonalDecomposition().pseudoInverse() * g);
  EXPECT_NEAR(proj.y.squaredNorm(), closed, 1e-9 * closed);
  EXPECT_LT((proj.B * proj.B.transpose() - JtJ).norm(), 1e-9 * JtJ.norm());
}

TEST(StateSpaceGate, AgreesWithTheFullGateWhenTheStateExplainsEveryResidual) {
  Eigen::Matrix3d A;
  A << 2, 0.3, 0, -0.4, 1.5, 0.2, 0.1, 0, 3;
  Keyframe kf;
  kf.p[0] = 1.0;
  kf.p[1] = -2.0;
  const LinearPositionCost cost(A, Eigen::Vector3d(0.3, -1.1, 0.4), Eigen::VectorXd::Zero(3));
  Eigen::Matrix3d Pp;
  Pp << 0.5, 0.1, 0, 0.1, 0.8, 0.05, 0, 0.05, 0.3;
  const GraphCovariance P = PositionCovariance(Pp);
  Innovation full, state;
  ASSERT_TRUE(BlockInnovation(cost, {Slot::kP}, {}, kf, P, &full, nullptr, GateSpace::kResidual));
  ASSERT_TRUE(BlockInnovation(cost, {Slot::kP}, {}, kf, P, &state, nullptr, GateSpace::kState));
  EXPECT_EQ(state.dim, 3);
  EXPECT_NEAR(state.d2, full.d2, 1e-9 * full.d2);
  EXPECT_NEAR(state.log_det_s, full.log_det_s, 1e-9);
}

// 600 residuals on the position with a misfit floor of 3 per residual that no position explains
// (edges in one source only): the full gate rejects every block, the state-space gate is
// chi-square with 3 degrees of freedom when the predicted position error is N(0, P).
TEST(StateSpaceGate, IsChiSquareInTheStateDimensionDespiteAMisfitFloor) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> n01;
  const int m = 600;
  Eigen::MatrixXd A(m, 3);
  for (int i = 0; i < A.size(); ++i) A.data()[i] = 0.2 * n01(rng);
  Eigen::VectorXd floor(m);
  for (int i = 0; i < m; ++i) floor(i) = 3.0 * n01(rng);
  // The floor is what remains at the truth: orthogonal to what the state explains.
  floor -= A * (A.transpose() * A).ldlt().solve(A.transpose() * floor);
  Eigen::Matrix3d Pp = Eigen::Vector3d(4.0, 1.0, 0.25).asDiagonal();
  const GraphCovariance P = PositionCovariance(Pp);
  const Eigen::Matrix3d L = Pp.llt().matrixL();
  const int trials = 4000;
  double sum = 0.0;
  int over = 0, full_over = 0;
  const double gate3 = ChiSquareQuantile(0.99, 3);
  for (int t = 0; t < trials; ++t) {
    // Truth at the origin; the estimate off by N(0, P); the block's noise N(0, I).
    const Eigen::Vector3d err = L * Eigen::Vector3d(n01(rng), n01(rng), n01(rng));
    Eigen::VectorXd noise(m);
    for (int i = 0; i < m; ++i) noise(i) = n01(rng);
    Keyframe kf;
    kf.p[0] = err.x();
    kf.p[1] = err.y();
    kf.p[2] = err.z();
    const LinearPositionCost cost(A, Eigen::Vector3d::Zero(), floor + noise);
    Innovation in;
    ASSERT_TRUE(BlockInnovation(cost, {Slot::kP}, {}, kf, P, &in, nullptr, GateSpace::kState));
    ASSERT_EQ(in.dim, 3);
    sum += in.d2;
    over += in.d2 > gate3;
    if (t < 20) {
      Innovation full;
      ASSERT_TRUE(BlockInnovation(cost, {Slot::kP}, {}, kf, P, &full));
      full_over += full.d2 > ChiSquareQuantile(0.99, m);
    }
  }
  EXPECT_NEAR(sum / trials, 3.0, 0.15);  // chi2_3: mean 3, sd of the mean 0.04
  EXPECT_NEAR(static_cast<double>(over) / trials, 0.01, 0.006);
  EXPECT_EQ(full_over, 20);  // the floor alone is 9 per residual
}

TEST(StateSpaceGate, RejectsAWrongPrediction) {
  const int m = 300;
  std::mt19937_64 rng(11);
  std::normal_distribution<double> n01;
  Eigen::MatrixXd A(m, 3);
  for (int i = 0; i < A.size(); ++i) A.data()[i] = 0.2 * n01(rng);
  const GraphCovariance P = PositionCovariance(Eigen::Matrix3d::Identity() * 0.04);
  Keyframe kf;
  kf.p[0] = 2.0;  // 10 sigma off
  const LinearPositionCost cost(A, Eigen::Vector3d::Zero(), Eigen::VectorXd::Zero(m));
  Innovation in;
  ASSERT_TRUE(BlockInnovation(cost, {Slot::kP}, {}, kf, P, &in, nullptr, GateSpace::kState));
  EXPECT_GT(in.d2, ChiSquareQuantile(0.999, 3));
}

// A block whose residual and Jacobian are scaled by w (SensorMeasurement::gate_scale: a frame
// down-weighted for its correlation with its neighbours in time) is tested on its own noise when
// the gate is told w, in either space; untold, it passes about 1 / w^2 more loosely.
TEST(StateSpaceGate, ADownWeightedBlockIsTestedOnItsOwnNoise) {
  Eigen::MatrixXd A(6, 3);
  A << 2, 0.3, 0, -0.4, 1.5, 0.2, 0.1, 0, 3, 1, 1, 0, 0, -1, 1, 0.5, 0, 0.5;
  Eigen::VectorXd floor(6);
  floor << 0.3, -0.2, 0.1, 0.4, -0.5, 0.2;
  const Eigen::Vector3d p0(0.3, -1.1, 0.4);
  Keyframe kf;
  kf.p[0] = 2.0;
  Eigen::Matrix3d Pp;
  Pp << 0.05, 0.01, 0, 0.01, 0.08, 0.005, 0, 0.005, 0.03;
  const GraphCovariance P = PositionCovariance(Pp);
  const double w = 0.1;
  const LinearPositionCost own(A, p0, floor);
  const LinearPositionCost weighted(w * A, p0, w * floor);
  for (GateSpace space : {GateSpace::kResidual, GateSpace::kState}) {
    Innovation a, b, c;
    ASSERT_TRUE(BlockInnovation(own, {Slot::kP}, {}, kf, P, &a, nullptr, space));
    ASSERT_TRUE(BlockInnovation(weighted, {Slot::kP}, {}, kf, P, &b, nullptr, space, w));
    ASSERT_TRUE(BlockInnovation(weighted, {Slot::kP}, {}, kf, P, &c, nullptr, space));
    EXPECT_EQ(b.dim, a.dim);
    EXPECT_NEAR(b.d2, a.d2, 1e-9 * a.d2);
    EXPECT_NEAR(b.log_det_s, a.log_det_s, 1e-9);
    EXPECT_GT(a.d2, ChiSquareQuantile(0.999, a.dim));  // 2 m off with 0.2-0.3 m sigmas
    EXPECT_LT(c.d2, ChiSquareQuantile(0.999, c.dim));  // what the gate saw when untold
  }
}

TEST(StateSpaceGate, ABlockThatSeesNothingCannotBeGated) {
  const LinearPositionCost cost(Eigen::MatrixXd::Zero(10, 3), Eigen::Vector3d::Zero(),
                                Eigen::VectorXd::Ones(10));
  Keyframe kf;
  Innovation in;
  bool evaluated = false;
  EXPECT_FALSE(BlockInnovation(cost, {Slot::kP}, {}, kf, GraphCovariance::Identity(), &in,
                               &evaluated, GateSpace::kState));
  EXPECT_TRUE(evaluated);
}

// r = A (p - p0) + b (theta - theta0) + e: a block on the keyframe's position and one scalar of
// the sensor's (an estimated map parameter) held at its estimate for the gate.
class PositionAndParameterCost : public ceres::CostFunction {
 public:
  PositionAndParameterCost(
      Eigen::MatrixXd A, Eigen::VectorXd b, Eigen::Vector3d p0, double t0, Eigen::VectorXd e)
      : A_(std::move(A)), b_(std::move(b)), p0_(std::move(p0)), t0_(t0), e_(std::move(e)) {
    set_num_residuals(static_cast<int>(A_.rows()));
    *mutable_parameter_block_sizes() = {3, 1};
  }
  bool Evaluate(double const* const* x, double* r, double** J) const override {
    const Eigen::Map<const Eigen::Vector3d> p(x[0]);
    Eigen::Map<Eigen::VectorXd>(r, num_residuals()) = A_ * (p - p0_) + b_ * (x[1][0] - t0_) + e_;
    if (J != nullptr && J[0] != nullptr) {
      Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>>(J[0], num_residuals(),
                                                                            3) = A_;
    }
    if (J != nullptr && J[1] != nullptr) Eigen::Map<Eigen::VectorXd>(J[1], num_residuals()) = b_;
    return true;
  }

 private:
  Eigen::MatrixXd A_;
  Eigen::VectorXd b_;
  Eigen::Vector3d p0_;
  double t0_;
  Eigen::VectorXd e_;
};

// A fixed block's variance (fixed_variances) widens S by v b b^T: the closed form, and by Monte
// Carlo the gate's d2 is chi-square in the residual's dimension when the parameter is as
// uncertain as its variance says, where the gate holding it exact would reject most blocks.
TEST(StateSpaceGate, AnUncertainFixedParameterWidensTheInnovation) {
  std::mt19937_64 rng(11);
  std::normal_distribution<double> n01;
  const int m = 12;
  Eigen::MatrixXd A(m, 3);
  for (int i = 0; i < A.size(); ++i) A.data()[i] = n01(rng);
  const Eigen::VectorXd b = Eigen::VectorXd::Constant(m, 1.5);  // a common shift of every residual
  Eigen::Matrix3d Pp;
  Pp << 0.2, 0.02, 0, 0.02, 0.3, 0.01, 0, 0.01, 0.1;
  const GraphCovariance P = PositionCovariance(Pp);
  const double v = 4.0;  // the parameter's variance
  Keyframe kf;
  double theta_hat = 0.5;
  const std::vector<const double*> fixed = {&theta_hat};
  const Eigen::Matrix3d Lp = Pp.llt().matrixL();
  // The closed form at one draw.
  {
    const PositionAndParameterCost cost(A, b, Eigen::Vector3d(0.2, -0.1, 0.3), 2.0,
                                        Eigen::VectorXd::Zero(m));
    Innovation in;
    ASSERT_TRUE(BlockInnovation(cost, {Slot::kP}, fixed, kf, P, &in, nullptr, GateSpace::kResidual,
                                1.0, {v}));
    const Eigen::MatrixXd S =
        A * Pp * A.transpose() + v * b * b.transpose() + Eigen::MatrixXd::Identity(m, m);
    const Eigen::VectorXd r = A * (-Eigen::Vector3d(0.2, -0.1, 0.3)) + b * (theta_hat - 2.0);
    const double want = r.dot(S.llt().solve(r));
    EXPECT_NEAR(in.d2, want, 1e-9 * want);
    EXPECT_THROW(BlockInnovation(cost, {Slot::kP}, fixed, kf, P, &in, nullptr, GateSpace::kResidual,
                                 1.0, {v, v}),
                 std::logic_error);
  }
  // Monte Carlo: truth p ~ N(0, Pp) about the estimate 0, theta ~ N(theta_hat, v), unit noise.
  double sum_with = 0.0, sum_without = 0.0;
  int rejected_with = 0, rejected_without = 0;
  const int n = 2000;
  const double q = ChiSquareQuantile(0.999, m);
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d p = Lp * Eigen::Vector3d(n01(rng), n01(rng), n01(rng));
    const double theta = theta_hat + std::sqrt(v) * n01(rng);
    Eigen::VectorXd noise(m);
    for (int i = 0; i < m; ++i) noise(i) = n01(rng);
    // The estimate is at p = 0 (kf.p) and theta_hat: the truth's block, r = A (p_est - p) +
    // b (theta_hat - theta) + noise.
    const PositionAndParameterCost cost(A, b, p, theta, noise);
    Innovation with, without;
    ASSERT_TRUE(BlockInnovation(cost, {Slot::kP}, fixed, kf, P, &with, nullptr,
                                GateSpace::kResidual, 1.0, {v}));
    ASSERT_TRUE(BlockInnovation(cost, {Slot::kP}, fixed, kf, P, &without));
    sum_with += with.d2;
    sum_without += without.d2;
    rejected_with += with.d2 > q;
    rejected_without += without.d2 > q;
  }
  EXPECT_NEAR(sum_with / n, m, 0.1 * m);
  EXPECT_LT(rejected_with, 0.01 * n);
  EXPECT_GT(sum_without / n, 3.0 * m);
  EXPECT_GT(rejected_without, 0.3 * n);
}

}  // namespace
}  // namespace skerry
