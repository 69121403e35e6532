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

}  // namespace
}  // namespace skerry
