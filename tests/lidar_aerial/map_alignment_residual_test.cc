// The fine residual: both adapters' Jacobians against central differences in the tangent space
// (EigenQuaternionManifold for the body rotation), the adapters against each other and against
// the extrinsic, the weighting of a scan, and the robust residual.

#include "skerry/lidar_aerial/map_alignment_residual.h"

#include <ceres/autodiff_cost_function.h>
#include <ceres/manifold.h>
#include <ceres/problem.h>
#include <ceres/solver.h>
#include <gtest/gtest.h>

#include <array>

#include "lidar_aerial/synthetic_scene.h"
#include "skerry/lidar_aerial/relief_displacement.h"
#include "skerry/lidar_aerial/scan_preparation.h"

namespace skerry::lidar_aerial {
namespace {

using geo::testing::FreshDir;

struct Fixture {
  testing::Scene scene = testing::Harbour();
  std::string path;
  std::unique_ptr<geo::Orthophoto> ortho;
  std::unique_ptr<AerialMap> map;
  std::shared_ptr<EdgeDistanceField> field;
  PlanarPose sensor;
  std::vector<Eigen::Vector3d> points_l;

  Fixture() {
    path = testing::WriteAerialImage(scene, FreshDir("harbour"));
    ortho = std::make_unique<geo::Orthophoto>(testing::LoadScene(path));
    sensor = {testing::GridToEnu(scene, *ortho, {100, 80}), 0.4};
    map = std::make_unique<AerialMap>(*ortho,
                                      Eigen::AlignedBox2d(sensor.t - Eigen::Vector2d(80, 80),
                                                          sensor.t + Eigen::Vector2d(80, 80)));
    field = std::make_shared<EdgeDistanceField>(*map);
    const testing::Scan scan = testing::SampleScan(scene, *ortho, sensor, 50.0, 0.3);
    ScanPreparationOptions o;
    o.max_points = 300;
    points_l =
        PrepareScan(scan.points_l, scan.intensity, Eigen::Quaterniond::Identity(), o).points_s;
  }
};

// Analytic (autodiff) Jacobian times the manifold's PlusJacobian against central differences of
// the residual along the tangent directions.
void ExpectTangentJacobians(const ceres::CostFunction& cost,
                            std::vector<std::vector<double>> x,
                            const std::vector<const ceres::Manifold*>& manifolds) {
  const int m = cost.num_residuals();
  std::vector<const double*> params;
  for (const auto& v : x) params.push_back(v.data());
  std::vector<std::vector<double>> jac(x.size());
  std::vector<double*> jp;
  for (size_t b = 0; b < x.size(); ++b) {
    jac[b].resize(static_cast<size_t>(m) * x[b].size());
    jp.push_back(jac[b].data());
  }
  std::vector<double> r(static_cast<size_t>(m));
  ASSERT_TRUE(cost.Evaluate(params.data(), r.data(), jp.data()));
  for (size_t b = 0; b < x.size(); ++b) {
    const int n = static_cast<int>(x[b].size());
    const int t = manifolds[b] ? manifolds[b]->TangentSize() : n;
    Eigen::MatrixXd plus = Eigen::MatrixXd::Identity(n, t);
    if (manifolds[b]) {
      Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> pj(n, t);
      manifolds[b]->PlusJacobian(x[b].data(), pj.data());
      plus = pj;
    }
    const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>
        J(jac[b].data(), m, n);
    const Eigen::MatrixXd analytic = J * plus;
    const double h = 1e-6;
    for (int k = 0; k < t; ++k) {
      std::vector<double> d(static_cast<size_t>(t), 0.0), xp(x[b].size()), xm(x[b].size());
      std::vector<double> rp(static_cast<size_t>(m)), rm(static_cast<size_t>(m));
      d[static_cast<size_t>(k)] = h;
      if (manifolds[b]) {
        manifolds[b]->Plus(x[b].data(), d.data(), xp.data());
        d[static_cast<size_t>(k)] = -h;
        manifolds[b]->Plus(x[b].data(), d.data(), xm.data());
      } else {
        xp = x[b];
        xm = x[b];
        xp[static_cast<size_t>(k)] += h;
        xm[static_cast<size_t>(k)] -= h;
      }
      std::vector<const double*> pp = params, pm = params;
      pp[b] = xp.data();
      pm[b] = xm.data();
      ASSERT_TRUE(cost.Evaluate(pp.data(), rp.data(), nullptr));
      ASSERT_TRUE(cost.Evaluate(pm.data(), rm.data(), nullptr));
      for (int i = 0; i < m; ++i) {
        const double numeric = (rp[static_cast<size_t>(i)] - rm[static_cast<size_t>(i)]) / (2 * h);
        EXPECT_NEAR(analytic(i, k), numeric, 1e-5 * (1.0 + std::abs(numeric)))
            << "block " << b << " residual " << i << " direction " << k;
      }
    }
  }
}

TEST(MapAlignmentResidual, BodyPoseJacobiansMatchTangentDifferences) {
  const Fixture f;
  ASSERT_GT(f.points_l.size(), 100u);
  const Eigen::Quaterniond q_b_s(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(0.02, Eigen::Vector3d::UnitX()));
  const Eigen::Vector3d p_b_s(1.5, -0.3, 2.0);
  for (const DistanceLoss loss : {DistanceLoss::kGemanMcClure, DistanceLoss::kHuber}) {
    SCOPED_TRACE(ToString(loss));
    MapAlignmentOptions o;
    o.loss = loss;
    o.loss_sigmas = 1.0;  // both sides of the scale among 300 points
    const auto cost = MapAlignmentCost::Create(f.field, f.points_l, q_b_s, p_b_s, o);
    const Eigen::Quaterniond q_w_b(Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitZ()) *
                                   Eigen::AngleAxisd(0.03, Eigen::Vector3d::UnitY()));
    const Eigen::Vector3d p_w_b(f.sensor.t.x() + 0.7, f.sensor.t.y() - 1.1, 0.4);
    const ceres::EigenQuaternionManifold quaternion;
    ExpectTangentJacobians(
        *cost, {{q_w_b.x(), q_w_b.y(), q_w_b.z(), q_w_b.w()}, {p_w_b.x(), p_w_b.y(), p_w_b.z()}},
        {&quaternion, nullptr});
  }
}

// The deskewed adapter: Jacobians in the tangent space of (q_w_b, p_w_b, v_w_b), and the
// velocity term is the body's motion over each point's time: a scan whose points were measured
// tau_i late from a body moving at v is the undistorted scan shifted by v tau_i.
TEST(MapAlignmentResidual, DeskewedJacobiansMatchTangentDifferences) {
  const Fixture f;
  std::vector<double> tau;
  for (size_t i = 0; i < f.points_l.size(); ++i) tau.push_back(-0.05 + 0.1 * i / f.points_l.size());
  MapAlignmentOptions o;
  o.loss_sigmas = 1.0;  // Geman-McClure, the default
  const auto cost = DeskewedMapAlignmentCost::Create(f.field, f.points_l, tau, o);
  const Eigen::Quaterniond q_w_b(Eigen::AngleAxisd(0.45, Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(0.03, Eigen::Vector3d::UnitY()));
  const Eigen::Vector3d p_w_b(f.sensor.t.x() + 0.7, f.sensor.t.y() - 1.1, 0.4);
  const ceres::EigenQuaternionManifold quaternion;
  ExpectTangentJacobians(*cost,
                         {{q_w_b.x(), q_w_b.y(), q_w_b.z(), q_w_b.w()},
                          {p_w_b.x(), p_w_b.y(), p_w_b.z()},
                          {3.0, -2.0, 0.1}},
                         {&quaternion, nullptr, nullptr});
}

TEST(MapAlignmentResidual, DeskewedVelocityMovesEachPointByItsTime) {
  const Fixture f;
  const int n = static_cast<int>(f.points_l.size());
  std::vector<double> tau;
  for (int i = 0; i < n; ++i) tau.push_back(0.1 * i / n);
  const Eigen::Vector3d v(4.0, -3.0, 0.0);
  const Eigen::Quaterniond q(Eigen::AngleAxisd(f.sensor.yaw, Eigen::Vector3d::UnitZ()));
  // The points as a moving body measured them: each seen from where the body was at tau_i.
  std::vector<Eigen::Vector3d> skewed;
  for (int i = 0; i < n; ++i) skewed.push_back(f.points_l[i] - q.inverse() * (v * tau[i]));
  const double qv[4] = {q.x(), q.y(), q.z(), q.w()};
  const double pv[3] = {f.sensor.t.x(), f.sensor.t.y(), 0.0};
  const double vv[3] = {v.x(), v.y(), v.z()};
  const double zero[3] = {0.0, 0.0, 0.0};
  Eigen::VectorXd r_static(n), r_moving(n), r_ignored(n);
  const double* ps[] = {qv, pv};
  ASSERT_TRUE(MapAlignmentCost::Create(f.field, f.points_l, Eigen::Quaterniond::Identity(),
                                       Eigen::Vector3d::Zero(), {})
                  ->Evaluate(ps, r_static.data(), nullptr));
  const auto cost = DeskewedMapAlignmentCost::Create(f.field, skewed, tau, {});
  const double* pm[] = {qv, pv, vv};
  ASSERT_TRUE(cost->Evaluate(pm, r_moving.data(), nullptr));
  EXPECT_LT((r_static - r_moving).cwiseAbs().maxCoeff(), 1e-9);
  const double* pz[] = {qv, pv, zero};
  ASSERT_TRUE(cost->Evaluate(pz, r_ignored.data(), nullptr));
  EXPECT_GT((r_static - r_ignored).norm(), 0.1);  // the skew matters: 0.5 m at the end
}

// The calibrated mounting's adapter: Jacobians in the tangent space of all five blocks, at a
// mounting off the declared one in every angle, with points deskewed about a tilted axis.
TEST(MapAlignmentResidual, MountedJacobiansMatchTangentDifferences) {
  const Fixture f;
  const int n = static_cast<int>(f.points_l.size());
  const Eigen::Vector3d axis = Eigen::Vector3d(0.1, 0.2, 1.0).normalized();
  std::vector<double> tau;
  std::vector<Eigen::Matrix3d> deskew;
  for (int i = 0; i < n; ++i) {
    tau.push_back(-0.05 + 0.1 * i / n);
    deskew.push_back(Eigen::AngleAxisd(0.3 * tau.back(), axis).toRotationMatrix());
  }
  const Eigen::Quaterniond q_b_s0(Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()) *
                                  Eigen::AngleAxisd(0.02, Eigen::Vector3d::UnitX()));
  const Eigen::Vector3d p_b_s0(1.5, -0.3, 2.0);
  MapAlignmentOptions o;
  o.loss_sigmas = 1.0;
  const auto cost =
      MountedMapAlignmentCost::Create(f.field, f.points_l, tau, deskew, q_b_s0, p_b_s0, o);
  const Eigen::Quaterniond q_w_b(Eigen::AngleAxisd(0.45, Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(0.03, Eigen::Vector3d::UnitY()));
  const Eigen::Vector3d p_w_b(f.sensor.t.x() + 0.7, f.sensor.t.y() - 1.1, 0.4);
  const Eigen::Quaterniond q_b_s =
      Eigen::AngleAxisd(0.03, Eigen::Vector3d(0.3, -0.5, 1.0).normalized()) * q_b_s0;
  const ceres::EigenQuaternionManifold quaternion;
  ExpectTangentJacobians(*cost,
                         {{q_w_b.x(), q_w_b.y(), q_w_b.z(), q_w_b.w()},
                          {p_w_b.x(), p_w_b.y(), p_w_b.z()},
                          {3.0, -2.0, 0.1},
                          {q_b_s.x(), q_b_s.y(), q_b_s.z(), q_b_s.w()},
                          {1.8, -0.1, 2.4}},
                         {&quaternion, nullptr, nullptr, &quaternion, nullptr});
}

// What the mounting's blocks mean: at the declared mounting the block is the deskewed one; a
// turn of the mounting about the body's z axis and a horizontal shift move every point as a
// sensor so mounted would have seen it; its roll, pitch and height do not enter.
TEST(MapAlignmentResidual, MountedSeesTheMountingsYawAndHorizontalLeverArmOnly) {
  const Fixture f;
  const int n = static_cast<int>(f.points_l.size());
  const Eigen::Vector3d axis = Eigen::Vector3d(-0.2, 0.1, 1.0).normalized();
  std::vector<double> tau;
  std::vector<Eigen::Matrix3d> deskew;
  for (int i = 0; i < n; ++i) {
    tau.push_back(0.1 * i / n);
    deskew.push_back(Eigen::AngleAxisd(0.4 * tau.back(), axis).toRotationMatrix());
  }
  const Eigen::Quaterniond q_b_s0(Eigen::AngleAxisd(-0.4, Eigen::Vector3d::UnitZ()) *
                                  Eigen::AngleAxisd(0.03, Eigen::Vector3d::UnitY()));
  const Eigen::Vector3d p_b_s0(0.5, 0.8, 3.0);
  const auto mounted =
      MountedMapAlignmentCost::Create(f.field, f.points_l, tau, deskew, q_b_s0, p_b_s0, {});
  const Eigen::Quaterniond q(Eigen::AngleAxisd(f.sensor.yaw + 0.4, Eigen::Vector3d::UnitZ()));
  const double qv[4] = {q.x(), q.y(), q.z(), q.w()};
  const double pv[3] = {f.sensor.t.x(), f.sensor.t.y(), 0.0};
  const double vv[3] = {2.0, -1.0, 0.0};
  const auto evaluate = [&](const ceres::CostFunction& cost, const Eigen::Quaterniond& q_b_s,
                            const Eigen::Vector3d& p_b_s) {
    Eigen::VectorXd r(n);
    const double qs[4] = {q_b_s.x(), q_b_s.y(), q_b_s.z(), q_b_s.w()};
    const double* pm[] = {qv, pv, vv, qs, p_b_s.data()};
    EXPECT_TRUE(cost.Evaluate(pm, r.data(), nullptr));
    return r;
  };
  Eigen::VectorXd deskewed(n);
  const double* pd[] = {qv, pv, vv};
  ASSERT_TRUE(DeskewedMapAlignmentCost::Create(f.field, f.points_l, tau, {})
                  ->Evaluate(pd, deskewed.data(), nullptr));
  EXPECT_LT((evaluate(*mounted, q_b_s0, p_b_s0) - deskewed).cwiseAbs().maxCoeff(), 1e-9);
  // Roll and pitch (about the body's x and y axes) and height: the same residual.
  // (ZYX angles: the pitch's turn after the roll's leaves the yaw at zero)
  const Eigen::Quaterniond tilted = Eigen::AngleAxisd(-0.04, Eigen::Vector3d::UnitY()) *
                                    Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitX()) * q_b_s0;
  EXPECT_LT((evaluate(*mounted, tilted, p_b_s0 + Eigen::Vector3d(0, 0, 0.7)) - deskewed)
                .cwiseAbs()
                .maxCoeff(),
            1e-9);
  // Yaw and a horizontal shift: the points as that mounting puts them, by hand.
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.03, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3d shift(0.3, -0.2, 0.0);
  std::vector<Eigen::Vector3d> moved(f.points_l.size());
  for (int i = 0; i < n; ++i) {
    moved[i] =
        deskew[i] * (turn * (deskew[i].transpose() * f.points_l[i] - p_b_s0) + p_b_s0 + shift);
  }
  Eigen::VectorXd by_hand(n);
  ASSERT_TRUE(DeskewedMapAlignmentCost::Create(f.field, moved, tau, {})
                  ->Evaluate(pd, by_hand.data(), nullptr));
  const Eigen::VectorXd turned =
      evaluate(*mounted, Eigen::Quaterniond(turn) * q_b_s0, p_b_s0 + shift);
  EXPECT_LT((turned - by_hand).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_GT((turned - deskewed).norm(), 0.1);  // not a trivial comparison
}

// A Gaussian prior on a mounting (q, p) at (q0, p0): 5 degrees, 1 m, as the seam puts one.
struct MountingPrior {
  Eigen::Quaterniond q0;
  Eigen::Vector3d p0;
  template <typename T>
  bool operator()(const T* q, const T* p, T* r) const {
    const Eigen::Quaternion<T> d =
        Eigen::Map<const Eigen::Quaternion<T>>(q) * q0.conjugate().cast<T>();
    for (int i = 0; i < 3; ++i) r[i] = T(2.0) * d.vec()[i] / T(5.0 * M_PI / 180.0);
    for (int i = 0; i < 3; ++i) r[3 + i] = p[i] - T(p0[i]);
    return true;
  }
};

// Perturb and recover: scans of the scene from four body poses held at the truth, put in the
// body frame with a mounting declared 2 degrees and 0.36 m off the true one; the blocks'
// mounting, solved from the declared one under a weak prior there, returns to where it goes
// from a true declaration (the scene's own minimum, which is itself near the truth).
TEST(MapAlignmentResidual, MountedRecoversAMountingTwoDegreesOff) {
  const Fixture f;
  const Eigen::Quaterniond q_true(Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()));
  const Eigen::Vector3d p_true(1.0, 0.5, 2.5);
  std::vector<testing::Scan> scans;
  std::vector<PlanarPose> bodies;
  for (int k = 0; k < 4; ++k) {
    bodies.push_back(
        {f.sensor.t + Eigen::Vector2d(8.0 * (k % 2) - 4.0, 6.0 * (k / 2) - 3.0), 0.9 * k - 1.0});
    // The sensor's planar pose: the body's, composed with the true (yaw-only) mounting.
    const PlanarPose sensor{bodies.back().Apply(p_true.head<2>()), bodies.back().yaw + 0.5};
    scans.push_back(testing::SampleScan(f.scene, *f.ortho, sensor, 50.0, 0.3));
  }
  // The mounting solved from blocks made with the declared one, which is also its start.
  const auto solve = [&](const Eigen::Quaterniond& q_decl, const Eigen::Vector3d& p_decl) {
    double q_est[4] = {q_decl.x(), q_decl.y(), q_decl.z(), q_decl.w()};
    Eigen::Vector3d p_est = p_decl;
    ceres::Problem problem;
    std::vector<std::array<double, 7>> states(scans.size());
    double v[3] = {0.0, 0.0, 0.0};
    for (size_t k = 0; k < scans.size(); ++k) {
      ScanPreparationOptions po;
      po.max_points = 300;
      std::vector<Eigen::Vector3d> points_b =
          PrepareScan(scans[k].points_l, scans[k].intensity, Eigen::Quaterniond::Identity(), po)
              .points_s;
      EXPECT_GT(points_b.size(), 100u);
      for (Eigen::Vector3d& p : points_b) p = q_decl * p + p_decl;  // as the dataset declares
      const size_t n = points_b.size();
      const Eigen::Quaterniond q_w_b(Eigen::AngleAxisd(bodies[k].yaw, Eigen::Vector3d::UnitZ()));
      states[k] = {q_w_b.x(),       q_w_b.y(),       q_w_b.z(), q_w_b.w(),
                   bodies[k].t.x(), bodies[k].t.y(), 0.0};
      MapAlignmentOptions o;
      o.loss_sigmas = 0.0;
      o.effective_points = 1e9;
      problem.AddResidualBlock(
          MountedMapAlignmentCost::Create(
              f.field, points_b, std::vector<double>(n, 0.0),
              std::vector<Eigen::Matrix3d>(n, Eigen::Matrix3d::Identity()), q_decl, p_decl, o)
              .release(),
          nullptr, states[k].data(), states[k].data() + 4, v, q_est, p_est.data());
      problem.SetParameterBlockConstant(states[k].data());
      problem.SetParameterBlockConstant(states[k].data() + 4);
    }
    problem.SetParameterBlockConstant(v);
    problem.SetManifold(q_est, new ceres::EigenQuaternionManifold);
    // The seam's prior at the declared mounting: holds what the map cannot see.
    problem.AddResidualBlock(
        new ceres::AutoDiffCostFunction<MountingPrior, 6, 4, 3>(new MountingPrior{q_decl, p_decl}),
        nullptr, q_est, p_est.data());
    ceres::Solver::Options options;
    options.max_num_iterations = 50;
    ceres::Solver::Summary summary;
    ceres::Solve(options, &problem, &summary);
    EXPECT_TRUE(summary.IsSolutionUsable()) << summary.BriefReport();
    EXPECT_NEAR(p_est.z(), p_decl.z(), 1e-9);  // not seen: held at the prior
    return std::make_pair(Eigen::Quaterniond(q_est[3], q_est[0], q_est[1], q_est[2]), p_est);
  };
  const auto [q_exact, p_exact] = solve(q_true, p_true);
  const Eigen::Quaterniond q_off =
      Eigen::AngleAxisd(2.0 * M_PI / 180.0, Eigen::Vector3d::UnitZ()) * q_true;
  const auto [q_found, p_found] = solve(q_off, p_true + Eigen::Vector3d(0.3, -0.2, 0.0));
  EXPECT_LT(q_found.angularDistance(q_exact) * 180.0 / M_PI, 0.01);
  EXPECT_LT((p_found - p_exact).head<2>().norm(), 0.01) << p_found.transpose();
  // The scene's own minimum: the sampled scans against the photograph's edges.
  EXPECT_LT(q_exact.angularDistance(q_true) * 180.0 / M_PI, 0.1);
  EXPECT_LT((p_exact - p_true).head<2>().norm(), 0.15) << p_exact.transpose();
}

TEST(MapAlignmentResidual, PlanarJacobianMatchesDifferences) {
  const Fixture f;
  std::vector<Eigen::Vector2d> xy;
  for (const Eigen::Vector3d& p : f.points_l) xy.push_back(p.head<2>());
  const auto cost = PlanarAlignmentCost::Create(f.field, xy, {});
  ExpectTangentJacobians(*cost, {{f.sensor.yaw + 0.01, f.sensor.t.x() - 0.4, f.sensor.t.y() + 0.3}},
                         {nullptr});
}

TEST(MapAlignmentResidual, AdaptersAndExtrinsicDescribeTheSameGeometry) {
  const Fixture f;
  std::vector<Eigen::Vector2d> xy;
  for (const Eigen::Vector3d& p : f.points_l) xy.push_back(p.head<2>());
  const double pose[3] = {f.sensor.yaw + 0.02, f.sensor.t.x() + 0.5, f.sensor.t.y() - 0.5};
  const int n = static_cast<int>(xy.size());
  Eigen::VectorXd r_planar(n), r_body(n), r_ext(n);
  const double* pp[] = {pose};
  ASSERT_TRUE(PlanarAlignmentCost::Create(f.field, xy, {})->Evaluate(pp, r_planar.data(), nullptr));
  // The body is the levelled sensor (identity extrinsic), at any height.
  const Eigen::Quaterniond q(Eigen::AngleAxisd(pose[0], Eigen::Vector3d::UnitZ()));
  const double qv[4] = {q.x(), q.y(), q.z(), q.w()};
  const double pv[3] = {pose[1], pose[2], 7.0};
  const double* pb[] = {qv, pv};
  ASSERT_TRUE(MapAlignmentCost::Create(f.field, f.points_l, Eigen::Quaterniond::Identity(),
                                       Eigen::Vector3d::Zero(), {})
                  ->Evaluate(pb, r_body.data(), nullptr));
  EXPECT_LT((r_planar - r_body).cwiseAbs().maxCoeff(), 1e-9);
  // A sensor mounted at T_b_s on a body at T_w_b = T_w_s T_b_s^-1.
  const Eigen::Quaterniond q_b_s(Eigen::AngleAxisd(-0.5, Eigen::Vector3d::UnitZ()));
  const Eigen::Vector3d p_b_s(2.0, 1.0, 3.0);
  const Eigen::Quaterniond q_w_b = q * q_b_s.inverse();
  const Eigen::Vector3d p_w_b = Eigen::Vector3d(pv[0], pv[1], pv[2]) - q_w_b * p_b_s;
  const double qb[4] = {q_w_b.x(), q_w_b.y(), q_w_b.z(), q_w_b.w()};
  const double pbv[3] = {p_w_b.x(), p_w_b.y(), p_w_b.z()};
  const double* pe[] = {qb, pbv};
  ASSERT_TRUE(MapAlignmentCost::Create(f.field, f.points_l, q_b_s, p_b_s, {})
                  ->Evaluate(pe, r_ext.data(), nullptr));
  EXPECT_LT((r_planar - r_ext).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_GT(r_planar.norm(), 0.1);  // not a trivial comparison
}

TEST(MapAlignmentResidual, AScanWeighsAsItsEffectivePointsWhateverItsSize) {
  const Fixture f;
  std::vector<Eigen::Vector2d> xy;
  for (const Eigen::Vector3d& p : f.points_l) xy.push_back(p.head<2>());
  std::vector<Eigen::Vector2d> four_times;
  for (int k = 0; k < 4; ++k) four_times.insert(four_times.end(), xy.begin(), xy.end());
  MapAlignmentOptions o;
  o.effective_points = 50.0;  // below both sizes
  const double pose[3] = {f.sensor.yaw + 0.05, f.sensor.t.x() + 1.0, f.sensor.t.y()};
  const double* pp[] = {pose};
  const auto cost = [&](const std::vector<Eigen::Vector2d>& pts, const MapAlignmentOptions& opt) {
    const auto c = PlanarAlignmentCost::Create(f.field, pts, opt);
    Eigen::VectorXd r(c->num_residuals());
    EXPECT_TRUE(c->Evaluate(pp, r.data(), nullptr));
    return r.squaredNorm();
  };
  EXPECT_NEAR(cost(four_times, o), cost(xy, o), 1e-9 * cost(xy, o));
  // With more effective points than points, each point counts fully.
  MapAlignmentOptions all = o;
  all.effective_points = 1e9;
  EXPECT_NEAR(cost(xy, all) * o.effective_points / static_cast<double>(xy.size()), cost(xy, o),
              1e-9 * cost(xy, o));
  // A scan's share of its information (consecutive scans repeat the map's errors) scales its
  // cost by the share whatever its size, also where every point already counts fully: its
  // residuals are exactly sqrt(share) times its own, as the gate assumes (gate_scale).
  for (const MapAlignmentOptions& base : {o, all}) {
    MapAlignmentOptions shared = base;
    shared.information_share = 0.1;
    EXPECT_NEAR(cost(xy, shared), 0.1 * cost(xy, base), 1e-9 * cost(xy, base));
  }
}

TEST(MapAlignmentResidual, HuberResidualIsLinearThenGrowsAsTheSquareRoot) {
  const double sigma = 0.5, k = 2.0;
  const DistanceLoss huber = DistanceLoss::kHuber;
  EXPECT_DOUBLE_EQ(RobustDistanceResidual(0.5, sigma, huber, k), 1.0);
  EXPECT_DOUBLE_EQ(RobustDistanceResidual(1.0, sigma, huber, k), 2.0);  // the threshold
  EXPECT_NEAR(RobustDistanceResidual(1.0 + 1e-9, sigma, huber, k), 2.0, 1e-8);
  EXPECT_DOUBLE_EQ(RobustDistanceResidual(4.0, sigma, huber, k), std::sqrt(2 * k * 8.0 - k * k));
  EXPECT_DOUBLE_EQ(RobustDistanceResidual(4.0, sigma, huber, 0.0), 8.0);  // no loss
}

// Geman-McClure's rho(s) = k^2 s / (k^2 + s) (Black and Rangarajan 1996, table 1): its square is
// that rho; near an edge it is the distance in sigmas; its influence d rho / d z peaks at
// z = k / sqrt(3) and falls towards zero far off, where Huber's stays at 2k.
TEST(MapAlignmentResidual, GemanMcClureResidualRedescends) {
  const double sigma = 0.5, k = 2.0;
  const DistanceLoss gm = DistanceLoss::kGemanMcClure;
  for (const double z : {0.0, 0.3, 1.0, 2.0, 5.0, 40.0}) {
    const double r = RobustDistanceResidual(z * sigma, sigma, gm, k);
    EXPECT_NEAR(r * r, k * k * z * z / (k * k + z * z), 1e-12) << z;
  }
  EXPECT_NEAR(RobustDistanceResidual(0.01 * sigma, sigma, gm, k), 0.01, 1e-6);
  EXPECT_DOUBLE_EQ(RobustDistanceResidual(4.0, sigma, gm, 0.0), 8.0);  // no loss
  // Influence psi(z) = d(r^2)/dz / 2, by central differences.
  const auto psi = [&](DistanceLoss loss, double z) {
    const double h = 1e-6;
    const double a = RobustDistanceResidual((z + h) * sigma, sigma, loss, k);
    const double b = RobustDistanceResidual((z - h) * sigma, sigma, loss, k);
    return (a * a - b * b) / (4.0 * h);
  };
  const double peak = psi(gm, k / std::sqrt(3.0));
  EXPECT_GT(peak, psi(gm, 0.8 * k / std::sqrt(3.0)));
  EXPECT_GT(peak, psi(gm, 1.2 * k / std::sqrt(3.0)));
  EXPECT_LT(psi(gm, 4.0 * k), 0.1 * peak);  // a point 4 m off barely pulls
  EXPECT_NEAR(psi(DistanceLoss::kHuber, 4.0 * k), k, 1e-6);
}

TEST(MapAlignmentResidual, LossNamesRoundTrip) {
  for (const DistanceLoss loss : {DistanceLoss::kGemanMcClure, DistanceLoss::kHuber}) {
    EXPECT_EQ(ParseDistanceLoss(ToString(loss)), loss);
  }
  EXPECT_THROW(ParseDistanceLoss("cauchy"), std::invalid_argument);
}

// The factor against the camera's ray, intersected here with the floor's plane: the ray from the
// viewpoint C through the top of the structure at (x, z_top) meets z = z_floor at u.
TEST(ReliefDisplacement, FactorPutsThePointWhereTheCameraRayMeetsTheFloor) {
  const Eigen::Vector3d C(12.0, -30.0, 812.0);
  const Eigen::Vector2d x(160.0, 75.0);
  const double z_top = 2.3, z_floor = 0.4;
  const Eigen::Vector3d top(x.x(), x.y(), z_top);
  const double s = (C.z() - z_floor) / (C.z() - top.z());  // along C -> top
  const Eigen::Vector2d u_ray = (C + s * (top - C)).head<2>();
  const double k = ReliefFactor(C, z_top, z_floor);
  EXPECT_NEAR((x + k * (x - C.head<2>()) - u_ray).norm(), 0.0, 1e-9);
  EXPECT_NEAR((u_ray - x).norm(), 1.9 * (x - C.head<2>()).norm() / (812.0 - 2.3), 1e-9);
  // Nothing standing, nothing moves; nor under a viewpoint that is not above the top.
  EXPECT_EQ(ReliefFactor(C, z_floor, z_floor), 0.0);
  EXPECT_EQ(ReliefFactor(Eigen::Vector3d(C.x(), C.y(), 1.5), z_top, z_floor), 0.0);
}

// With relief factors the cost reads the field where the photograph shows each point: equal to the
// plain cost on the points moved there; and its Jacobians still match tangent differences.
TEST(MapAlignmentResidual, ReliefReadsTheFieldWhereThePhotoShowsEachPoint) {
  const Fixture f;
  const int n = static_cast<int>(f.points_l.size());
  const std::vector<double> tau(static_cast<size_t>(n), 0.0);
  std::vector<double> k;
  for (int i = 0; i < n; ++i) k.push_back(i % 3 == 0 ? 0.0 : 0.002 + 0.001 * (i % 5));
  const Eigen::Vector2d nadir = f.sensor.t + Eigen::Vector2d(-120.0, 40.0);
  const Eigen::Quaterniond q(Eigen::AngleAxisd(f.sensor.yaw + 0.01, Eigen::Vector3d::UnitZ()));
  const Eigen::Vector3d p(f.sensor.t.x() + 0.3, f.sensor.t.y() - 0.2, 0.0);
  std::vector<Eigen::Vector3d> shown;
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3d x = q * f.points_l[i] + p;
    x.head<2>() += k[i] * (x.head<2>() - nadir);
    shown.push_back(q.inverse() * (x - p));
  }
  const double qv[4] = {q.x(), q.y(), q.z(), q.w()};
  const double vv[3] = {0.0, 0.0, 0.0};
  const double* x[] = {qv, p.data(), vv};
  Eigen::VectorXd r_relief(n), r_shown(n), r_plain(n);
  const auto cost = DeskewedMapAlignmentCost::Create(f.field, f.points_l, tau, {}, k, nadir);
  ASSERT_TRUE(cost->Evaluate(x, r_relief.data(), nullptr));
  ASSERT_TRUE(DeskewedMapAlignmentCost::Create(f.field, shown, tau, {})
                  ->Evaluate(x, r_shown.data(), nullptr));
  ASSERT_TRUE(DeskewedMapAlignmentCost::Create(f.field, f.points_l, tau, {})
                  ->Evaluate(x, r_plain.data(), nullptr));
  EXPECT_LT((r_relief - r_shown).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_GT((r_relief - r_plain).norm(), 0.1);  // the factors move points by decimetres
  const ceres::EigenQuaternionManifold quaternion;
  ExpectTangentJacobians(*cost,
                         {{qv[0], qv[1], qv[2], qv[3]}, {p.x(), p.y(), p.z()}, {1.0, 2.0, 0.0}},
                         {&quaternion, nullptr, nullptr});
  EXPECT_THROW(DeskewedMapAlignmentCost::Create(f.field, f.points_l, tau, {}, {0.1}, nadir),
               std::invalid_argument);
}

}  // namespace
}  // namespace skerry::lidar_aerial
