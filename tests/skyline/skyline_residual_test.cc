#include "skerry/skyline/skyline_residual.h"

#include <ceres/ceres.h>
#include <gtest/gtest.h>

#include <array>
#include <random>

#include "skerry/core/parallel_for.h"
#include "skerry/geo/terrain_sharpening.h"
#include "skerry/skyline/crest_correlation.h"
#include "skyline/skyline_test_scene.h"

namespace skerry::skyline {
namespace {

constexpr double kDeg = M_PI / 180.0;

struct Scene {
  std::shared_ptr<const HorizonPredictor> horizon =
      std::make_shared<HorizonPredictor>(testing::MountainRing());
  CameraModel camera{[] {
    CameraConfig c = PinholeFromFov("camera", 1920, 1080, 70.0);
    c.distortion = {-0.05, 0.01, 0.0, 0.0};
    return c;
  }()};
  // Body at (120, -340, 0) heading 30 deg (clockwise from north), rolled 2 deg; mast 4 m.
  Eigen::Quaterniond q_w_b =
      Eigen::Quaterniond(Eigen::AngleAxisd(-30 * kDeg, Eigen::Vector3d::UnitZ()) *
                         Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()) *
                         Eigen::AngleAxisd(2 * kDeg, Eigen::Vector3d::UnitX()));
  Eigen::Vector3d p_w_b{120.0, -340.0, 0.0};
  Eigen::Quaterniond q_b_c = LevelCameraRotation(0.0);
  Eigen::Vector3d p_b_c{1.0, 0.2, 4.0};

  Eigen::Matrix3d RWc() const { return (q_w_b * q_b_c).toRotationMatrix(); }
  Eigen::Vector3d PWc() const { return p_w_b + q_w_b * p_b_c; }
};

// Jacobians against central differences in each block's tangent space (Ceres' manifolds).
TEST(SkylineCost, JacobiansMatchNumericDifferencesInTheTangentSpace) {
  const Scene s;
  const auto samples = testing::SyntheticSkyline(*s.horizon, s.camera, s.RWc(), s.PWc(), 16);
  ASSERT_GT(samples.size(), 80u);
  // Evaluate away from the truth so that residuals are not zero.
  Eigen::Quaterniond q_w_b =
      s.q_w_b * Eigen::Quaterniond(Eigen::AngleAxisd(0.003, Eigen::Vector3d(1, 2, 3).normalized()));
  Eigen::Vector3d p_w_b = s.p_w_b + Eigen::Vector3d(8, -5, 1.5);
  Eigen::Quaterniond q_b_c = s.q_b_c;
  Eigen::Vector3d p_b_c = s.p_b_c;
  auto model = std::make_shared<SkylineResidualModel>(s.horizon, s.camera, samples,
                                                      SkylineResidualOptions{});
  const SkylineCost cost(model);
  const int n = cost.num_residuals();
  std::vector<double*> params = {q_w_b.coeffs().data(), p_w_b.data(), q_b_c.coeffs().data(),
                                 p_b_c.data()};
  std::vector<std::vector<double>> jac(4);
  std::vector<double*> jac_ptr(4);
  for (int b = 0; b < 4; ++b) {
    jac[b].resize(n * cost.parameter_block_sizes()[b]);
    jac_ptr[b] = jac[b].data();
  }
  std::vector<double> r0(n);
  ASSERT_TRUE(cost.Evaluate(params.data(), r0.data(), jac_ptr.data()));
  ceres::EigenQuaternionManifold quat;
  for (int b = 0; b < 4; ++b) {
    const int size = cost.parameter_block_sizes()[b];
    const bool is_quat = size == 4;
    Eigen::MatrixXd analytic =
        Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
            jac[b].data(), n, size);
    if (is_quat) {
      Eigen::Matrix<double, 4, 3, Eigen::RowMajor> plus;
      quat.PlusJacobian(params[b], plus.data());
      analytic = analytic * plus;
    }
    const double h = is_quat ? 1e-6 : 0.05;
    for (int k = 0; k < 3; ++k) {
      std::vector<double> xp(size), xm(size);
      const Eigen::Vector3d d = Eigen::Vector3d::Unit(k) * h;
      if (is_quat) {
        quat.Plus(params[b], d.data(), xp.data());
        const Eigen::Vector3d md = -d;
        quat.Plus(params[b], md.data(), xm.data());
      } else {
        for (int i = 0; i < 3; ++i) {
          xp[i] = params[b][i] + d[i];
          xm[i] = params[b][i] - d[i];
        }
      }
      std::vector<double> rp(n), rm(n);
      std::vector<double*> pp = params, pm = params;
      pp[b] = xp.data();
      pm[b] = xm.data();
      cost.Evaluate(pp.data(), rp.data(), nullptr);
      cost.Evaluate(pm.data(), rm.data(), nullptr);
      const Eigen::VectorXd num =
          (Eigen::Map<Eigen::VectorXd>(rp.data(), n) - Eigen::Map<Eigen::VectorXd>(rm.data(), n)) /
          (2 * h);
      // The horizon's own derivative agrees with its numeric one to a few per cent on a fine
      // grid and less well on this 25 m one, where the bilinear surface's kinks hold the
      // maximum (see horizon_predictor_test); the rest of the chain is exact.
      EXPECT_LT((analytic.col(k) - num).norm(), 0.08 * num.norm() + 1e-6)
          << "block " << b << " axis " << k << "\n"
          << analytic.col(k).head(8).transpose() << "\n"
          << num.head(8).transpose();
    }
  }
}

// A cost with the camera's estimated parameter as a fifth block, evaluated at a pose 8 m east,
// 5 m south and 1.5 m above the scene's at the parameter `value`: what the three parameters'
// tests check.
struct FifthBlock {
  int traced = 0;  ///< horizon traces made by the two evaluations of the central difference
  Eigen::VectorXd analytic;  ///< the block's Jacobian
  Eigen::VectorXd numeric;   ///< its central difference by +-h
};
FifthBlock CheckFifthBlock(const Scene& s,
                           std::shared_ptr<const HorizonPredictor> horizon,
                           SkylineParameter parameter,
                           double value,
                           double h) {
  const auto samples = testing::SyntheticSkyline(*horizon, s.camera, s.RWc(), s.PWc(), 16);
  Eigen::Vector3d p_w_b = s.p_w_b + Eigen::Vector3d(8, -5, 1.5);
  Eigen::Quaterniond q_w_b = s.q_w_b;
  Eigen::Quaterniond q_b_c = s.q_b_c;
  Eigen::Vector3d p_b_c = s.p_b_c;
  auto model =
      std::make_shared<SkylineResidualModel>(horizon, s.camera, samples, SkylineResidualOptions{});
  const SkylineCost with(model, parameter);
  const SkylineCost without(
      std::make_shared<SkylineResidualModel>(horizon, s.camera, samples, SkylineResidualOptions{}));
  EXPECT_EQ(with.parameter_block_sizes(), (std::vector<int32_t>{4, 3, 4, 3, 1}));
  const int n = with.num_residuals();
  double x = value;
  std::vector<double*> params = {q_w_b.coeffs().data(), p_w_b.data(), q_b_c.coeffs().data(),
                                 p_b_c.data(), &x};
  std::vector<std::vector<double>> jac(5), jac0(4);
  std::vector<double*> ptr(5), ptr0(4);
  for (int b = 0; b < 5; ++b) {
    jac[b].resize(n * with.parameter_block_sizes()[b]);
    ptr[b] = jac[b].data();
    if (b < 4) {
      jac0[b].resize(jac[b].size());
      ptr0[b] = jac0[b].data();
    }
  }
  Eigen::VectorXd r(n), r0(n);
  EXPECT_TRUE(with.Evaluate(params.data(), r.data(), ptr.data()));
  // At the model's own value the cost is the one without the block, Jacobians and all.
  EXPECT_TRUE(without.Evaluate(params.data(), r0.data(), ptr0.data()));
  EXPECT_EQ(r, r0);
  for (int b = 0; b < 4; ++b) EXPECT_EQ(jac[b], jac0[b]) << "block " << b;
  Eigen::VectorXd rp(n), rm(n);
  double xp = x + h, xm = x - h;
  std::vector<double*> pp = params, pm = params;
  pp[4] = &xp;
  pm[4] = &xm;
  FifthBlock out;
  const long traced = model->traced_poses();
  EXPECT_TRUE(with.Evaluate(pp.data(), rp.data(), nullptr));
  EXPECT_TRUE(with.Evaluate(pm.data(), rm.data(), nullptr));
  out.traced = static_cast<int>(model->traced_poses() - traced);
  out.numeric = (rp - rm) / (2 * h);
  out.analytic = Eigen::Map<Eigen::VectorXd>(jac[4].data(), n);
  // A value that is not a number is an invalid point for the solver, not a residual.
  double bad = std::nan("");
  pp[4] = &bad;
  EXPECT_FALSE(with.Evaluate(pp.data(), rp.data(), nullptr));
  return out;
}

// With the refraction coefficient as a fifth block (the camera's estimated parameter): its
// Jacobian against central differences, the pose blocks' unchanged by it, and the horizon traced
// again when only k changes (the cache holds one pose and k).
TEST(SkylineCost, TheRefractionBlockMatchesNumericDifferences) {
  const Scene s;
  // A ring 5-8 km off: k moves the horizon by s / (2 R) per unit, ~5e-4 rad, ~0.7 px.
  const FifthBlock k = CheckFifthBlock(s, s.horizon, SkylineParameter::kRefraction,
                                       s.horizon->options().refraction_k, 0.05);
  EXPECT_EQ(k.traced, 2) << "only k changed: traced again";
  EXPECT_GT(k.numeric.norm(), 1.0);
  EXPECT_LT((k.analytic - k.numeric).norm(), 0.02 * k.numeric.norm())
      << k.analytic.head(6).transpose() << "\n"
      << k.numeric.head(6).transpose();
}

// How far a changed world moves a frame's skyline (mean |e_world - e_plain| over the samples
// both see, px) and how much of that a model of the change misses (mean |e_world - e_model|).
struct SkylineShift {
  double moved = 0.0;
  double missed = 0.0;
  int compared = 0;
};
SkylineShift CompareShift(const std::vector<double>& e_plain,
                          const std::vector<double>& e_model,
                          const std::vector<double>& e_world) {
  SkylineShift out;
  for (size_t i = 0; i < e_plain.size(); ++i) {
    if (!std::isfinite(e_model[i]) || !std::isfinite(e_world[i])) continue;
    out.moved += std::abs(e_world[i] - e_plain[i]);
    out.missed += std::abs(e_world[i] - e_model[i]);
    ++out.compared;
  }
  if (out.compared > 0) {
    out.moved /= out.compared;
    out.missed /= out.compared;
  }
  return out;
}

std::shared_ptr<const HorizonPredictor> RaisedRing(double by) {
  return std::make_shared<HorizonPredictor>(testing::RaisedMountainRing(by));
}

// With the crest offset c as the fifth block: its Jacobian against central differences; at the
// options' c the cost without the block; and the first-order model against numbers, a map whose
// land is really raised by c: the residuals of the plain map at c are those of the raised map.
TEST(SkylineCost, TheCrestOffsetPredictsARaisedMap) {
  const Scene s;
  // A ring 5-8 km off, f ~ 1370 px: a metre raises its skyline by ~0.2 px.
  const FifthBlock c = CheckFifthBlock(s, s.horizon, SkylineParameter::kCrestOffset, 0.0, 2.0);
  EXPECT_EQ(c.traced, 0) << "c needs no new trace";
  EXPECT_GT(c.numeric.norm(), 0.5);
  EXPECT_LT((c.analytic - c.numeric).norm(), 0.01 * c.numeric.norm())
      << c.analytic.head(6).transpose() << "\n"
      << c.numeric.head(6).transpose();

  // Against a map really raised by 10 m.
  const auto samples = testing::SyntheticSkyline(*s.horizon, s.camera, s.RWc(), s.PWc(), 16);
  const double by = 10.0;
  SkylineResidualOptions at_c;
  at_c.crest_offset_m = by;
  const SkylineResidualModel plain_at_c(s.horizon, s.camera, samples, at_c);
  const SkylineResidualModel plain(s.horizon, s.camera, samples, SkylineResidualOptions{});
  const SkylineResidualModel raised(RaisedRing(by), s.camera, samples, SkylineResidualOptions{});
  const Eigen::Matrix3d r_w_c = s.RWc();
  const Eigen::Vector3d p_w_c = s.PWc() + Eigen::Vector3d(8, -5, 1.5);
  const std::vector<double> e_c = plain_at_c.PixelErrors(r_w_c, p_w_c);
  const std::vector<double> e_0 = plain.PixelErrors(r_w_c, p_w_c);
  const std::vector<double> e_up = raised.PixelErrors(r_w_c, p_w_c);
  const SkylineShift shift = CompareShift(e_0, e_c, e_up);
  ASSERT_GT(shift.compared, 80);
  std::printf("raised 10 m: the skyline moves %.3f px, the model misses %.3f px\n", shift.moved,
              shift.missed);
  EXPECT_GT(shift.moved, 1.0) << "raising the land by 10 m moves the skyline by pixels";
  EXPECT_LT(shift.missed, 0.1 * shift.moved)
      << "the first-order model leaves " << shift.missed << " px of " << shift.moved;
}

// The sharpening gain g as the fifth block (skyline.dem_sharpening_sigma): on a ring with relief a
// cell or two wide, g times the map's detail (what a sharpening of gain 1 adds) predicts the
// skyline of the map really sharpened with gain g, to first order; its Jacobian against central
// differences; a map without its detail refused.
TEST(SkylineCost, TheSharpeningGainPredictsASharpenedMap) {
  const Scene s;
  geo::EnuHeightGrid rough = testing::MountainRing();
  for (int r = 0; r < rough.rows; ++r) {
    for (int c = 0; c < rough.cols; ++c) {
      const Eigen::Vector2d p = rough.NodePosition(c, r);
      double& z = rough.up_m[static_cast<size_t>(r) * rough.cols + c];
      if (z + p.squaredNorm() / (2 * 6371000.0) > 0.5) {
        z += 30.0 * std::sin(p.x() / 40.0) * std::sin(p.y() / 47.0);  // bumps ~4 cells wide
      }
    }
  }
  const double footprint_m = 0.75 * rough.spacing_m;
  geo::EnuHeightGrid detail = rough;
  geo::SharpenTerrain({1.0, footprint_m}, 6371000.0, &detail);
  for (size_t i = 0; i < detail.up_m.size(); ++i) detail.up_m[i] -= rough.up_m[i];
  geo::EnuHeightGrid sharpened = rough;
  const double gain = 0.8;
  geo::SharpenTerrain({gain, footprint_m}, 6371000.0, &sharpened);
  auto plain = std::make_shared<HorizonPredictor>(rough);
  EXPECT_THROW(SkylineCost(std::make_shared<SkylineResidualModel>(
                               plain, s.camera,
                               testing::SyntheticSkyline(*plain, s.camera, s.RWc(), s.PWc(), 16),
                               SkylineResidualOptions{}),
                           SkylineParameter::kDetailGain),
               std::invalid_argument);
  auto with_detail = std::make_shared<HorizonPredictor>(rough);
  with_detail->AttachDetail(detail);
  const auto world = std::make_shared<HorizonPredictor>(sharpened);
  const auto samples = testing::SyntheticSkyline(*plain, s.camera, s.RWc(), s.PWc(), 16);
  ASSERT_GT(samples.size(), 80u);
  const Eigen::Matrix3d r_w_c = s.RWc();
  const Eigen::Vector3d p_w_c = s.PWc() + Eigen::Vector3d(8, -5, 1.5);
  SkylineResidualOptions at_gain;
  at_gain.detail_gain = gain;
  const std::vector<double> e_0 =
      SkylineResidualModel(plain, s.camera, samples, {}).PixelErrors(r_w_c, p_w_c);
  const std::vector<double> e_g =
      SkylineResidualModel(with_detail, s.camera, samples, at_gain).PixelErrors(r_w_c, p_w_c);
  const std::vector<double> e_world =
      SkylineResidualModel(world, s.camera, samples, {}).PixelErrors(r_w_c, p_w_c);
  const SkylineShift shift = CompareShift(e_0, e_g, e_world);
  ASSERT_GT(shift.compared, 80);
  std::printf("sharpened with gain %.1f: the skyline moves %.3f px, the model misses %.3f px\n",
              gain, shift.moved, shift.missed);
  EXPECT_GT(shift.moved, 0.3) << "sharpening moves the skyline by a good part of a pixel";
  EXPECT_LT(shift.missed, 0.25 * shift.moved)
      << "the first-order model leaves " << shift.missed << " px of " << shift.moved;

  // The block's Jacobian.
  const FifthBlock g = CheckFifthBlock(s, with_detail, SkylineParameter::kDetailGain, 0.0, 0.1);
  EXPECT_EQ(g.traced, 0) << "g needs no new trace";
  EXPECT_GT(g.numeric.norm(), 0.5);
  EXPECT_LT((g.analytic - g.numeric).norm(), 0.01 * g.numeric.norm());
}

// A ring of four cameras on a body whose height is known (the water surface): from a start 30 m
// and 1 deg off and c = 0, the pose and a crest offset of 10 m are recovered together; with c
// held at 0 the map's low crests pull the position instead.
TEST(SkylineCost, ARingOfFourRecoversTheCrestOffsetWithThePose) {
  const Scene s;
  const double truth_c = 10.0;
  const auto terrain = RaisedRing(truth_c);
  const auto solve = [&](bool estimate_c, double* c, Eigen::Vector3d* p, Eigen::Quaterniond* q) {
    ceres::Problem problem;
    std::array<Eigen::Quaterniond, 4> q_b_cs;  // the problem reads its parameters from here
    std::array<Eigen::Vector3d, 4> p_b_cs;
    for (int k = 0; k < 4; ++k) {
      const Eigen::Quaterniond q_b_c = LevelCameraRotation(90.0 * k);
      q_b_cs[k] = q_b_c;
      p_b_cs[k] = s.p_b_c;
      const Eigen::Matrix3d r_w_c = (s.q_w_b * q_b_c).toRotationMatrix();
      const Eigen::Vector3d p_w_c = s.p_w_b + s.q_w_b * s.p_b_c;
      const auto samples = testing::SyntheticSkyline(*terrain, s.camera, r_w_c, p_w_c, 16);
      auto model = std::make_shared<SkylineResidualModel>(s.horizon, s.camera, samples,
                                                          SkylineResidualOptions{});
      double* q_b_c_param = q_b_cs[k].coeffs().data();
      double* p_b_c_param = p_b_cs[k].data();
      if (estimate_c) {
        problem.AddResidualBlock(new SkylineCost(model, SkylineParameter::kCrestOffset), nullptr,
                                 {q->coeffs().data(), p->data(), q_b_c_param, p_b_c_param, c});
      } else {
        problem.AddResidualBlock(new SkylineCost(model), nullptr,
                                 {q->coeffs().data(), p->data(), q_b_c_param, p_b_c_param});
      }
      problem.SetParameterBlockConstant(q_b_c_param);
      problem.SetParameterBlockConstant(p_b_c_param);
    }
    problem.SetManifold(q->coeffs().data(), new ceres::EigenQuaternionManifold);
    problem.SetManifold(p->data(), new ceres::SubsetManifold(3, {2}));  // height known
    ceres::Solver::Options options;
    options.max_num_iterations = 100;
    ceres::Solver::Summary summary;
    ceres::Solve(options, &problem, &summary);
    return summary.BriefReport();
  };
  const Eigen::Quaterniond q0 =
      s.q_w_b * Eigen::Quaterniond(Eigen::AngleAxisd(kDeg, Eigen::Vector3d(1, -1, 1).normalized()));
  const Eigen::Vector3d p0 = s.p_w_b + Eigen::Vector3d(30.0, -20.0, 0.0);
  double c = 0.0;
  Eigen::Vector3d p = p0;
  Eigen::Quaterniond q = q0;
  const std::string report = solve(true, &c, &p, &q);
  std::printf("ring of four: crest offset %.3f m (world 10), position %.3f m off\n", c,
              (p - s.p_w_b).head<2>().norm());
  EXPECT_NEAR(c, truth_c, 1.0) << report;
  EXPECT_LT((p - s.p_w_b).head<2>().norm(), 1.0) << report << "\n" << p.transpose();
  EXPECT_LT(q.angularDistance(s.q_w_b), 0.01 * kDeg) << report;
  double c_held = 0.0;
  Eigen::Vector3d p_held = p0;
  Eigen::Quaterniond q_held = q0;
  solve(false, &c_held, &p_held, &q_held);
  std::printf("ring of four, offset held at 0: position %.3f m off\n",
              (p_held - s.p_w_b).head<2>().norm());
  EXPECT_GT((p_held - s.p_w_b).head<2>().norm(), 3.0 * (p - s.p_w_b).head<2>().norm() + 1.0)
      << "held: " << p_held.transpose() << "\nestimated: " << p.transpose();
}

// Perturb the pose by 40 m, 3 m up and 2 deg in each angle, and recover it from one frame.
TEST(SkylineCost, PerturbAndRecoverTheSixDofPose) {
  const Scene s;
  const auto samples = testing::SyntheticSkyline(*s.horizon, s.camera, s.RWc(), s.PWc(), 8);
  auto model = std::make_shared<SkylineResidualModel>(s.horizon, s.camera, samples,
                                                      SkylineResidualOptions{});
  Eigen::Quaterniond q =
      s.q_w_b * Eigen::Quaterniond(Eigen::AngleAxisd(2 * kDeg * std::sqrt(3.0),
                                                     Eigen::Vector3d(1, 1, 1).normalized()));
  Eigen::Vector3d p = s.p_w_b + Eigen::Vector3d(40.0, -25.0, 3.0);
  Eigen::Quaterniond q_b_c = s.q_b_c;
  Eigen::Vector3d p_b_c = s.p_b_c;
  ceres::Problem problem;
  problem.AddResidualBlock(new SkylineCost(model), nullptr, q.coeffs().data(), p.data(),
                           q_b_c.coeffs().data(), p_b_c.data());
  problem.SetManifold(q.coeffs().data(), new ceres::EigenQuaternionManifold);
  problem.SetParameterBlockConstant(q_b_c.coeffs().data());
  problem.SetParameterBlockConstant(p_b_c.data());
  ceres::Solver::Options options;
  options.max_num_iterations = 100;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  EXPECT_LT((p - s.p_w_b).norm(), 0.5) << summary.BriefReport() << "\n" << p.transpose();
  EXPECT_LT(q.angularDistance(s.q_w_b), 0.005 * kDeg) << summary.BriefReport();
}

// A second evaluation at the same pose (a solver's linearisation after the candidate's cost, a
// window's first solve after the gate) re-uses the horizon traced for the first; any other pose
// is traced again, and the results are those of a model that never cached.
TEST(SkylineResidualModel, ReusesTheHorizonTracedAtTheSamePoseOnly) {
  const Scene s;
  const auto samples = testing::SyntheticSkyline(*s.horizon, s.camera, s.RWc(), s.PWc(), 16);
  const SkylineResidualModel model(s.horizon, s.camera, samples, SkylineResidualOptions{});
  const int n = model.size();
  const Eigen::Matrix3d r_a = s.RWc();
  const Eigen::Vector3d p_a = s.PWc() + Eigen::Vector3d(8.0, -5.0, 1.5);
  const Eigen::Matrix3d r_b = Eigen::AngleAxisd(0.01, Eigen::Vector3d::UnitZ()) * r_a;
  const Eigen::Vector3d p_b = p_a + Eigen::Vector3d(30.0, 0.0, 0.0);
  auto evaluate = [&](const SkylineResidualModel& m, const Eigen::Matrix3d& r,
                      const Eigen::Vector3d& p) {
    Eigen::VectorXd res(n);
    Eigen::Matrix<double, Eigen::Dynamic, 3> jr, jp;
    m.Evaluate(r, p, res.data(), &jr, &jp);
    Eigen::MatrixXd all(n, 7);
    all << res, jr, jp;
    return all;
  };
  std::vector<double> scratch(static_cast<size_t>(n));
  model.Evaluate(r_a, p_a, scratch.data());  // the candidate's cost
  EXPECT_EQ(model.traced_poses(), 1);
  const Eigen::MatrixXd at_a = evaluate(model, r_a, p_a);  // linearised there: re-used
  EXPECT_EQ(model.traced_poses(), 1);
  const Eigen::MatrixXd at_b = evaluate(model, r_b, p_b);  // turned and moved: traced
  EXPECT_EQ(model.traced_poses(), 2);
  evaluate(model, r_b, p_a);  // turned only: traced (the rays' azimuths change)
  EXPECT_EQ(model.traced_poses(), 3);
  const Eigen::MatrixXd again_a = evaluate(model, r_a, p_a);
  EXPECT_EQ(model.traced_poses(), 4);

  const SkylineResidualModel fresh_a(s.horizon, s.camera, samples, SkylineResidualOptions{});
  const SkylineResidualModel fresh_b(s.horizon, s.camera, samples, SkylineResidualOptions{});
  const Eigen::MatrixXd want_a = evaluate(fresh_a, r_a, p_a);
  EXPECT_GT(want_a.col(0).norm(), 1.0);  // away from the truth: the comparison means something
  EXPECT_EQ(at_a, want_a);
  EXPECT_EQ(again_a, want_a);
  EXPECT_EQ(at_b, evaluate(fresh_b, r_b, p_b));
  EXPECT_NE(at_a, at_b);
}

// skyline.threads: a frame's samples traced on several threads give the residuals and Jacobians
// of one thread to the last bit, with the map's term, a crest offset and both derivatives in
// them, and inside another ParallelFor (the batch's blocks) the frame stays on its caller's
// thread.
TEST(SkylineResidualModel, TheSameOnAnyNumberOfThreads) {
  const Scene s;
  const auto samples = testing::SyntheticSkyline(*s.horizon, s.camera, s.RWc(), s.PWc(), 8);
  ASSERT_GT(samples.size(), 160u);
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.004, Eigen::Vector3d::UnitZ()) * s.RWc();
  const Eigen::Vector3d p = s.PWc() + Eigen::Vector3d(8.0, -5.0, 1.5);
  auto evaluate = [&](int threads) {
    SkylineResidualOptions options;
    options.threads = threads;
    SkylineResidualModel model(s.horizon, s.camera, samples, options);
    model.AddMapError(r, p, 4.0, 90.0);
    const int n = model.size();
    Eigen::VectorXd res(n), jk(n), jc(n);
    Eigen::Matrix<double, Eigen::Dynamic, 3> jr, jp;
    EXPECT_GT(model.Evaluate(r, p, {0.13, 3.0, 0.0}, res.data(), &jr, &jp, {&jk, &jc}), n / 2);
    Eigen::MatrixXd all(n, 9);
    all << res, jr, jp, jk, jc;
    return all;
  };
  const Eigen::MatrixXd one = evaluate(1);
  EXPECT_GT(one.col(0).norm(), 1.0);  // away from the truth
  EXPECT_EQ(evaluate(2), one);
  EXPECT_EQ(evaluate(3), one);
  // Nested: two frames on two threads, each asking for four.
  std::vector<Eigen::MatrixXd> nested(2);
  ParallelFor(2, 2, [&](size_t i) {
    nested[i] = evaluate(4);
    return true;
  });
  EXPECT_EQ(nested[0], one);
  EXPECT_EQ(nested[1], one);
}

// The map's own height error (AddMapError) against numbers: a hill 4 km off on the left of the
// view, the open sea on the right, on a round Earth. Raising the land by 1 m moves each land
// sample's predicted horizon by what AddMapError adds per metre of DEM error; water samples keep
// their weight. The residual's scale is sigma_px over the combined sigma, so the map term is read
// back from residuals before and after.
TEST(SkylineResidualModel, TheMapsErrorWeighsASampleByItsHorizonsRange) {
  constexpr double kR = 6371000.0;
  const auto world = [](double lift) {
    return std::make_shared<const HorizonPredictor>(
        testing::Grid(801, 90.0, [lift](double x, double y) {
          const double hill =
              300.0 * std::exp(-0.5 * (std::pow(x + 1500.0, 2) + std::pow(y - 4000.0, 2)) /
                               (600.0 * 600.0));
          return (hill > 0.5 ? hill + lift : 0.0) - (x * x + y * y) / (2 * kR);
        }));
  };
  const auto horizon = world(0.0), raised = world(1.0);
  const CameraModel camera(PinholeFromFov("camera", 1920, 1080, 70.0));
  // Looking north, level, 10 m up (optical frame: z forward, x right, y down).
  const Eigen::Matrix3d r_w_c = (Eigen::Matrix3d() << 1, 0, 0, 0, 0, 1, 0, -1, 0).finished();
  const Eigen::Vector3d p_w_c(0.0, 0.0, 10.0);
  const auto samples = testing::SyntheticSkyline(*horizon, camera, r_w_c, p_w_c, 16);
  SkylineResidualOptions o;
  o.correlation_px = 0.0;  // residual i is sample i's alone
  o.huber_sigmas = 0.0;
  SkylineResidualModel model(horizon, camera, samples, o);
  const SkylineResidualModel on_raised(raised, camera, samples, o);
  const int n = model.size();
  // Away from the truth (pitched 0.2 deg), so that every residual is far from 0.
  const Eigen::Matrix3d pitched = Eigen::AngleAxisd(0.2 * kDeg, Eigen::Vector3d::UnitX()) * r_w_c;
  std::vector<double> before(n), after(n);
  model.Evaluate(pitched, p_w_c, before.data());
  const std::vector<double> moved = on_raised.PixelErrors(pitched, p_w_c);
  const std::vector<double> base = model.PixelErrors(pitched, p_w_c);
  constexpr double kSigmaM = 4.0;
  const double mean = model.AddMapError(pitched, p_w_c, kSigmaM);
  EXPECT_GT(mean, 1.0);
  model.Evaluate(pitched, p_w_c, after.data());
  int land = 0, water = 0, switched = 0;
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    ASSERT_GT(std::abs(before[i]), 1.0) << i;
    // The lifted hill's foot may rise above the sea horizon beyond it: another point makes the
    // horizon there, and the difference is not the map error's derivative.
    const Eigen::Vector3d r = pitched * model.rays_c()[i];
    const double a = std::atan2(r.x(), r.y());
    if (std::abs(horizon->Trace(p_w_c, a).distance_m - raised->Trace(p_w_c, a).distance_m) >
        500.0) {
      ++switched;
      continue;
    }
    const double term = std::sqrt(std::pow(before[i] / after[i], 2) - 1.0);  // px, sigma_px 1
    const double per_metre = std::abs(moved[i] - base[i]);  // px per metre of DEM error
    if (per_metre < 1e-9) {
      EXPECT_EQ(after[i], before[i]) << "water sample " << i;
      ++water;
    } else {
      EXPECT_NEAR(term, kSigmaM * per_metre, 0.03 * kSigmaM * per_metre) << "land sample " << i;
      sum += term;
      ++land;
    }
  }
  ASSERT_GT(land, 10);
  ASSERT_GT(water, 10);
  EXPECT_LE(switched, 2);
  // Replaced, not added: 0 gives the model back as it was.
  EXPECT_EQ(model.AddMapError(r_w_c, p_w_c, 0.0), 0.0);
  model.Evaluate(pitched, p_w_c, after.data());
  EXPECT_EQ(after, before);
  EXPECT_THROW(model.AddMapError(r_w_c, p_w_c, -1.0), std::invalid_argument);
  EXPECT_THROW(model.AddMapError(r_w_c, p_w_c, std::nan("")), std::invalid_argument);
  // The frame weight scales every residual, as at construction.
  model.SetFrameWeight(0.25);
  SkylineResidualOptions quarter = o;
  quarter.frame_weight = 0.25;
  const SkylineResidualModel built(horizon, camera, samples, quarter);
  std::vector<double> set(n), want(n);
  model.Evaluate(pitched, p_w_c, set.data());
  built.Evaluate(pitched, p_w_c, want.data());
  EXPECT_EQ(set, want);
  EXPECT_THROW(model.SetFrameWeight(0.0), std::invalid_argument);
}

// With the map's error: samples' errors are the extraction's (AR(1) along the skyline) plus the
// map's, m_i times a field on the ground with exponential correlation, drawn at the samples'
// horizon points. The whitened residuals have unit variance with the map term and the field's
// correlation length, and not without (the map's error counted as noise, or as white).
TEST(SkylineResidualModel, WhitensTheMapsErrorSharedByNeighbouringHorizons) {
  constexpr double kR = 6371000.0;
  const auto horizon =
      std::make_shared<const HorizonPredictor>(testing::Grid(801, 90.0, [](double x, double y) {
        const double hill =
            300.0 *
            std::exp(-0.5 * (std::pow(x + 1500.0, 2) + std::pow(y - 4000.0, 2)) / (600.0 * 600.0));
        return (hill > 0.5 ? hill : 0.0) - (x * x + y * y) / (2 * kR);
      }));
  const CameraModel camera(PinholeFromFov("camera", 1920, 1080, 70.0));
  const Eigen::Matrix3d r_w_c = (Eigen::Matrix3d() << 1, 0, 0, 0, 0, 1, 0, -1, 0).finished();
  const Eigen::Vector3d p_w_c(0.0, 0.0, 10.0);
  const auto truth = testing::SyntheticSkyline(*horizon, camera, r_w_c, p_w_c, 8);
  SkylineResidualOptions o;
  o.sigma_px = 0.5;
  o.correlation_px = 20.0;
  o.huber_sigmas = 0.0;
  constexpr double kSigmaM = 4.0, kLengthM = 300.0;
  SkylineResidualModel probe(horizon, camera, truth, o);
  ASSERT_EQ(probe.size(), static_cast<int>(truth.size()));
  probe.AddMapError(r_w_c, p_w_c, kSigmaM, kLengthM);
  // Each sample's map term and ground point, as the model takes them.
  const int n = probe.size();
  Eigen::VectorXd m = Eigen::VectorXd::Zero(n);
  std::vector<Eigen::Vector2d> ground(static_cast<size_t>(n), Eigen::Vector2d::Zero());
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d r = r_w_c * probe.rays_c()[i];
    const HorizonSample h = horizon->Trace(p_w_c, std::atan2(r.x(), r.y()));
    ground[i] = h.point_w.head<2>();
    if (h.valid && !h.truncated && !HorizonOnWater(*horizon, h.point_w)) {
      const double c = std::cos(h.elevation_rad);
      m[i] = 1371.0 * kSigmaM * c * c / h.distance_m;  // ~ px per rad near the axis
    }
  }
  ASSERT_GT((m.array() > 0).count(), 30);
  Eigen::MatrixXd c_map(n, n);
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      c_map(i, j) = m[i] * m[j] * std::exp(-(ground[i] - ground[j]).norm() / kLengthM);
    }
  }
  const Eigen::MatrixXd l_map = (c_map + 1e-9 * Eigen::MatrixXd::Identity(n, n)).llt().matrixL();
  std::mt19937 rng(11);
  std::normal_distribution<double> normal;
  const double rho_px = std::exp(-8.0 / o.correlation_px);
  // Per model: the sum of squares and of products of neighbours of the whitened residuals.
  struct Moments {
    double square = 0, lag1 = 0;
  } with, white, without;
  int count = 0;
  for (int trial = 0; trial < 60; ++trial) {
    auto noisy = truth;
    Eigen::VectorXd z(n);
    for (int i = 0; i < n; ++i) z[i] = normal(rng);
    const Eigen::VectorXd map_error = l_map * z;
    double e = o.sigma_px * normal(rng);
    for (int i = 0; i < n; ++i) {
      if (i > 0) e = rho_px * e + o.sigma_px * std::sqrt(1 - rho_px * rho_px) * normal(rng);
      noisy[static_cast<size_t>(i)].pixel.y() += e + map_error[i];
    }
    SkylineResidualModel model(horizon, camera, noisy, o);
    const auto accumulate = [&](double dem_sigma, double length, Moments* out) {
      model.AddMapError(r_w_c, p_w_c, dem_sigma, length);
      std::vector<double> r(static_cast<size_t>(n));
      model.Evaluate(r_w_c, p_w_c, r.data());
      for (int i = 0; i < n; ++i) {
        out->square += r[i] * r[i];
        if (i > 0) out->lag1 += r[i] * r[i - 1];
      }
    };
    accumulate(kSigmaM, kLengthM, &with);
    accumulate(kSigmaM, 0.0, &white);
    accumulate(0.0, 0.0, &without);
    count += n;
  }
  EXPECT_NEAR(with.square / count, 1.0, 0.1);
  EXPECT_LT(std::abs(with.lag1 / with.square), 0.1);
  // The map's error taken for the extraction's: far more than unit variance.
  EXPECT_GT(without.square / count, 2.0);
  // Counted as independent from sample to sample: neighbours' whitened residuals still correlated.
  EXPECT_GT(white.lag1 / white.square, 0.2);
}

// The AR(1) whitening turns correlated column errors into white unit-variance residuals.
TEST(SkylineResidualModel, WhitensCorrelatedColumnErrors) {
  const Scene s;
  const auto truth = testing::SyntheticSkyline(*s.horizon, s.camera, s.RWc(), s.PWc(), 4);
  SkylineResidualOptions o;
  o.sigma_px = 0.8;
  o.correlation_px = 24.0;
  o.huber_sigmas = 0.0;
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  const double rho = std::exp(-4.0 / o.correlation_px);
  double sum2 = 0, lag1 = 0;
  int count = 0;
  for (int trial = 0; trial < 40; ++trial) {
    auto noisy = truth;
    double e = o.sigma_px * normal(rng);
    for (size_t i = 0; i < noisy.size(); ++i) {
      if (i > 0) e = rho * e + o.sigma_px * std::sqrt(1 - rho * rho) * normal(rng);
      noisy[i].pixel.y() += e;
    }
    const SkylineResidualModel model(s.horizon, s.camera, noisy, o);
    std::vector<double> r(model.size());
    model.Evaluate(s.RWc(), s.PWc(), r.data());
    for (int i = 1; i < model.size(); ++i) {
      sum2 += r[i] * r[i];
      lag1 += r[i] * r[i - 1];
      ++count;
    }
  }
  // A row error at a fixed column is (nearly) an elevation error at a fixed azimuth for a camera
  // rolled by 2 deg: unit variance to a few per cent.
  EXPECT_NEAR(sum2 / count, 1.0, 0.06);
  EXPECT_NEAR(lag1 / count, 0.0, 0.05);
}

}  // namespace
}  // namespace skerry::skyline
