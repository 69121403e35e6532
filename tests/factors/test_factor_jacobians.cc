// Every factor's Jacobians against numeric differences in the tangent space (ceres::GradientChecker
// with EigenQuaternionManifold on the quaternion blocks), at random non-trivial states; and the
// skerry tangent convention of LinearizeResidual (left, full-angle, world-frame rotation vector).

#include <ceres/gradient_checker.h>
#include <ceres/loss_function.h>
#include <ceres/manifold.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <vector>

#include "factors/test_utils.h"
#include "skerry/factors/bias_random_walk_factor.h"
#include "skerry/factors/factor_linearization.h"
#include "skerry/factors/gnss_drift_factor.h"
#include "skerry/factors/gnss_drift_step_factor.h"
#include "skerry/factors/gnss_heading_factor.h"
#include "skerry/factors/gnss_position_factor.h"
#include "skerry/factors/imu_factor.h"
#include "skerry/factors/linear_prior_factor.h"
#include "skerry/factors/pose_fix_factor.h"
#include "skerry/factors/state_prior_factor.h"
#include "skerry/factors/water_surface_factor.h"

namespace skerry {
namespace {

constexpr double kPi = 3.14159265358979323846;

using test::RandomQuaternion;
using test::RandomVector;

// Ambient parameter blocks of one test point; pointers stay valid while the object lives.
struct Blocks {
  std::vector<Eigen::VectorXd> values;
  std::vector<const double*> ptrs() const {
    std::vector<const double*> p;
    for (const Eigen::VectorXd& v : values) p.push_back(v.data());
    return p;
  }
  void Add(const Eigen::Quaterniond& q) { values.push_back(q.coeffs()); }
  void Add(const Eigen::Vector3d& v) { values.push_back(v); }
};

// Runs ceres::GradientChecker (EigenQuaternionManifold on every size-4 block) and compares the
// tangent ("local") Jacobians with its numeric ones. The checker's own pass/fail is per entry and
// purely relative, so structurally-zero entries (1e-16 vs 1e-15 round-off) would fail it; compare
// instead with a tolerance relative to the block's largest entry.
void CheckGradients(const ceres::CostFunction& cost, const Blocks& blocks, double tol = 1e-7) {
  const ceres::EigenQuaternionManifold quaternion_manifold;
  std::vector<const ceres::Manifold*> manifolds;
  for (int size : cost.parameter_block_sizes()) {
    manifolds.push_back(size == 4 ? &quaternion_manifold : nullptr);
  }
  ASSERT_EQ(blocks.values.size(), manifolds.size());
  ceres::NumericDiffOptions options;
  // The checker differentiates with Ridders' method; its default first step (1e-2 |x|) is large
  // enough on quaternion components to straddle the Log branch cut of a rotation residual near pi
  // and to stop the extrapolation early (errors up to 1e-3 relative observed on a smooth heading
  // residual). 1e-3 gives converged derivatives.
  options.ridders_relative_initial_step_size = 1e-3;
  const ceres::GradientChecker checker(&cost, &manifolds, options);
  ceres::GradientChecker::ProbeResults results;
  const std::vector<const double*> ptrs = blocks.ptrs();
  checker.Probe(ptrs.data(), tol, &results);
  ASSERT_TRUE(results.return_value);
  ASSERT_EQ(results.local_jacobians.size(), blocks.values.size());
  double total = 0.0;
  for (size_t k = 0; k < results.local_jacobians.size(); ++k) {
    const ceres::Matrix& J = results.local_jacobians[k];
    const ceres::Matrix& J_num = results.local_numeric_jacobians[k];
    const double scale = std::max(1.0, J_num.cwiseAbs().maxCoeff());
    EXPECT_LE((J - J_num).cwiseAbs().maxCoeff(), tol * scale) << "block " << k << "\nanalytic\n"
                                                              << J << "\nnumeric\n"
                                                              << J_num;
    total += J.norm();
  }
  // Guard against a vacuous pass: the Jacobian must not be all zero.
  EXPECT_GT(total, 0.0);
}

class FactorJacobianTest : public ::testing::Test {
 protected:
  std::mt19937 rng_{7};
};

// An IMU interval with Earth terms exaggerated so that their Jacobians are not lost in the
// tolerance: a rate of 3 deg/s and a gravity gradient of 1e-3 1/s^2 (the real ones are 7e-5 rad/s
// and 3e-6), the IMU rotated and 1 m off the body origin.
// `calibrated`: the factor with the gyro's sensor errors as a ninth block.
struct ImuInterval {
  test::AnalyticTrajectory traj;
  ImuConfig imu = test::RotatedOffsetImu();
  Eigen::Vector3d bg_lin{0.002, -0.001, 0.003}, ba_lin{0.04, -0.02, 0.06};
  bool calibrated = false;
  std::shared_ptr<ImuPreintegration> pim;
  Eigen::Vector3d gyro_start = traj.gyro(0.3) + bg_lin, gyro_end = traj.gyro(0.8) + bg_lin;
  ImuEarthTerms earth;

  explicit ImuInterval(bool calibrated_factor = false) : calibrated(calibrated_factor) {
    pim = std::make_shared<ImuPreintegration>(imu.noise, bg_lin, ba_lin, calibrated);
    for (const test::ImuStep& s : test::IdealImuSteps(traj, 0.3, 0.8, 200.0, bg_lin, ba_lin)) {
      pim->Integrate(s.dt, s.gyro, s.accel);
    }
    earth.omega_ie_w = Eigen::Vector3d(0.01, 0.03, 0.05);
    earth.gravity.p_ref_w = Eigen::Vector3d(1.0, -2.0, 0.5);
    earth.gravity.g_ref_w = Eigen::Vector3d(0.02, -0.03, -9.8);
    Eigen::Matrix3d G;
    G << -1.0, 0.2, 0.1, 0.2, -1.2, -0.3, 0.1, -0.3, 2.2;
    earth.gravity.dg_dp = 1e-3 * G;
  }
  std::unique_ptr<ceres::CostFunction> Analytic() const {
    return calibrated ? ImuFactor::CreateCalibrated(*pim, imu, gyro_start, gyro_end, earth)
                      : ImuFactor::Create(*pim, imu, gyro_start, gyro_end, earth);
  }
  std::unique_ptr<ceres::CostFunction> AutoDiff() const {
    return calibrated ? ImuFactor::CreateCalibratedAutoDiff(*pim, imu, gyro_start, gyro_end, earth)
                      : ImuFactor::CreateAutoDiff(*pim, imu, gyro_start, gyro_end, earth);
  }
  // Random states, with biases away from the linearisation point (exercises the correction).
  Blocks Random(std::mt19937* rng) const {
    Blocks b;
    b.Add(RandomQuaternion(rng));
    b.Add(RandomVector(rng, 5.0));
    b.Add(RandomVector(rng, 2.0));
    b.Add(Eigen::Vector3d(bg_lin + RandomVector(rng, 0.01)));
    b.Add(Eigen::Vector3d(ba_lin + RandomVector(rng, 0.1)));
    b.Add(RandomQuaternion(rng));
    b.Add(RandomVector(rng, 5.0));
    b.Add(RandomVector(rng, 2.0));
    if (calibrated) {  // sensor errors of a few percent: far beyond a real gyro's, to be seen
      Eigen::VectorXd e(9);
      for (int k = 0; k < 3; ++k) e.segment<3>(3 * k) = RandomVector(rng, 0.03);
      b.values.push_back(e);
    }
    return b;
  }
  // Near the truth, where the rotation residual is small (small-angle branch of Log).
  Blocks NearTruth() const {
    const NavState si = traj.BodyState(0.3, imu, bg_lin, ba_lin);
    const NavState sj = traj.BodyState(0.8, imu, bg_lin, ba_lin);
    Blocks b;
    for (const NavState* s : {&si, &sj}) {
      b.Add(s->q_w_b);
      b.Add(s->p_w_b);
      b.Add(s->v_w);
      if (s == &si) {
        b.Add(s->bg);
        b.Add(s->ba);
      }
    }
    if (calibrated) b.values.push_back(Eigen::VectorXd::Zero(9));
    return b;
  }
};

// Both cost functions of the factor: the analytic Jacobians and the autodiff reference.
TEST_F(FactorJacobianTest, ImuFactor) {
  for (const bool calibrated : {false, true}) {
    const ImuInterval interval(calibrated);
    for (const bool analytic : {true, false}) {
      SCOPED_TRACE(std::string(analytic ? "analytic" : "autodiff") +
                   (calibrated ? ", calibrated" : ""));
      const std::unique_ptr<ceres::CostFunction> cost =
          analytic ? interval.Analytic() : interval.AutoDiff();
      EXPECT_EQ(cost->parameter_block_sizes().size(), calibrated ? 9u : 8u);
      for (int trial = 0; trial < 5; ++trial) CheckGradients(*cost, interval.Random(&rng_));
      CheckGradients(*cost, interval.NearTruth());
    }
  }
}

// A calibrated factor at zero sensor errors is the plain factor: the same residual and Jacobians
// to the last bit; with errors, its residual is the plain factor's on samples corrected for them.
TEST_F(FactorJacobianTest, CalibratedImuFactorAtZeroErrorsIsThePlainOne) {
  const ImuInterval plain(false), calibrated(true);
  const std::unique_ptr<ceres::CostFunction> a = plain.Analytic(), b = calibrated.Analytic();
  for (int trial = 0; trial < 5; ++trial) {
    Blocks x = calibrated.Random(&rng_);
    x.values.back().setZero();
    const std::vector<const double*> px = x.ptrs();
    std::vector<Eigen::Matrix<double, 9, Eigen::Dynamic, Eigen::RowMajor>> Ja, Jb;
    std::vector<double*> pa, pb;
    for (int32_t size : b->parameter_block_sizes()) {
      Jb.emplace_back(9, size);
      pb.push_back(Jb.back().data());
    }
    for (int32_t size : a->parameter_block_sizes()) {
      Ja.emplace_back(9, size);
      pa.push_back(Ja.back().data());
    }
    Eigen::Matrix<double, 9, 1> ra, rb;
    ASSERT_TRUE(a->Evaluate(px.data(), ra.data(), pa.data()));
    ASSERT_TRUE(b->Evaluate(px.data(), rb.data(), pb.data()));
    EXPECT_EQ(ra, rb);
    for (size_t k = 0; k < Ja.size(); ++k) EXPECT_EQ(Ja[k], Jb[k]) << "block " << k;
    EXPECT_GT(Jb.back().norm(), 0.0);
  }
}

// The analytic Jacobians against the autodiff ones, far tighter than against numeric
// differences: the same residual to round-off, the same tangent Jacobians (ambient times the
// EigenQuaternionManifold's PlusJacobian) to 1e-10 of the block's largest entry, at random
// states and near the truth, and with some blocks' Jacobians not requested (as Ceres asks for
// constant blocks).
// PredictBodyState with the gyro's sensor errors puts state j where the calibrated factor's
// residual vanishes (the window predicts its new keyframes so; to the prediction's 4e-5 sigmas with
// this fixture's exaggerated Earth terms); without them it misses by sigmas.
TEST_F(FactorJacobianTest, PredictionWithTheGyroCalibrationZeroesTheCalibratedResidual) {
  const ImuInterval interval(true);
  const std::unique_ptr<ceres::CostFunction> cost = interval.Analytic();
  Blocks x = interval.NearTruth();
  Eigen::VectorXd e(9);
  for (int k = 0; k < 3; ++k) e.segment<3>(3 * k) = RandomVector(&rng_, 0.003);
  x.values.back() = e;
  const Eigen::Quaterniond q_i(x.values[0].data());
  const Eigen::Vector3d p_i = x.values[1], v_i = x.values[2], bg = x.values[3], ba = x.values[4];
  for (const bool with_e : {true, false}) {
    Eigen::Quaterniond q_j;
    Eigen::Vector3d p_j, v_j;
    PredictBodyState(*interval.pim, interval.imu, interval.earth, interval.gyro_start,
                     interval.gyro_end, q_i, p_i, v_i, bg, ba, &q_j, &p_j, &v_j,
                     with_e ? e.data() : nullptr);
    Blocks y = x;
    y.values[5] = q_j.coeffs();
    y.values[6] = p_j;
    y.values[7] = v_j;
    Eigen::Matrix<double, 9, 1> r;
    const std::vector<const double*> py = y.ptrs();
    ASSERT_TRUE(cost->Evaluate(py.data(), r.data(), nullptr));
    if (with_e) {
      EXPECT_LT(r.norm(), 1e-4) << r.transpose();  // the exaggerated Earth terms: ~4e-5
    } else {
      EXPECT_GT(r.norm(), 1.0) << r.transpose();
    }
  }
}

void CompareImuJacobians(const ImuInterval& interval, std::mt19937* rng);

TEST_F(FactorJacobianTest, ImuFactorAnalyticMatchesAutoDiff) {
  for (const bool calibrated : {false, true}) {
    SCOPED_TRACE(calibrated ? "calibrated" : "plain");
    CompareImuJacobians(ImuInterval(calibrated), &rng_);
  }
}

void CompareImuJacobians(const ImuInterval& interval, std::mt19937* rng) {
  const std::unique_ptr<ceres::CostFunction> analytic = interval.Analytic();
  const std::unique_ptr<ceres::CostFunction> autodiff = interval.AutoDiff();
  const std::vector<int32_t>& sizes = analytic->parameter_block_sizes();
  ASSERT_EQ(sizes, autodiff->parameter_block_sizes());
  ASSERT_EQ(analytic->num_residuals(), 9);
  const ceres::EigenQuaternionManifold manifold;
  for (int trial = 0; trial < 21; ++trial) {
    const Blocks b = trial < 20 ? interval.Random(rng) : interval.NearTruth();
    const std::vector<const double*> x = b.ptrs();
    std::vector<Eigen::Matrix<double, 9, Eigen::Dynamic, Eigen::RowMajor>> J_an, J_ad;
    std::vector<double*> p_an, p_ad;
    for (int32_t size : sizes) {
      J_an.emplace_back(9, size);
      J_ad.emplace_back(9, size);
    }
    for (size_t k = 0; k < sizes.size(); ++k) {
      // Every third trial leaves blocks 1 and 4 (p_i, ba) out, as for constant blocks.
      const bool skip = trial % 3 == 2 && (k == 1 || k == 4);
      p_an.push_back(skip ? nullptr : J_an[k].data());
      p_ad.push_back(J_ad[k].data());
      if (skip) J_an[k].setConstant(-7.0);  // must stay untouched
    }
    Eigen::Matrix<double, 9, 1> r_an, r_ad, r_plain;
    ASSERT_TRUE(analytic->Evaluate(x.data(), r_an.data(), p_an.data()));
    ASSERT_TRUE(autodiff->Evaluate(x.data(), r_ad.data(), p_ad.data()));
    ASSERT_TRUE(analytic->Evaluate(x.data(), r_plain.data(), nullptr));
    EXPECT_LT((r_an - r_ad).norm(), 1e-12 * (1.0 + r_ad.norm())) << "trial " << trial;
    EXPECT_EQ(r_an, r_plain) << "trial " << trial;
    for (size_t k = 0; k < sizes.size(); ++k) {
      if (p_an[k] == nullptr) {
        EXPECT_TRUE((J_an[k].array() == -7.0).all()) << "block " << k << " written";
        continue;
      }
      Eigen::MatrixXd T_an = J_an[k], T_ad = J_ad[k];
      if (sizes[k] == 4) {
        Eigen::Matrix<double, 4, 3, Eigen::RowMajor> P;
        ASSERT_TRUE(manifold.PlusJacobian(x[k], P.data()));
        T_an = J_an[k] * P;
        T_ad = J_ad[k] * P;
        // No component along q: the residual does not see the quaternion's norm.
        const Eigen::Map<const Eigen::Vector4d> q(x[k]);
        EXPECT_LT((J_an[k] * q).norm(), 1e-12 * J_an[k].norm()) << "block " << k;
      }
      const double scale = std::max(1.0, T_ad.cwiseAbs().maxCoeff());
      EXPECT_LT((T_an - T_ad).cwiseAbs().maxCoeff(), 1e-10 * scale)
          << "trial " << trial << " block " << k << "\nanalytic\n"
          << T_an << "\nautodiff\n"
          << T_ad;
    }
  }
}

TEST_F(FactorJacobianTest, BiasRandomWalkFactor) {
  ImuNoise noise;
  const BiasRandomWalkFactor cost(noise, 0.37);
  Blocks b;
  for (int k = 0; k < 4; ++k) b.Add(RandomVector(&rng_, 0.1));
  CheckGradients(cost, b);
  // Values: r = (b_j - b_i) / (sigma_rw sqrt(dt)).
  Eigen::Matrix<double, 6, 1> r;
  const std::vector<const double*> p = b.ptrs();
  ASSERT_TRUE(cost.Evaluate(p.data(), r.data(), nullptr));
  const double sg = noise.gyro_bias_random_walk_rad_s2_sqrt_hz * std::sqrt(0.37);
  const double sa = noise.accel_bias_random_walk_m_s3_sqrt_hz * std::sqrt(0.37);
  EXPECT_LT((r.head<3>() - (b.values[2] - b.values[0]) / sg).norm(), 1e-9);
  EXPECT_LT((r.tail<3>() - (b.values[3] - b.values[1]) / sa).norm(), 1e-9);
}

TEST_F(FactorJacobianTest, GnssPositionFactor) {
  const Eigen::Vector3d lever(1.2, -0.4, 2.5), sigma(0.5, 0.7, 1.5);
  for (double dt : {0.0, 0.08, -0.05}) {
    const std::unique_ptr<ceres::CostFunction> cost =
        GnssPositionFactor::Create(RandomVector(&rng_, 10.0), sigma, lever, dt);
    Blocks b;
    b.Add(RandomQuaternion(&rng_));
    b.Add(RandomVector(&rng_, 10.0));
    b.Add(RandomVector(&rng_, 3.0));
    b.Add(RandomVector(&rng_, 0.3));  // GNSS bias
    CheckGradients(*cost, b);
  }
}

// GTSAM GPSFactorArm's closed form, in skerry's left (world-frame) rotation tangent:
// d r / d theta = -sqrt_info [R l]x, d r / d p = sqrt_info, d r / d v = sqrt_info dt,
// d r / d gb = sqrt_info.
TEST_F(FactorJacobianTest, GnssPositionFactorClosedFormTangentJacobian) {
  const Eigen::Vector3d lever(1.2, -0.4, 2.5), sigma(0.5, 0.7, 1.5), z(3.0, -2.0, 1.0);
  const double dt = 0.08;
  // Sigmas along the local level at the fix, 4 mrad from w's axes.
  const Eigen::Matrix3d R_n_w = ExpSO3(Eigen::Vector3d(0.003, -0.002, 0.002));
  const std::unique_ptr<ceres::CostFunction> cost =
      GnssPositionFactor::Create(z, sigma, lever, dt, R_n_w);
  const Eigen::Quaterniond q = RandomQuaternion(&rng_);
  const Eigen::Vector3d p = RandomVector(&rng_, 10.0), v = RandomVector(&rng_, 3.0);
  const Eigen::Vector3d gb = RandomVector(&rng_, 0.3);
  Blocks b;
  b.Add(q);
  b.Add(p);
  b.Add(v);
  b.Add(gb);
  LinearizedResidual lin;
  ASSERT_TRUE(LinearizeResidual(*cost, nullptr, b.ptrs(), b.ptrs(), &lin));
  const Eigen::Matrix3d S = sigma.cwiseInverse().asDiagonal() * R_n_w;
  EXPECT_LT((lin.residual - S * (p + v * dt + q * lever + gb - z)).norm(), 1e-12);
  EXPECT_LT((lin.jacobians[0] - (-S * Hat<double>(q * lever))).norm(), 1e-12);
  EXPECT_LT((lin.jacobians[1] - S).norm(), 1e-12);
  EXPECT_LT((lin.jacobians[2] - dt * S).norm(), 1e-12);
  EXPECT_LT((lin.jacobians[3] - S).norm(), 1e-12);
}

// Gauss-Markov drift transition: analytic Jacobians vs numeric, and the closed-form values
// r = (b_j - phi b_i) / (sigma sqrt(1 - phi^2)), phi = exp(-dt / tau).
TEST_F(FactorJacobianTest, GnssDriftFactor) {
  GnssDriftParams params;
  params.sigma_horizontal_m = 0.15;
  params.sigma_vertical_m = 0.3;
  params.tau_s = 300.0;
  for (double dt : {0.1, 2.0, 500.0}) {
    const GnssDriftFactor cost(params, dt);
    Blocks b;
    b.Add(RandomVector(&rng_, 0.3));
    b.Add(RandomVector(&rng_, 0.3));
    CheckGradients(cost, b);
    const double phi = std::exp(-dt / params.tau_s);
    EXPECT_NEAR(cost.phi(), phi, 1e-15);
    const Eigen::Vector3d sigma_w = Eigen::Vector3d(0.15, 0.15, 0.3) * std::sqrt(1.0 - phi * phi);
    Eigen::Vector3d r;
    const std::vector<const double*> p = b.ptrs();
    ASSERT_TRUE(cost.Evaluate(p.data(), r.data(), nullptr));
    const Eigen::Vector3d expected = (b.values[1] - phi * b.values[0]).cwiseQuotient(sigma_w);
    EXPECT_LT((r - expected).norm(), 1e-9 * expected.norm()) << dt;
  }
}

TEST_F(FactorJacobianTest, GnssDriftPriorFactor) {
  const GnssDriftParams params;  // defaults: 0.15 / 0.3 m
  const GnssDriftPriorFactor cost(params);
  Blocks b;
  b.Add(RandomVector(&rng_, 0.3));
  CheckGradients(cost, b);
  Eigen::Vector3d r;
  const std::vector<const double*> p = b.ptrs();
  ASSERT_TRUE(cost.Evaluate(p.data(), r.data(), nullptr));
  EXPECT_LT((r - b.values[0].cwiseQuotient(Eigen::Vector3d(0.15, 0.15, 0.3))).norm(), 1e-12);
}

// Drift transition with a step: analytic Jacobians vs numeric; the residual whitens the
// transition's noise and the step's covariance together, L^T (Q_w + C_s) L = I, and is zero
// where b_j = phi b_i + s; with C_s = 0 it is GnssDriftFactor's.
TEST_F(FactorJacobianTest, GnssDriftStepFactor) {
  GnssDriftParams params;
  params.sigma_horizontal_m = 2.0;
  params.sigma_vertical_m = 3.0;
  params.tau_s = 300.0;
  const Eigen::Vector3d step(14.5, -0.4, 0.2);
  Eigen::Matrix3d A = Eigen::Matrix3d::Random();
  const Eigen::Matrix3d C = 0.1 * A * A.transpose() + 0.01 * Eigen::Matrix3d::Identity();
  for (double dt : {0.1, 0.5, 20.0}) {
    const GnssDriftStepFactor cost(params, dt, step, C);
    Blocks b;
    b.Add(RandomVector(&rng_, 2.0));
    b.Add(RandomVector(&rng_, 2.0));
    CheckGradients(cost, b);
    double* jac[2] = {nullptr, nullptr};
    Eigen::Matrix<double, 3, 3, Eigen::RowMajor> J_j;
    jac[1] = J_j.data();
    Eigen::Vector3d r;
    const std::vector<const double*> p = b.ptrs();
    ASSERT_TRUE(cost.Evaluate(p.data(), r.data(), jac));
    const double phi = std::exp(-dt / params.tau_s);
    const Eigen::Vector3d sigma_w = Eigen::Vector3d(2.0, 2.0, 3.0) * std::sqrt(1.0 - phi * phi);
    const Eigen::Matrix3d Q = sigma_w.cwiseAbs2().asDiagonal();
    // J_j is L^T: whitening the sum of both covariances.
    EXPECT_LT((J_j * (Q + C) * J_j.transpose() - Eigen::Matrix3d::Identity()).norm(), 1e-9) << dt;
    EXPECT_LT((r - J_j * (b.values[1] - phi * b.values[0] - step)).norm(), 1e-12);
    const Eigen::Vector3d b_j = phi * b.values[0] + step;
    const double* on[2] = {b.values[0].data(), b_j.data()};
    ASSERT_TRUE(cost.Evaluate(on, r.data(), nullptr));
    EXPECT_LT(r.norm(), 1e-12);
  }
  // No step, no covariance: the plain transition.
  const GnssDriftStepFactor none(params, 0.5, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Zero());
  const GnssDriftFactor plain(params, 0.5);
  Blocks b;
  b.Add(RandomVector(&rng_, 2.0));
  b.Add(RandomVector(&rng_, 2.0));
  const std::vector<const double*> p = b.ptrs();
  Eigen::Vector3d r_step, r_plain;
  ASSERT_TRUE(none.Evaluate(p.data(), r_step.data(), nullptr));
  ASSERT_TRUE(plain.Evaluate(p.data(), r_plain.data(), nullptr));
  EXPECT_LT((r_step - r_plain).norm(), 1e-9 * r_plain.norm());
  // A covariance that is not finite is refused, not whitened into garbage.
  Eigen::Matrix3d bad = C;
  bad(0, 0) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(GnssDriftStepFactor(params, 0.5, step, bad), std::invalid_argument);
}

TEST_F(FactorJacobianTest, GnssHeadingFactor) {
  const Eigen::Vector3d baseline(0.9, 0.3, -0.2);
  for (int trial = 0; trial < 5; ++trial) {
    const double z = std::uniform_real_distribution<double>(-3.0, 3.0)(rng_);
    // A fix far from the origin: its local level turned from w by a few mrad.
    const Eigen::Matrix3d R_n_w = ExpSO3(RandomVector(&rng_, 0.005));
    const std::unique_ptr<ceres::CostFunction> cost =
        GnssHeadingFactor::Create(z, 0.02, baseline, R_n_w);
    // Mostly level attitudes (a boat), random yaw: the baseline's horizontal projection is long.
    const Eigen::Quaterniond q(
        Eigen::AngleAxisd(std::uniform_real_distribution<double>(-3.0, 3.0)(rng_),
                          Eigen::Vector3d::UnitZ()) *
        Eigen::AngleAxisd(0.1, Eigen::Vector3d(1.0, 0.5, 0.0).normalized()));
    Blocks b;
    b.Add(q);
    CheckGradients(*cost, b);
  }
}

// Heading convention: clockwise from north. A level body whose baseline (x, forward) points
// east has heading +pi/2; a yaw of +a (counter-clockwise about up) has heading -a.
TEST_F(FactorJacobianTest, GnssHeadingConvention) {
  const Eigen::Vector3d baseline = Eigen::Vector3d::UnitX();
  const double sigma = 0.1;
  auto residual = [&](double heading, double yaw) {
    const std::unique_ptr<ceres::CostFunction> cost =
        GnssHeadingFactor::Create(heading, sigma, baseline, Eigen::Matrix3d::Identity());
    const Eigen::Quaterniond q(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()));
    const double* p[] = {q.coeffs().data()};
    double r = 0.0;
    EXPECT_TRUE(cost->Evaluate(p, &r, nullptr));
    return r * sigma;
  };
  EXPECT_NEAR(residual(kPi / 2.0, 0.0), 0.0, 1e-12);  // x forward = east
  EXPECT_NEAR(residual(0.0, kPi / 2.0), 0.0, 1e-12);  // yaw +90 deg: x points north
  EXPECT_NEAR(residual(kPi / 2.0 - 0.3, 0.3), 0.0, 1e-12);
  // Wrap: heading 179 deg vs measured -179 deg is a 2 deg error, not 358.
  const double d = kPi / 180.0;
  EXPECT_NEAR(std::abs(residual(-179.0 * d, kPi / 2.0 - 179.0 * d)), 2.0 * d, 1e-9);
}

// Pose fixes of every kind (en, enu, enh, enuh) with full correlated covariances, a lever arm and
// a turned sensor: the Jacobians on q_w_b, p_w_b, q_b_s and p_b_s.
TEST_F(FactorJacobianTest, PoseFixFactor) {
  for (int kind = 0; kind < 4; ++kind) {
    for (int trial = 0; trial < 3; ++trial) {
      PoseFix fix;
      fix.has_up = kind % 2 == 1;
      fix.has_heading = kind >= 2;
      fix.p_w = RandomVector(&rng_, 50.0);
      fix.heading_deg = std::uniform_real_distribution<double>(-180.0, 180.0)(rng_);
      const Eigen::Matrix4d A = Eigen::Matrix4d::Random();
      fix.covariance = A * A.transpose() + 0.1 * Eigen::Matrix4d::Identity();
      const Eigen::Matrix3d R_n_w = ExpSO3(RandomVector(&rng_, 0.005));
      const std::unique_ptr<ceres::CostFunction> cost = PoseFixFactor::Create(fix, R_n_w);
      ASSERT_EQ(cost->num_residuals(), 2 + fix.has_up + fix.has_heading);
      // A vessel's attitude (small roll/pitch, any yaw) and a sensor turned on the mast.
      const Eigen::Quaterniond q_w_b(
          Eigen::AngleAxisd(std::uniform_real_distribution<double>(-3.0, 3.0)(rng_),
                            Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(0.1, Eigen::Vector3d(1.0, 0.5, 0.0).normalized()));
      const Eigen::Quaterniond q_b_s(Eigen::AngleAxisd(1.2, Eigen::Vector3d::UnitZ()) *
                                     Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitX()));
      Blocks b;
      b.Add(q_w_b);
      b.Add(Eigen::Vector3d(fix.p_w + RandomVector(&rng_, 1.0)));
      b.Add(q_b_s);
      b.Add(Eigen::Vector3d(0.5, -0.3, 4.0));
      CheckGradients(*cost, b);
    }
  }
}

// 20 km east of the origin the w axes are tilted 3 mrad from the local level: a horizontal fix
// must see the error along the local east and north, so that a 100 m error along the local up
// (a diverged vertical channel) leaves its residual alone.
TEST_F(FactorJacobianTest, PoseFixIsInTheLocalLevel) {
  const double tilt = 20000.0 / 6.371e6;  // rad, about the local north axis
  const Eigen::Matrix3d R_n_w = Eigen::AngleAxisd(-tilt, Eigen::Vector3d::UnitY()).matrix();
  PoseFix fix;
  fix.p_w = Eigen::Vector3d(20000.0, 0.0, -31.4);
  fix.covariance = Eigen::Vector4d(0.25, 0.25, 1.0, 1e-4).asDiagonal();
  const std::unique_ptr<ceres::CostFunction> cost = PoseFixFactor::Create(fix, R_n_w);
  const Eigen::Vector3d up_n = R_n_w.transpose() * Eigen::Vector3d::UnitZ();  // local up in w
  const Eigen::Vector3d p = fix.p_w + 100.0 * up_n;
  const Eigen::Vector4d q = Eigen::Quaterniond::Identity().coeffs();
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  const double* params[] = {q.data(), p.data(), q.data(), zero.data()};
  Eigen::Vector2d r;
  ASSERT_TRUE(cost->Evaluate(params, r.data(), nullptr));
  EXPECT_LT(r.norm(), 1e-9) << r.transpose();  // 0.63 m / 0.5 = 1.26 in w's axes
}

// The residual is whitened by the measured components' covariance: at a pose whose errors are
// e, r^T r = e^T C^-1 e; and a covariance that is not positive definite is refused.
TEST_F(FactorJacobianTest, PoseFixWhiteningAndBadCovariance) {
  PoseFix fix;
  fix.has_heading = true;
  fix.p_w = Eigen::Vector3d(10.0, 20.0, 0.0);
  fix.heading_deg = 90.0;  // x axis east
  fix.covariance << 0.25, 0.1, 0, 0.005, 0.1, 0.36, 0, 0, 0, 0, 9, 0, 0.005, 0, 0, 0.0004;
  const std::unique_ptr<ceres::CostFunction> cost =
      PoseFixFactor::Create(fix, Eigen::Matrix3d::Identity());
  const Eigen::Vector4d q = Eigen::Quaterniond::Identity().coeffs();  // x axis east
  const Eigen::Vector3d e(0.3, -0.2, 0.0);
  const Eigen::Vector3d p = fix.p_w + e;
  const Eigen::Vector4d q_bs = Eigen::Quaterniond::Identity().coeffs();
  const Eigen::Vector3d p_bs = Eigen::Vector3d::Zero();
  const double* params[] = {q.data(), p.data(), q_bs.data(), p_bs.data()};
  Eigen::Vector3d r;
  ASSERT_TRUE(cost->Evaluate(params, r.data(), nullptr));
  Eigen::Matrix3d C;
  C << 0.25, 0.1, 0.005, 0.1, 0.36, 0, 0.005, 0, 0.0004;
  const Eigen::Vector3d err(e.x(), e.y(), 0.0);
  EXPECT_NEAR(r.squaredNorm(), err.dot(C.ldlt().solve(err)), 1e-9);
  PoseFix bad = fix;
  bad.covariance(1, 0) = bad.covariance(0, 1) = 0.5;  // |rho| > 1
  EXPECT_THROW(PoseFixFactor::Create(bad, Eigen::Matrix3d::Identity()), std::invalid_argument);
  bad = fix;
  bad.covariance(3, 3) = 0.0;
  EXPECT_THROW(PoseFixFactor::Create(bad, Eigen::Matrix3d::Identity()), std::invalid_argument);
  bad = fix;
  bad.covariance(2, 2) = -1.0;  // up is not measured: its row is ignored
  EXPECT_NO_THROW(PoseFixFactor::Create(bad, Eigen::Matrix3d::Identity()));
}

TEST_F(FactorJacobianTest, WaterSurfaceFactor) {
  const WaterSurfaceFactor cost(440.0, 6.37e6, 440.3, 0.3);
  for (int trial = 0; trial < 5; ++trial) {
    Blocks b;
    b.Add(Eigen::Vector3d(RandomVector(&rng_, 5000.0)));
    CheckGradients(cost, b);
  }
  // The tangent plane rises above the ellipsoid: 10 km east at z = -7.85 m is on it.
  const Eigen::Vector3d p(10000.0, 0.0, -1e8 / (2.0 * 6.37e6) + 0.3);
  const double* params[] = {p.data()};
  double r = 1.0;
  ASSERT_TRUE(cost.Evaluate(params, &r, nullptr));
  EXPECT_NEAR(r, 0.0, 1e-12);
  EXPECT_THROW(WaterSurfaceFactor(440.0, 6.37e6, 440.0, 0.0), std::invalid_argument);
}

TEST_F(FactorJacobianTest, StatePriorFactor) {
  NavState prior;
  prior.q_w_b = RandomQuaternion(&rng_);
  prior.p_w_b = RandomVector(&rng_, 10.0);
  prior.v_w = RandomVector(&rng_, 2.0);
  prior.bg = RandomVector(&rng_, 0.01);
  prior.ba = RandomVector(&rng_, 0.1);
  // A full (correlated) covariance.
  const Eigen::Matrix<double, 15, 15> A = Eigen::Matrix<double, 15, 15>::Random();
  const StateCovariance cov = A * A.transpose() * 0.01 + StateCovariance::Identity() * 1e-3;
  const std::unique_ptr<ceres::CostFunction> cost = StatePriorFactor::Create(prior, cov);
  Blocks b;
  b.Add(Eigen::Quaterniond(prior.q_w_b * ExpQ<double>(RandomVector(&rng_, 0.3))));
  b.Add(Eigen::Vector3d(prior.p_w_b + RandomVector(&rng_, 1.0)));
  b.Add(Eigen::Vector3d(prior.v_w + RandomVector(&rng_, 0.5)));
  b.Add(Eigen::Vector3d(prior.bg + RandomVector(&rng_, 0.01)));
  b.Add(Eigen::Vector3d(prior.ba + RandomVector(&rng_, 0.1)));
  CheckGradients(*cost, b);
  // Whitening: |r|^2 = e^T cov^-1 e with e the left tangent error.
  Eigen::Matrix<double, 15, 1> e, r;
  e << LogQ<double>(Eigen::Quaterniond(b.values[0].data()) * prior.q_w_b.conjugate()),
      b.values[1] - prior.p_w_b, b.values[2] - prior.v_w, b.values[3] - prior.bg,
      b.values[4] - prior.ba;
  const std::vector<const double*> p = b.ptrs();
  ASSERT_TRUE(cost->Evaluate(p.data(), r.data(), nullptr));
  EXPECT_NEAR(r.squaredNorm(), e.dot(cov.ldlt().solve(e)), 1e-8 * r.squaredNorm());
  // At the prior itself the residual is zero and the rotation Jacobian is still exact.
  Blocks b0;
  b0.Add(prior.q_w_b);
  b0.Add(prior.p_w_b);
  b0.Add(prior.v_w);
  b0.Add(prior.bg);
  b0.Add(prior.ba);
  CheckGradients(*cost, b0);
}

TEST_F(FactorJacobianTest, LinearPriorFactorAwayFromX0) {
  const std::vector<int> sizes = {4, 3, 3, 4, 3};
  std::vector<Eigen::VectorXd> x0;
  Blocks x;
  for (int size : sizes) {
    if (size == 4) {
      const Eigen::Quaterniond q0 = RandomQuaternion(&rng_);
      x0.push_back(q0.coeffs());
      x.Add(Eigen::Quaterniond(ExpQ<double>(RandomVector(&rng_, 0.4)) * q0));
    } else {
      const Eigen::Vector3d v0 = RandomVector(&rng_, 2.0);
      x0.push_back(v0);
      x.Add(Eigen::Vector3d(v0 + RandomVector(&rng_, 0.5)));
    }
  }
  const Eigen::MatrixXd J = Eigen::MatrixXd::Random(10, 15);
  const Eigen::VectorXd r0 = Eigen::VectorXd::Random(10);
  const LinearPriorFactor cost(sizes, x0, J, r0);
  CheckGradients(cost, x);
  // Residual definition: r0 + J [Log(q x0^-1); p - p0; ...].
  Eigen::VectorXd delta(15);
  int col = 0;
  for (size_t k = 0; k < sizes.size(); ++k) {
    if (sizes[k] == 4) {
      const Eigen::Quaterniond q(x.values[k].data()), q0(x0[k].data());
      delta.segment<3>(col) = LogQ<double>(q * q0.conjugate());
      col += 3;
    } else {
      delta.segment<3>(col) = x.values[k] - x0[k];
      col += 3;
    }
  }
  Eigen::VectorXd r(10);
  const std::vector<const double*> p = x.ptrs();
  ASSERT_TRUE(cost.Evaluate(p.data(), r.data(), nullptr));
  EXPECT_LT((r - (r0 + J * delta)).norm(), 1e-12);
}

// ---------------------------------------------------------------------------------------------
// LinearizeResidual: quaternion blocks get d r(Exp(theta) * q) / d theta (full angle, world
// frame, at theta = 0), other blocks plain Jacobians; robust losses scale both by sqrt(rho').

// Numeric tangent Jacobians of `cost` at `blocks`, skerry convention, by central differences.
std::vector<Eigen::MatrixXd> NumericTangentJacobians(const ceres::CostFunction& cost,
                                                     const Blocks& blocks) {
  std::vector<Eigen::MatrixXd> out;
  for (size_t k = 0; k < blocks.values.size(); ++k) {
    const bool is_quat = blocks.values[k].size() == 4;
    auto f = [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
      Blocks moved = blocks;
      if (is_quat) {
        const Eigen::Quaterniond q(blocks.values[k].data());
        moved.values[k] = (ExpQ<double>(Eigen::Vector3d(d)) * q).coeffs();
      } else {
        moved.values[k] = blocks.values[k] + d;
      }
      Eigen::VectorXd r(cost.num_residuals());
      const std::vector<const double*> p = moved.ptrs();
      EXPECT_TRUE(cost.Evaluate(p.data(), r.data(), nullptr));
      return r;
    };
    out.push_back(
        test::NumericJacobian(f, Eigen::VectorXd::Zero(is_quat ? 3 : blocks.values[k].size())));
  }
  return out;
}

TEST(LinearizeResidualTest, QuaternionLeftPlusJacobianIsNumericDerivative) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 10; ++trial) {
    const Eigen::Quaterniond q = RandomQuaternion(&rng);
    auto f = [&](const Eigen::VectorXd& d) -> Eigen::VectorXd {
      return (ExpQ<double>(Eigen::Vector3d(d)) * q).coeffs();
    };
    test::TestJacobian("left plus", QuaternionLeftPlusJacobian(q.coeffs().data()), f,
                       Eigen::VectorXd::Zero(3), 1e-9);
  }
}

class LinearizeImuFactorTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const test::AnalyticTrajectory traj;
    const ImuConfig imu = test::RotatedOffsetImu();
    const Eigen::Vector3d bg(0.002, -0.001, 0.003), ba(0.04, -0.02, 0.06);
    auto pim = std::make_shared<ImuPreintegration>(
        test::Preintegrate(test::IdealImuSteps(traj, 0.3, 0.8, 200.0, bg, ba), imu.noise, bg, ba));
    cost_ = ImuFactor::Create(*pim, imu, traj.gyro(0.3) + bg, traj.gyro(0.8) + bg,
                              traj.EarthTerms(0.3));
    // Near-truth states perturbed so the whitened residual is O(10): in a robust loss's tail.
    const NavState si = traj.BodyState(0.3, imu, bg, ba), sj = traj.BodyState(0.8, imu, bg, ba);
    blocks_.Add(si.q_w_b);
    blocks_.Add(si.p_w_b);
    blocks_.Add(si.v_w);
    blocks_.Add(si.bg);
    blocks_.Add(si.ba);
    blocks_.Add(Eigen::Quaterniond(ExpQ<double>(Eigen::Vector3d(0.002, -0.001, 0.003)) * sj.q_w_b));
    blocks_.Add(Eigen::Vector3d(sj.p_w_b + Eigen::Vector3d(0.01, 0.02, -0.01)));
    blocks_.Add(Eigen::Vector3d(sj.v_w + Eigen::Vector3d(-0.01, 0.005, 0.01)));
  }
  std::unique_ptr<ceres::CostFunction> cost_;
  Blocks blocks_;
};

TEST_F(LinearizeImuFactorTest, TangentJacobiansMatchNumericLeftPerturbation) {
  LinearizedResidual lin;
  ASSERT_TRUE(LinearizeResidual(*cost_, nullptr, blocks_.ptrs(), blocks_.ptrs(), &lin));
  Eigen::VectorXd r(9);
  const std::vector<const double*> p = blocks_.ptrs();
  ASSERT_TRUE(cost_->Evaluate(p.data(), r.data(), nullptr));
  EXPECT_LT((lin.residual - r).norm(), 1e-12 * r.norm());
  const std::vector<Eigen::MatrixXd> J_num = NumericTangentJacobians(*cost_, blocks_);
  ASSERT_EQ(lin.jacobians.size(), J_num.size());
  for (size_t k = 0; k < J_num.size(); ++k) {
    ASSERT_EQ(lin.jacobians[k].cols(), J_num[k].cols()) << k;
    const double scale = std::max(1.0, J_num[k].cwiseAbs().maxCoeff());
    EXPECT_LT((lin.jacobians[k] - J_num[k]).cwiseAbs().maxCoeff(), 1e-6 * scale)
        << "block " << k << "\nanalytic\n"
        << lin.jacobians[k] << "\nnumeric\n"
        << J_num[k];
  }
}

TEST_F(LinearizeImuFactorTest, RobustLossAppliesTriggsScaling) {
  LinearizedResidual plain;
  ASSERT_TRUE(LinearizeResidual(*cost_, nullptr, blocks_.ptrs(), blocks_.ptrs(), &plain));
  const double s = plain.residual.squaredNorm();
  ASSERT_GT(s, 9.0);  // in the tail of both losses below (scale 3 sigma)
  const double a = 3.0;
  // rho'(s) in closed form: Huber a/sqrt(s) for s > a^2; Cauchy 1 / (1 + s / a^2).
  const ceres::HuberLoss huber(a);
  const ceres::CauchyLoss cauchy(a);
  const std::vector<std::pair<const ceres::LossFunction*, double>> cases = {
      {&huber, a / std::sqrt(s)}, {&cauchy, 1.0 / (1.0 + s / (a * a))}};
  for (const auto& [loss, rho1] : cases) {
    LinearizedResidual robust;
    ASSERT_TRUE(LinearizeResidual(*cost_, loss, blocks_.ptrs(), blocks_.ptrs(), &robust));
    const double w = std::sqrt(rho1);
    EXPECT_LT(w, 0.99);
    EXPECT_LT((robust.residual - w * plain.residual).norm(), 1e-12 * plain.residual.norm());
    for (size_t k = 0; k < plain.jacobians.size(); ++k) {
      EXPECT_LT((robust.jacobians[k] - w * plain.jacobians[k]).norm(),
                1e-12 * (1.0 + plain.jacobians[k].norm()))
          << k;
    }
  }
}

// First-estimate Jacobians: residual at one point, Jacobians at another.
TEST_F(LinearizeImuFactorTest, FirstEstimateJacobians) {
  Blocks moved = blocks_;
  moved.values[6] += Eigen::Vector3d(0.3, -0.2, 0.1);  // p_j
  moved.values[0] = (ExpQ<double>(Eigen::Vector3d(0.05, 0.0, -0.02)) *
                     Eigen::Quaterniond(blocks_.values[0].data()))
                        .coeffs();  // q_i
  LinearizedResidual fej, at_moved, at_orig;
  ASSERT_TRUE(LinearizeResidual(*cost_, nullptr, moved.ptrs(), blocks_.ptrs(), &fej));
  ASSERT_TRUE(LinearizeResidual(*cost_, nullptr, moved.ptrs(), moved.ptrs(), &at_moved));
  ASSERT_TRUE(LinearizeResidual(*cost_, nullptr, blocks_.ptrs(), blocks_.ptrs(), &at_orig));
  EXPECT_LT((fej.residual - at_moved.residual).norm(), 1e-12 * at_moved.residual.norm());
  for (size_t k = 0; k < fej.jacobians.size(); ++k) {
    EXPECT_LT((fej.jacobians[k] - at_orig.jacobians[k]).norm(), 1e-12 * at_orig.jacobians[k].norm())
        << k;
  }
  EXPECT_GT((at_moved.jacobians[0] - at_orig.jacobians[0]).norm(),
            1e-3 * at_orig.jacobians[0].norm());
}

}  // namespace
}  // namespace skerry
