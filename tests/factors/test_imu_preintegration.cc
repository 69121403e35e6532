// ImuPreintegration, PredictBodyState and the ImuFactor residual against an analytic trajectory,
// numeric bias Jacobians and a Monte-Carlo covariance.

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <cmath>
#include <memory>
#include <random>

#include "factors/test_utils.h"
#include "skerry/core/measurements.h"
#include "skerry/core/time.h"
#include "skerry/factors/imu_factor.h"
#include "skerry/factors/imu_preintegration.h"

namespace skerry {
namespace {

using test::AnalyticTrajectory;
using test::ImuStep;
using test::kGravityW;

// The generator itself: its closed-form gyro, velocity, acceleration and body velocity agree with
// numeric derivatives of its positions and attitudes.
TEST(TrajectoryTest, ClosedFormsMatchNumericDerivatives) {
  const AnalyticTrajectory traj;
  const ImuConfig imu = test::RotatedOffsetImu();
  const double h = 1e-4;
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  for (double t : {0.0, 0.7, 1.9, 3.3}) {
    const Eigen::Vector3d w_num =
        LogQ<double>(traj.q_w_i(t - h).conjugate() * traj.q_w_i(t + h)) / (2.0 * h);
    EXPECT_LT((traj.gyro(t) - w_num).norm(), 1e-7) << t;
    const Eigen::Vector3d v_num = (traj.p_w_i(t + h) - traj.p_w_i(t - h)) / (2.0 * h);
    EXPECT_LT((traj.v_w_i(t) - v_num).norm(), 1e-7) << t;
    const Eigen::Vector3d a_num = (traj.v_w_i(t + h) - traj.v_w_i(t - h)) / (2.0 * h);
    EXPECT_LT((traj.a_w_i(t) - a_num).norm(), 1e-7) << t;
    const Eigen::Vector3d vb_num = (traj.BodyState(t + h, imu, zero, zero).p_w_b -
                                    traj.BodyState(t - h, imu, zero, zero).p_w_b) /
                                   (2.0 * h);
    EXPECT_LT((traj.BodyState(t, imu, zero, zero).v_w - vb_num).norm(), 1e-7) << t;
  }
}

struct DeltaErrors {
  double rot, vel, pos;
};

// Errors of noise-free, bias-free preintegration over [t0, t1] against the true relative motion.
DeltaErrors PreintegrationErrors(double t0, double t1, double rate_hz) {
  const AnalyticTrajectory traj;
  const ImuPreintegration pim =
      test::Preintegrate(test::IdealImuSteps(traj, t0, t1, rate_hz), ImuNoise(),
                         Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  const double dt = t1 - t0;
  EXPECT_NEAR(pim.deltas().dt_s, dt, 1e-12);
  const Eigen::Quaterniond q_i = traj.q_w_i(t0), q_j = traj.q_w_i(t1);
  const Eigen::Vector3d p_i = traj.p_w_i(t0), p_j = traj.p_w_i(t1);
  const Eigen::Vector3d v_i = traj.v_w_i(t0), v_j = traj.v_w_i(t1);
  const Eigen::Quaterniond dq_true = q_i.conjugate() * q_j;
  const Eigen::Vector3d dv_true = q_i.conjugate() * (v_j - v_i - kGravityW * dt);
  const Eigen::Vector3d dp_true =
      q_i.conjugate() * (p_j - p_i - v_i * dt - 0.5 * kGravityW * dt * dt);
  return {test::AngleBetween(dq_true, pim.deltas().dq), (pim.deltas().dv - dv_true).norm(),
          (pim.deltas().dp - dp_true).norm()};
}

// The scheme holds the trapezoidal average of two samples over each step and rotates it with the
// attitude at the middle of the step: dR, dv and dp are all second order in dt. So: errors far
// below a millimetre at 1 kHz over 1 s, and 5x the rate shrinks every error ~25x.
TEST(ImuPreintegrationTest, MatchesAnalyticTrajectory) {
  const DeltaErrors e200 = PreintegrationErrors(2.0, 3.0, 200.0);
  const DeltaErrors e1000 = PreintegrationErrors(2.0, 3.0, 1000.0);
  EXPECT_LT(e1000.rot, 1e-7);
  EXPECT_LT(e1000.vel, 2e-6);
  EXPECT_LT(e1000.pos, 1e-6);
  EXPECT_GT(e200.rot / e1000.rot, 15.0);
  EXPECT_GT(e200.vel / e1000.vel, 20.0);
  EXPECT_LT(e200.vel / e1000.vel, 30.0);
  EXPECT_GT(e200.pos / e1000.pos, 20.0);
  EXPECT_LT(e200.pos / e1000.pos, 30.0);
}

TEST(ImuPreintegrationTest, EmptyAndZeroLengthSteps) {
  ImuPreintegration pim(ImuNoise(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  pim.Integrate(0.0, Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(4, 5, 6));
  pim.Integrate(-0.01, Eigen::Vector3d(1, 2, 3), Eigen::Vector3d(4, 5, 6));
  EXPECT_EQ(pim.deltas().dt_s, 0.0);
  EXPECT_EQ(pim.deltas().dv, Eigen::Vector3d::Zero());
  EXPECT_EQ(pim.covariance(), ImuPreintegration::Matrix9::Zero());
}

// IntegrateBetween holds the average of two timestamped samples over their interval: fed with
// ideal samples of the analytic trajectory it gives exactly the trapezoidal steps above.
TEST(ImuPreintegrationTest, IntegrateBetweenIsTheTrapezoidalStep) {
  const AnalyticTrajectory traj;
  const double rate_hz = 200.0;
  const TimeNs t0_ns = SecondsToNs(2.0);
  const TimeNs step_ns = SecondsToNs(1.0 / rate_hz);
  std::vector<ImuSample> samples;
  for (int k = 0; k <= 200; ++k) {
    ImuSample s;
    s.t_ns = t0_ns + k * step_ns;
    s.gyro_rad_s = traj.gyro(NsToSeconds(s.t_ns));
    s.accel_m_s2 = traj.accel(NsToSeconds(s.t_ns));
    samples.push_back(s);
  }
  ImuPreintegration pim(ImuNoise(), Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  for (size_t k = 0; k + 1 < samples.size(); ++k)
    IntegrateBetween(samples[k], samples[k + 1], &pim);
  const ImuPreintegration ref =
      test::Preintegrate(test::IdealImuSteps(traj, 2.0, 3.0, rate_hz), ImuNoise(),
                         Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero());
  EXPECT_NEAR(pim.deltas().dt_s, 1.0, 1e-12);
  EXPECT_LT(test::AngleBetween(pim.deltas().dq, ref.deltas().dq), 1e-12);
  EXPECT_LT((pim.deltas().dv - ref.deltas().dv).norm(), 1e-10);
  EXPECT_LT((pim.deltas().dp - ref.deltas().dp).norm(), 1e-10);
  EXPECT_LT((pim.covariance() - ref.covariance()).norm(), 1e-9 * ref.covariance().norm());
}

// KeyframeGyro: mean gyro of the samples in (t - 25 ms, t], t the last sample's time.
TEST(ImuPreintegrationTest, KeyframeGyroAveragesTheLast25Ms) {
  std::vector<ImuSample> samples;
  for (int k = 0; k < 10; ++k) {  // 200 Hz: t = 0, 5, ..., 45 ms; gyro x = k
    ImuSample s;
    s.t_ns = k * 5'000'000;
    s.gyro_rad_s = Eigen::Vector3d(k, 2.0 * k, -1.0);
    samples.push_back(s);
  }
  // (20 ms, 45 ms] holds k = 5..9: mean 7.
  const Eigen::Vector3d g = KeyframeGyro(samples.begin(), samples.end());
  EXPECT_LT((g - Eigen::Vector3d(7.0, 14.0, -1.0)).norm(), 1e-12) << g.transpose();
  // A sub-range ends earlier: samples 0..3 (t = 15 ms) -> (-10 ms, 15 ms] holds all four.
  const Eigen::Vector3d g4 = KeyframeGyro(samples.begin(), samples.begin() + 4);
  EXPECT_LT((g4 - Eigen::Vector3d(1.5, 3.0, -1.0)).norm(), 1e-12) << g4.transpose();
  // A single sample is its own mean.
  const Eigen::Vector3d g1 = KeyframeGyro(samples.begin() + 6, samples.begin() + 7);
  EXPECT_LT((g1 - samples[6].gyro_rad_s).norm(), 1e-15);
}

// Single step with constant inputs: closed forms dR = Exp(w dt), dv = Exp(w dt / 2) a dt,
// dp = Exp(w dt / 2) a dt^2 / 2 (the midpoint attitude) and the one-step covariance blocks, where
// gyro noise reaches v and p through the midpoint attitude: M = Exp(w dt / 2) [a]x Jr(w dt / 2).
TEST(ImuPreintegrationTest, SingleStepClosedForm) {
  ImuNoise noise;
  const Eigen::Vector3d bg(0.01, -0.02, 0.005), ba(0.1, 0.05, -0.2);
  const Eigen::Vector3d w(0.3, -0.1, 0.5), a(1.0, -2.0, 9.0);
  const double dt = 0.01;
  ImuPreintegration pim(noise, bg, ba);
  pim.Integrate(dt, w, a);
  const Eigen::Vector3d phi = (w - bg) * dt;
  const Eigen::Matrix3d R_half = ExpSO3(0.5 * phi);
  EXPECT_LT(test::AngleBetween(pim.deltas().dq, ExpQ<double>(phi)), 1e-15);
  EXPECT_LT((pim.deltas().dv - R_half * (a - ba) * dt).norm(), 1e-15);
  EXPECT_LT((pim.deltas().dp - 0.5 * R_half * (a - ba) * dt * dt).norm(), 1e-15);
  const double var_g = std::pow(noise.gyro_noise_density_rad_s_sqrt_hz, 2) / dt;
  const double var_a = std::pow(noise.accel_noise_density_m_s2_sqrt_hz, 2) / dt;
  const Eigen::Matrix3d Jr = RightJacobianSO3(phi);
  const Eigen::Matrix3d M = R_half * Hat<double>(a - ba) * RightJacobianSO3(0.5 * phi);
  const Eigen::Matrix3d I = Eigen::Matrix3d::Identity();
  const auto& C = pim.covariance();
  auto near = [](const Eigen::Matrix3d& x, const Eigen::Matrix3d& y) {
    return (x - y).norm() <= 1e-12 * std::max(y.norm(), 1e-30);
  };
  EXPECT_TRUE(near(C.block<3, 3>(0, 0), var_g * dt * dt * Jr * Jr.transpose()));
  EXPECT_TRUE(near(C.block<3, 3>(0, 3), -0.5 * var_g * std::pow(dt, 3) * Jr * M.transpose()));
  EXPECT_TRUE(near(C.block<3, 3>(3, 3),
                   var_a * dt * dt * I + var_g * std::pow(dt, 4) / 4 * M * M.transpose()));
  EXPECT_TRUE(near(C.block<3, 3>(6, 6), var_a * std::pow(dt, 4) / 4 * I +
                                            var_g * std::pow(dt, 6) / 16 * M * M.transpose()));
  EXPECT_TRUE(near(C.block<3, 3>(3, 6), var_a * std::pow(dt, 3) / 2 * I +
                                            var_g * std::pow(dt, 5) / 8 * M * M.transpose()));
}

// Re-integrates with perturbed linearisation biases: output [Log(dR0^T dR), dv, dp].
Eigen::VectorXd DeltasAtBias(const std::vector<ImuStep>& steps,
                             const Eigen::Vector3d& bg,
                             const Eigen::Vector3d& ba,
                             const Eigen::Quaterniond& dq0) {
  const ImuPreintegration pim = test::Preintegrate(steps, ImuNoise(), bg, ba);
  Eigen::VectorXd out(9);
  out << LogQ<double>(dq0.conjugate() * pim.deltas().dq), pim.deltas().dv, pim.deltas().dp;
  return out;
}

TEST(ImuPreintegrationTest, BiasJacobiansMatchNumericReintegration) {
  const AnalyticTrajectory traj;
  const Eigen::Vector3d bg(0.004, -0.003, 0.006), ba(0.08, -0.05, 0.12);
  const std::vector<ImuStep> steps = test::IdealImuSteps(traj, 1.0, 2.0, 200.0, bg, ba);
  const ImuPreintegration pim = test::Preintegrate(steps, ImuNoise(), bg, ba);
  // Every Jacobian must be non-trivial for the comparison to mean something.
  for (const Eigen::Matrix3d* J : {&pim.deltas().J_R_bg, &pim.deltas().J_v_bg, &pim.deltas().J_v_ba,
                                   &pim.deltas().J_p_bg, &pim.deltas().J_p_ba}) {
    EXPECT_GT(J->norm(), 0.1);
  }
  const Eigen::Quaterniond dq0 = pim.deltas().dq;
  Eigen::Vector3d x0_bg = bg, x0_ba = ba;
  auto f_bg = [&](const Eigen::VectorXd& x) -> Eigen::VectorXd {
    return DeltasAtBias(steps, Eigen::Vector3d(x), x0_ba, dq0);
  };
  auto f_ba = [&](const Eigen::VectorXd& x) -> Eigen::VectorXd {
    return DeltasAtBias(steps, x0_bg, Eigen::Vector3d(x), dq0);
  };
  const Eigen::MatrixXd J_bg_num = test::NumericJacobian(f_bg, bg);
  const Eigen::MatrixXd J_ba_num = test::NumericJacobian(f_ba, ba);
  const double tol = 1e-6;
  EXPECT_LT((pim.deltas().J_R_bg - J_bg_num.middleRows<3>(0)).norm(), tol) << J_bg_num;
  EXPECT_LT((pim.deltas().J_v_bg - J_bg_num.middleRows<3>(3)).norm(), tol) << J_bg_num;
  EXPECT_LT((pim.deltas().J_p_bg - J_bg_num.middleRows<3>(6)).norm(), tol) << J_bg_num;
  EXPECT_LT(J_ba_num.middleRows<3>(0).norm(), tol) << J_ba_num;  // dR does not depend on ba
  EXPECT_LT((pim.deltas().J_v_ba - J_ba_num.middleRows<3>(3)).norm(), tol) << J_ba_num;
  EXPECT_LT((pim.deltas().J_p_ba - J_ba_num.middleRows<3>(6)).norm(), tol) << J_ba_num;
}

// The gyro calibration Jacobians against numeric differences: the samples of a gyro with sensor
// errors E, (I + E) omega + bg, re-integrated for each perturbed e = vec(E) (column-major), in
// the tangent of the deltas (Log(dR0^T dR), dv, dp). The rates are the trajectory's own, so every
// column of E moves the deltas.
Eigen::VectorXd DeltasWithGyroErrors(const std::vector<ImuStep>& steps,
                                     const Eigen::Vector3d& bg,
                                     const Eigen::Vector3d& ba,
                                     const Eigen::VectorXd& e,
                                     const Eigen::Quaterniond& dq0) {
  const Eigen::Matrix3d E = Eigen::Map<const Eigen::Matrix3d>(e.data());
  ImuPreintegration pim(ImuNoise(), bg, ba);
  for (const ImuStep& s : steps) {
    pim.Integrate(s.dt, Eigen::Vector3d((Eigen::Matrix3d::Identity() + E) * (s.gyro - bg) + bg),
                  s.accel);
  }
  Eigen::VectorXd out(9);
  out << LogQ<double>(dq0.conjugate() * pim.deltas().dq), pim.deltas().dv, pim.deltas().dp;
  return out;
}

TEST(ImuPreintegrationTest, GyroCalibrationJacobiansMatchNumericReintegration) {
  const AnalyticTrajectory traj;
  const Eigen::Vector3d bg(0.004, -0.003, 0.006), ba(0.08, -0.05, 0.12);
  const std::vector<ImuStep> steps = test::IdealImuSteps(traj, 1.0, 2.0, 200.0, bg, ba);
  ImuPreintegration pim(ImuNoise(), bg, ba, /*gyro_calibration=*/true);
  for (const ImuStep& s : steps) pim.Integrate(s.dt, s.gyro, s.accel);
  ASSERT_NE(pim.gyro_calibration(), nullptr);
  EXPECT_EQ(test::Preintegrate(steps, ImuNoise(), bg, ba).gyro_calibration(), nullptr);
  const GyroCalibrationJacobians& c = *pim.gyro_calibration();
  // The deltas are those of a preintegration without the Jacobians, to the last bit.
  const ImuPreintegration plain = test::Preintegrate(steps, ImuNoise(), bg, ba);
  EXPECT_EQ(plain.deltas().dp, pim.deltas().dp);
  EXPECT_EQ(plain.covariance(), pim.covariance());
  const Eigen::Quaterniond dq0 = pim.deltas().dq;
  auto f = [&](const Eigen::VectorXd& e) -> Eigen::VectorXd {
    return DeltasWithGyroErrors(steps, bg, ba, e, dq0);
  };
  const Eigen::MatrixXd J_num = test::NumericJacobian(f, Eigen::VectorXd::Zero(9));
  // Every column is non-trivial (the trajectory turns about every axis).
  for (int k = 0; k < 9; ++k) EXPECT_GT(J_num.col(k).norm(), 1e-3) << k;
  // The true rate is (I + E)^-1 w: the derivative at E = 0 is that of -E w.
  const double tol = 1e-6 * J_num.norm();
  EXPECT_LT((c.J_R + J_num.middleRows<3>(0)).norm(), tol) << J_num;
  EXPECT_LT((c.J_v + J_num.middleRows<3>(3)).norm(), tol) << J_num;
  EXPECT_LT((c.J_p + J_num.middleRows<3>(6)).norm(), tol) << J_num;
}

// ImuDeltas::Corrected is the first-order update: for a bias change d it matches re-integration to
// O(|d|^2), much better than the uncorrected deltas (O(|d|)).
TEST(ImuPreintegrationTest, CorrectedDeltasMatchReintegrationToSecondOrder) {
  const AnalyticTrajectory traj;
  const Eigen::Vector3d bg(0.004, -0.003, 0.006), ba(0.08, -0.05, 0.12);
  const std::vector<ImuStep> steps = test::IdealImuSteps(traj, 1.0, 2.0, 200.0);
  const ImuPreintegration pim = test::Preintegrate(steps, ImuNoise(), bg, ba);
  for (double scale : {1e-2, 1e-3}) {
    const Eigen::Vector3d dbg = scale * Eigen::Vector3d(0.5, -1.0, 0.7);
    const Eigen::Vector3d dba = 10.0 * scale * Eigen::Vector3d(-0.3, 0.8, 1.0);
    const ImuPreintegration ref = test::Preintegrate(steps, ImuNoise(), bg + dbg, ba + dba);
    Eigen::Quaterniond dq;
    Eigen::Vector3d dv, dp;
    pim.deltas().Corrected<double>(bg + dbg, ba + dba, &dq, &dv, &dp);
    const double err_rot = test::AngleBetween(dq, ref.deltas().dq);
    const double err_v = (dv - ref.deltas().dv).norm();
    const double err_p = (dp - ref.deltas().dp).norm();
    const double raw_rot = test::AngleBetween(pim.deltas().dq, ref.deltas().dq);
    const double raw_v = (pim.deltas().dv - ref.deltas().dv).norm();
    EXPECT_LT(err_rot, 0.01 * raw_rot) << scale;
    EXPECT_LT(err_v, 0.01 * raw_v) << scale;
    // Second order: absolute errors scale with scale^2 (constant ~ |d2 delta / d bias2| ~ 1).
    EXPECT_LT(err_rot, 5.0 * scale * scale) << scale;
    EXPECT_LT(err_v, 50.0 * scale * scale) << scale;
    EXPECT_LT(err_p, 50.0 * scale * scale) << scale;
  }
}

// Monte-Carlo: noisy samples (white, discrete sigma = density / sqrt(dt)) integrated many times;
// the sample covariance of [Log(dR_ref^T dR), dv - dv_ref, dp - dp_ref] (reference: the same
// integration without noise) must match covariance().
TEST(ImuPreintegrationTest, CovarianceMatchesMonteCarlo) {
  const AnalyticTrajectory traj;
  ImuNoise noise;
  // Larger than default densities so noise clearly dominates round-off, still small enough for
  // the first-order propagation to hold.
  noise.gyro_noise_density_rad_s_sqrt_hz = 2e-3;
  noise.accel_noise_density_m_s2_sqrt_hz = 2e-2;
  const std::vector<ImuStep> steps = test::IdealImuSteps(traj, 0.5, 1.0, 200.0);
  const Eigen::Vector3d bg = Eigen::Vector3d::Zero(), ba = Eigen::Vector3d::Zero();
  const ImuPreintegration ref = test::Preintegrate(steps, noise, bg, ba);
  const double dt = steps.front().dt;
  const double sg = noise.gyro_noise_density_rad_s_sqrt_hz / std::sqrt(dt);
  const double sa = noise.accel_noise_density_m_s2_sqrt_hz / std::sqrt(dt);

  constexpr int kRuns = 2000;
  std::mt19937 rng(42);
  std::normal_distribution<double> n01(0.0, 1.0);
  Eigen::Matrix<double, 9, Eigen::Dynamic> err(9, kRuns);
  for (int run = 0; run < kRuns; ++run) {
    ImuPreintegration pim(noise, bg, ba);
    for (const ImuStep& s : steps) {
      const Eigen::Vector3d ng(n01(rng), n01(rng), n01(rng));
      const Eigen::Vector3d na(n01(rng), n01(rng), n01(rng));
      pim.Integrate(s.dt, s.gyro + sg * ng, s.accel + sa * na);
    }
    err.col(run) << LogQ<double>(ref.deltas().dq.conjugate() * pim.deltas().dq),
        pim.deltas().dv - ref.deltas().dv, pim.deltas().dp - ref.deltas().dp;
  }
  const Eigen::Matrix<double, 9, 1> mean = err.rowwise().mean();
  const Eigen::Matrix<double, 9, Eigen::Dynamic> centred = err.colwise() - mean;
  const Eigen::Matrix<double, 9, 9> S = centred * centred.transpose() / (kRuns - 1);
  const Eigen::Matrix<double, 9, 9>& C = ref.covariance();

  // Sample variances have relative std sqrt(2 / N) = 3.2%: 15% is ~4.7 sigma.
  for (int k = 0; k < 9; ++k) {
    EXPECT_NEAR(S(k, k) / C(k, k), 1.0, 0.15)
        << "diag " << k << " S=" << S(k, k) << " C=" << C(k, k);
  }
  // Whitened sample covariance ~ I: off-diagonal entries have std ~ 1/sqrt(N) = 0.022; 0.15 is
  // ~6.7 sigma for each of the 81 entries. This checks the cross-covariances (v-p, R-v, R-p).
  const Eigen::LLT<Eigen::Matrix<double, 9, 9>> llt(C);
  const Eigen::Matrix<double, 9, 9> Linv =
      llt.matrixL().solve(Eigen::Matrix<double, 9, 9>::Identity());
  const Eigen::Matrix<double, 9, 9> W = Linv * S * Linv.transpose();
  EXPECT_LT((W - Eigen::Matrix<double, 9, 9>::Identity()).cwiseAbs().maxCoeff(), 0.15) << W;
  // The cross terms really are there (otherwise the whitened check would be weak): dv-dp are
  // strongly correlated after 0.5 s.
  EXPECT_GT(C(3, 6) / std::sqrt(C(3, 3) * C(6, 6)), 0.5);
  // And the mean error is ~0 (first-order unbiased): |mean| < 4 sigma / sqrt(N).
  for (int k = 0; k < 9; ++k) {
    EXPECT_LT(std::abs(mean[k]), 4.0 * std::sqrt(C(k, k) / kRuns)) << k;
  }
}

// Deterministic counterpart of the Monte-Carlo check, exact to first order at any step length:
// the covariance is sum_k G_k Q_k G_k^T, where G_k is the derivative of the final error
// [Log(dR0^T dR), dv - dv0, dp - dp0] w.r.t. the gyro/accel measurement of step k (numeric
// central differences of a re-integration) and Q_k = density^2 / dt I. A low rate (20 Hz) and a
// fast turn make every block of the error dynamics (A_RR, A_vR, A_pR, A_pv) matter, which a
// 200 Hz Monte-Carlo run cannot resolve.
TEST(ImuPreintegrationTest, CovarianceIsLinearisedNoisePropagation) {
  ImuNoise noise;
  const Eigen::Vector3d bg(0.01, -0.02, 0.015), ba(0.1, 0.2, -0.1);
  std::vector<ImuStep> steps;
  for (int k = 0; k < 20; ++k) {
    const double t = 0.05 * k;
    steps.push_back({0.05, Eigen::Vector3d(0.8 * std::sin(t), 1.2, -0.6 + 0.5 * t),
                     Eigen::Vector3d(2.0 + std::cos(3.0 * t), -1.5, 9.0 + t)});
  }
  const ImuPreintegration pim = test::Preintegrate(steps, noise, bg, ba);
  const Eigen::Quaterniond dq0 = pim.deltas().dq;
  Eigen::Matrix<double, 9, 9> C = Eigen::Matrix<double, 9, 9>::Zero();
  for (size_t k = 0; k < steps.size(); ++k) {
    for (int sensor = 0; sensor < 2; ++sensor) {
      auto f = [&](const Eigen::VectorXd& x) -> Eigen::VectorXd {
        std::vector<ImuStep> moved = steps;
        (sensor == 0 ? moved[k].gyro : moved[k].accel) += x;
        const ImuPreintegration p = test::Preintegrate(moved, noise, bg, ba);
        Eigen::VectorXd e(9);
        e << LogQ<double>(dq0.conjugate() * p.deltas().dq), p.deltas().dv - pim.deltas().dv,
            p.deltas().dp - pim.deltas().dp;
        return e;
      };
      const Eigen::MatrixXd G = test::NumericJacobian(f, Eigen::VectorXd::Zero(3));
      const double density = sensor == 0 ? noise.gyro_noise_density_rad_s_sqrt_hz
                                         : noise.accel_noise_density_m_s2_sqrt_hz;
      C += density * density / steps[k].dt * G * G.transpose();
    }
  }
  const Eigen::Matrix<double, 9, 9>& P = pim.covariance();
  // Relative to each entry's scale sqrt(C_ii C_jj): 1e-6 is far above numeric-difference error.
  for (int r = 0; r < 9; ++r) {
    for (int c = 0; c < 9; ++c) {
      EXPECT_NEAR(P(r, c), C(r, c), 1e-6 * std::sqrt(C(r, r) * C(c, c))) << r << "," << c;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// ImuFactor and PredictBodyState on the true body states of the analytic trajectory, with a
// rotated and offset IMU and non-zero biases.

struct TruthFixture {
  TruthFixture() = default;
  explicit TruthFixture(const AnalyticTrajectory& t) : traj(t) {}
  /// The motion 31 km from the origin of a WGS84 frame at 47.6 N (on the sea surface there, 75 m
  /// below the tangent plane): gravity tilted by 4.8 mrad, the Earth's rate 15 deg/h.
  static TruthFixture Round() {
    return TruthFixture(AnalyticTrajectory(EarthModel(GeoOrigin{47.6, 9.45, 400.0}),
                                           Eigen::Vector3d(25000.0, -18000.0, -75.0)));
  }

  AnalyticTrajectory traj;
  ImuConfig imu = test::RotatedOffsetImu();
  Eigen::Vector3d bg{0.003, -0.002, 0.004};
  Eigen::Vector3d ba{0.05, -0.08, 0.1};
  double t0 = 1.0, t1 = 2.0;

  std::shared_ptr<ImuPreintegration> Pim(double rate_hz) const {
    return std::make_shared<ImuPreintegration>(
        test::Preintegrate(test::IdealImuSteps(traj, t0, t1, rate_hz, bg, ba), imu.noise, bg, ba));
  }
  Eigen::Vector3d GyroAt(double t) const { return traj.gyro(t) + bg; }
  NavState State(double t) const { return traj.BodyState(t, imu, bg, ba); }
  ImuEarthTerms Earth() const { return traj.EarthTerms(t0); }
};

Eigen::Matrix<double, 9, 1> UnwhitenedImuResidual(const TruthFixture& fx,
                                                  double rate_hz,
                                                  const NavState& si,
                                                  const NavState& sj,
                                                  const ImuEarthTerms* earth = nullptr) {
  const ImuFactor factor(*fx.Pim(rate_hz), fx.imu, fx.GyroAt(fx.t0), fx.GyroAt(fx.t1),
                         earth != nullptr ? *earth : fx.Earth());
  Eigen::Matrix<double, 9, 1> r;
  factor(si.q_w_b.coeffs().data(), si.p_w_b.data(), si.v_w.data(), si.bg.data(), si.ba.data(),
         sj.q_w_b.coeffs().data(), sj.p_w_b.data(), sj.v_w.data(), r.data());
  return factor.sqrt_info().fullPivLu().solve(r);
}

// The residual at the true states is only the integration error of the scheme (second order, see
// MatchesAnalyticTrajectory): < 1e-7 rad / 1e-6 m/s / 1e-6 m at 1 kHz, and it converges to zero
// (a quarter when the rate doubles), on the flat Earth and 31 km out on the round one. A wrong
// lever-arm, extrinsic or Earth term would leave a residual that does not converge.
class ImuFactorOnEarth : public ::testing::TestWithParam<bool> {
 protected:
  TruthFixture Fixture() const { return GetParam() ? TruthFixture::Round() : TruthFixture(); }
};

INSTANTIATE_TEST_SUITE_P(FlatAndRound,
                         ImuFactorOnEarth,
                         ::testing::Values(false, true),
                         [](const ::testing::TestParamInfo<bool>& info) {
                           return info.param ? "Round" : "Flat";
                         });

TEST_P(ImuFactorOnEarth, ResidualVanishesAtTrueStates) {
  const TruthFixture fx = Fixture();
  const NavState si = fx.State(fx.t0), sj = fx.State(fx.t1);
  const Eigen::Matrix<double, 9, 1> r500 = UnwhitenedImuResidual(fx, 500.0, si, sj);
  const Eigen::Matrix<double, 9, 1> r1000 = UnwhitenedImuResidual(fx, 1000.0, si, sj);
  EXPECT_LT(r1000.head<3>().norm(), 1e-7) << r1000.transpose();
  EXPECT_LT(r1000.segment<3>(3).norm(), 1e-6) << r1000.transpose();
  if (!GetParam()) {
    // Second-order convergence of the midpoint rule: twice the rate, a quarter of the residual.
    EXPECT_LT(r1000.tail<3>().norm(), 1e-6) << r1000.transpose();
    EXPECT_NEAR(r500.segment<3>(3).norm() / r1000.segment<3>(3).norm(), 4.0, 0.5);
    EXPECT_NEAR(r500.tail<3>().norm() / r1000.tail<3>().norm(), 4.0, 0.5);
  } else {
    // On the round Earth the position residual stops at 1.5e-5 m over this 1 s interval: the
    // trapezoid of the Coriolis double integral and the dp dt / 3 of the Earth's turn are exact
    // for a constant acceleration only (error ~ |W| |a| dt^3 / 6, 1e-8 m over a 0.1 s keyframe
    // interval, against a preintegration sigma of 1e-4 m there).
    EXPECT_LT(r1000.tail<3>().norm(), 3e-5) << r1000.transpose();
  }
  // Sanity: a 1 cm/s velocity error at j shows up one-for-one (rotated into i) in r_v.
  NavState sj_bad = sj;
  sj_bad.v_w += Eigen::Vector3d(0.01, 0.0, 0.0);
  const Eigen::Matrix<double, 9, 1> r_bad = UnwhitenedImuResidual(fx, 1000.0, si, sj_bad);
  EXPECT_NEAR((r_bad - r1000).segment<3>(3).norm(), 0.01, 1e-9);
}

// Whitening: sqrt_info^T sqrt_info = covariance^-1, so the whitened residual of an error e has
// squared norm e^T cov^-1 e (the Mahalanobis distance the solver must see).
TEST(ImuFactorTruthTest, SqrtInfoWhitensThePreintegrationCovariance) {
  const TruthFixture fx;
  const std::shared_ptr<ImuPreintegration> pim = fx.Pim(200.0);
  const ImuFactor factor(*pim, fx.imu, fx.GyroAt(fx.t0), fx.GyroAt(fx.t1), fx.Earth());
  const Eigen::Matrix<double, 9, 9> W =
      factor.sqrt_info() * pim->covariance() * factor.sqrt_info().transpose();
  EXPECT_LT((W - Eigen::Matrix<double, 9, 9>::Identity()).cwiseAbs().maxCoeff(), 1e-6) << W;
  const Eigen::Matrix<double, 9, 9> info = factor.sqrt_info().transpose() * factor.sqrt_info();
  const Eigen::Matrix<double, 9, 9> cov_inv = pim->covariance().inverse();
  EXPECT_LT((info - cov_inv).norm(), 1e-6 * cov_inv.norm());
}

// Gauge: the IMU factor only sees gravity, so a rotation about the world vertical plus a
// translation applied to both states leaves the residual unchanged; a tilt of both states does
// not (it changes the direction of gravity relative to the motion).
TEST(ImuFactorTruthTest, ResidualInvariantToYawAndTranslationGauge) {
  const TruthFixture fx;
  NavState si = fx.State(fx.t0), sj = fx.State(fx.t1);
  // Away from the truth so the residual is not ~0.
  sj.q_w_b = ExpQ<double>(Eigen::Vector3d(0.02, -0.03, 0.05)) * sj.q_w_b;
  sj.p_w_b += Eigen::Vector3d(0.3, -0.2, 0.1);
  sj.v_w += Eigen::Vector3d(0.1, 0.2, -0.1);
  const Eigen::Matrix<double, 9, 1> r0 = UnwhitenedImuResidual(fx, 200.0, si, sj);
  ASSERT_GT(r0.norm(), 0.05);
  auto transformed = [&](const Eigen::Quaterniond& q_g, const Eigen::Vector3d& t_g) {
    NavState a = si, b = sj;
    for (NavState* s : {&a, &b}) {
      s->q_w_b = q_g * s->q_w_b;
      s->p_w_b = q_g * s->p_w_b + t_g;
      s->v_w = q_g * s->v_w;
    }
    return UnwhitenedImuResidual(fx, 200.0, a, b);
  };
  const Eigen::Vector3d t_g(100.0, -50.0, 3.0);
  const Eigen::Quaterniond yaw(Eigen::AngleAxisd(1.1, Eigen::Vector3d::UnitZ()));
  EXPECT_LT((transformed(yaw, t_g) - r0).norm(), 1e-9 * (1.0 + r0.norm()));
  const Eigen::Quaterniond tilt(Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitX()));
  EXPECT_GT((transformed(tilt, t_g) - r0).norm(), 0.1);
}

// On the round Earth the Earth's terms are what keeps the residual at the truth near zero: the
// same factor with the flat terms (no rotation, the origin's gravity) is off by the Coriolis
// acceleration (2 W v ~ 5e-4 m/s^2) and the gravity tilt 31 km out (0.047 m/s^2) over the 1 s.
TEST(ImuFactorTruthTest, RoundEarthNeedsTheEarthTerms) {
  const TruthFixture fx = TruthFixture::Round();
  const NavState si = fx.State(fx.t0), sj = fx.State(fx.t1);
  const Eigen::Matrix<double, 9, 1> r = UnwhitenedImuResidual(fx, 1000.0, si, sj);
  ImuEarthTerms flat;
  flat.gravity.g_ref_w =
      Eigen::Vector3d(0.0, 0.0, -fx.traj.earth().Gravity(Eigen::Vector3d::Zero()).norm());
  const Eigen::Matrix<double, 9, 1> r_flat = UnwhitenedImuResidual(fx, 1000.0, si, sj, &flat);
  EXPECT_LT(r.segment<3>(3).norm(), 2e-3);
  EXPECT_GT(r_flat.segment<3>(3).norm(), 0.04) << r_flat.transpose();
  // The Earth's rate alone: gravity right, no rotation. The gyro's 15 deg/h over 1 s.
  ImuEarthTerms no_rotation = fx.Earth();
  no_rotation.omega_ie_w.setZero();
  const Eigen::Matrix<double, 9, 1> r_still =
      UnwhitenedImuResidual(fx, 1000.0, si, sj, &no_rotation);
  EXPECT_NEAR(r_still.head<3>().norm(), 7.29e-5, 0.1e-5);
  EXPECT_LT(r.head<3>().norm(), 1e-6);
}

TEST_P(ImuFactorOnEarth, PredictBodyStateReproducesTruth) {
  const TruthFixture fx = Fixture();
  const NavState si = fx.State(fx.t0), sj = fx.State(fx.t1);
  const std::shared_ptr<ImuPreintegration> pim = fx.Pim(1000.0);
  Eigen::Quaterniond q;
  Eigen::Vector3d p, v;
  PredictBodyState(*pim, fx.imu, fx.Earth(), fx.GyroAt(fx.t0), fx.GyroAt(fx.t1), si.q_w_b, si.p_w_b,
                   si.v_w, si.bg, si.ba, &q, &p, &v);
  EXPECT_LT(test::AngleBetween(q, sj.q_w_b), 1e-6);
  EXPECT_LT((v - sj.v_w).norm(), 2e-3);
  EXPECT_LT((p - sj.p_w_b).norm(), 1e-3);
  // The predicted state makes the factor residual zero to round-off (prediction and residual are
  // the same model, inverted).
  NavState pred = sj;
  pred.q_w_b = q;
  pred.p_w_b = p;
  pred.v_w = v;
  EXPECT_LT(UnwhitenedImuResidual(fx, 1000.0, si, pred).norm(), 1e-9);
}

// PredictBodyState with biases different from the linearisation point uses the corrected deltas:
// predicting with (bg, ba) from a preintegration linearised elsewhere still lands on the truth to
// second order in the bias offset.
TEST(ImuFactorTruthTest, PredictWithBiasCorrection) {
  TruthFixture fx;
  const std::vector<ImuStep> steps =
      test::IdealImuSteps(fx.traj, fx.t0, fx.t1, 1000.0, fx.bg, fx.ba);
  const Eigen::Vector3d bg_lin = fx.bg + Eigen::Vector3d(1e-3, -1e-3, 5e-4);
  const Eigen::Vector3d ba_lin = fx.ba + Eigen::Vector3d(-0.02, 0.01, 0.03);
  const ImuPreintegration pim = test::Preintegrate(steps, fx.imu.noise, bg_lin, ba_lin);
  const NavState si = fx.State(fx.t0), sj = fx.State(fx.t1);
  Eigen::Quaterniond q;
  Eigen::Vector3d p, v;
  PredictBodyState(pim, fx.imu, fx.Earth(), fx.GyroAt(fx.t0), fx.GyroAt(fx.t1), si.q_w_b, si.p_w_b,
                   si.v_w, fx.bg, fx.ba, &q, &p, &v);
  EXPECT_LT(test::AngleBetween(q, sj.q_w_b), 1e-5);
  EXPECT_LT((v - sj.v_w).norm(), 3e-3);
  EXPECT_LT((p - sj.p_w_b).norm(), 2e-3);
}

}  // namespace
}  // namespace skerry
