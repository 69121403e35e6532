// A block's information at the map's scale (information_at_scale.h): the kept block's Jacobian on
// the position against central differences, its information along and across the weak
// direction, and the measure on costs whose curvature is (a bowl) and is not (fine texture on a
// flat floor) what they rise over a metre.

#include "skerry/lidar_aerial/information_at_scale.h"

#include <ceres/autodiff_cost_function.h>
#include <gtest/gtest.h>

#include <cmath>

namespace skerry::lidar_aerial {
namespace {

// A block on (q, p, v) whose residuals are a bowl across the unit direction `across` (curvature
// a^2) and, along the perpendicular, a bowl of curvature b^2 plus ripples of amplitude c and
// period `period_m` (a breakwater's rock: steep locally, flat over metres); q and v enter weakly.
struct Textured {
  Eigen::Vector2d across;
  double a, b, c, period_m;
  template <typename T>
  bool operator()(const T* q, const T* p, const T* v, T* r) const {
    const T u = T(across.x()) * p[0] + T(across.y()) * p[1];
    const T s = -T(across.y()) * p[0] + T(across.x()) * p[1];
    r[0] = T(a) * u + T(0.1) * q[2];
    r[1] = T(b) * s + T(c) * sin(T(2.0 * M_PI / period_m) * s) + T(0.05) * v[0];
    r[2] = T(0.3) * p[2] * p[2] + T(0.2) * q[0] * s;
    return true;
  }
  static std::shared_ptr<ceres::CostFunction> Create(const Textured& t) {
    return std::make_shared<ceres::AutoDiffCostFunction<Textured, 3, 4, 3, 3>>(new Textured(t));
  }
};

NavState At(const Eigen::Vector3d& p) {
  NavState s;
  s.q_w_b = Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(0.2, -0.1, 1).normalized()));
  s.p_w_b = p;
  s.v_w = Eigen::Vector3d(1.0, -0.5, 0.1);
  return s;
}

Eigen::Matrix<double, 3, 3, Eigen::RowMajor> PositionJacobian(const ceres::CostFunction& cost,
                                                              const NavState& s,
                                                              Eigen::Vector3d* r) {
  Eigen::Matrix<double, 3, 4, Eigen::RowMajor> jq;
  Eigen::Matrix<double, 3, 3, Eigen::RowMajor> jp, jv;
  const double* x[] = {s.q_w_b.coeffs().data(), s.p_w_b.data(), s.v_w.data()};
  double* j[] = {jq.data(), jp.data(), jv.data()};
  EXPECT_TRUE(cost.Evaluate(x, r->data(), j));
  return jp;
}

TEST(InformationAtScale, TheKeptBlocksJacobianMatchesCentralDifferences) {
  const Eigen::Vector2d across = Eigen::Vector2d(1.0, 2.0).normalized();
  const auto inner = Textured::Create({across, 3.0, 2.0, 0.2, 0.5});
  const Eigen::Vector3d p0(0.3, -0.2, 0.1);
  const Eigen::Vector2d w(-across.y(), across.x());
  const auto kept = KeepAlong(inner, p0, w, 0.04);
  const NavState s = At(Eigen::Vector3d(0.7, 0.4, -0.3));
  Eigen::Vector3d r;
  const auto jp = PositionJacobian(*kept, s, &r);
  constexpr double h = 1e-6;
  for (int k = 0; k < 3; ++k) {
    NavState plus = s, minus = s;
    plus.p_w_b(k) += h;
    minus.p_w_b(k) -= h;
    Eigen::Vector3d rp, rm;
    PositionJacobian(*kept, plus, &rp);
    PositionJacobian(*kept, minus, &rm);
    EXPECT_LT((jp.col(k) - (rp - rm) / (2 * h)).norm(), 1e-6) << "p" << k;
  }
  // The rotation and velocity Jacobians are the inner block's at the remapped position.
  const Eigen::Vector3d w3(w.x(), w.y(), 0.0);
  NavState mapped = s;
  mapped.p_w_b = p0 + (Eigen::Matrix3d::Identity() - 0.8 * w3 * w3.transpose()) * (s.p_w_b - p0);
  Eigen::Vector3d r_inner;
  PositionJacobian(*inner, mapped, &r_inner);
  EXPECT_LT((r - r_inner).norm(), 1e-12);
}

TEST(InformationAtScale, TheKeptBlockHoldsTheShareAlongAndAllAcross) {
  const Eigen::Vector2d across(0.6, 0.8);
  const Eigen::Vector2d w(-0.8, 0.6);
  const auto inner = Textured::Create({across, 3.0, 2.0, 0.0, 0.5});
  const NavState s = At(Eigen::Vector3d(0.0, 0.0, 0.0));
  Eigen::Vector3d r;
  const auto J0 = PositionJacobian(*inner, s, &r);
  const auto J1 = PositionJacobian(*KeepAlong(inner, s.p_w_b, w, 0.25), s, &r);
  const Eigen::Matrix2d I0 = (J0.transpose() * J0).topLeftCorner<2, 2>();
  const Eigen::Matrix2d I1 = (J1.transpose() * J1).topLeftCorner<2, 2>();
  EXPECT_NEAR(w.dot(I1 * w), 0.25 * w.dot(I0 * w), 1e-9);
  EXPECT_NEAR(across.dot(I1 * across), across.dot(I0 * across), 1e-9);
  // keep 1: the block itself.
  EXPECT_EQ(KeepAlong(inner, s.p_w_b, w, 1.0).get(), inner.get());
}

TEST(InformationAtScale, ABowlKeepsItsCurvatureAndFineTextureLosesIt) {
  const Eigen::Vector2d across(1.0, 0.0);
  const NavState s = At(Eigen::Vector3d::Zero());
  // A bowl along y: f rises by b^2 s^2, as the curvature says.
  const auto bowl = MeasureWeakDirection(*Textured::Create({across, 3.0, 1.0, 0.0, 0.5}), s, 1.0);
  ASSERT_TRUE(bowl);
  EXPECT_GT(std::abs(bowl->direction.y()), 0.99);
  EXPECT_NEAR(bowl->local, 1.0, 0.05);
  EXPECT_GT(bowl->keep, 0.9);
  // Ripples of 0.5 m on a shallow floor: locally steep (c 2 pi / 0.5 = 2.5 on a floor of 0.1),
  // over a metre the cost rises as the floor alone does.
  const auto rock = MeasureWeakDirection(*Textured::Create({across, 3.0, 0.1, 0.2, 0.5}), s, 1.0);
  ASSERT_TRUE(rock);
  EXPECT_GT(std::abs(rock->direction.y()), 0.99);
  EXPECT_GT(rock->local, 5.0);
  EXPECT_LT(rock->keep, 0.01);
  EXPECT_LT(rock->constraint_ratio, 0.01 * rock->local / 9.0 + 1e-9);
  // Scale 0: the local curvature as it is.
  const auto local = MeasureWeakDirection(*Textured::Create({across, 3.0, 0.1, 0.2, 0.5}), s, 0.0);
  ASSERT_TRUE(local);
  EXPECT_EQ(local->keep, 1.0);
}

}  // namespace
}  // namespace skerry::lidar_aerial
