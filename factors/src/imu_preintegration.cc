#include "skerry/factors/imu_preintegration.h"

#include <cmath>

#include "skerry/core/so3.h"

namespace skerry {

ImuPreintegration::ImuPreintegration(const ImuNoise& noise,
                                     const Eigen::Vector3d& bg_lin,
                                     const Eigen::Vector3d& ba_lin,
                                     bool gyro_calibration)
    : noise_(noise), has_calibration_(gyro_calibration) {
  d_.bg_lin = bg_lin;
  d_.ba_lin = ba_lin;
}

void ImuPreintegration::Integrate(double dt_s,
                                  const Eigen::Vector3d& gyro_rad_s,
                                  const Eigen::Vector3d& accel_m_s2) {
  if (!(dt_s > 0.0)) return;
  const Eigen::Vector3d w = gyro_rad_s - d_.bg_lin;
  const Eigen::Vector3d a = accel_m_s2 - d_.ba_lin;
  const double dt2 = dt_s * dt_s;
  const Eigen::Matrix3d dR = d_.dq.toRotationMatrix();
  const Eigen::Vector3d phi = w * dt_s;
  // Exp(phi) once, for R_step (ExpSO3 is its rotation matrix) and for the delta rotation below.
  const Eigen::Quaterniond q_step = ExpQ(phi);
  const Eigen::Matrix3d R_step = q_step.toRotationMatrix();
  const Eigen::Matrix3d Jr = RightJacobianSO3(phi);
  // The specific force is rotated with the attitude at the middle of the step, dR Exp(phi / 2):
  // second order in the step (the start attitude, Forster eq. 33-35, is first order; on a hull
  // rolling 3 deg at 8 s that left 0.13 m after 120 s of noise-free 200 Hz data, the midpoint
  // 6 mm; tests/solvers/test_strapdown_round_earth.cc).
  const Eigen::Matrix3d R_half = ExpSO3(0.5 * phi);
  const Eigen::Matrix3d Jr_half = RightJacobianSO3(0.5 * phi);
  const Eigen::Matrix3d dR_mid = dR * R_half;
  const Eigen::Matrix3d dR_mid_a_hat = dR_mid * Hat(a);

  // Covariance of [dphi, dv, dp] (Forster eq. 62-63, with the midpoint rotation). A gyro noise
  // n_g moves dphi by Jr dt n_g and the midpoint attitude by R_half^T dphi + Jr_half dt / 2 n_g.
  Matrix9 A = Matrix9::Identity();
  A.block<3, 3>(kR, kR) = R_step.transpose();
  A.block<3, 3>(kV, kR) = -dR_mid_a_hat * R_half.transpose() * dt_s;
  A.block<3, 3>(kP, kR) = -0.5 * dR_mid_a_hat * R_half.transpose() * dt2;
  A.block<3, 3>(kP, kV) = Eigen::Matrix3d::Identity() * dt_s;
  Eigen::Matrix<double, 9, 3> B_g = Eigen::Matrix<double, 9, 3>::Zero();
  Eigen::Matrix<double, 9, 3> B_a = Eigen::Matrix<double, 9, 3>::Zero();
  B_g.block<3, 3>(kR, 0) = Jr * dt_s;
  B_g.block<3, 3>(kV, 0) = -0.5 * dR_mid_a_hat * Jr_half * dt2;
  B_g.block<3, 3>(kP, 0) = -0.25 * dR_mid_a_hat * Jr_half * dt2 * dt_s;
  B_a.block<3, 3>(kV, 0) = dR_mid * dt_s;
  B_a.block<3, 3>(kP, 0) = 0.5 * dR_mid * dt2;
  // Discrete-time white-noise variances from continuous densities: sigma_d^2 = sigma_c^2 / dt.
  const double var_g =
      noise_.gyro_noise_density_rad_s_sqrt_hz * noise_.gyro_noise_density_rad_s_sqrt_hz / dt_s;
  const double var_a =
      noise_.accel_noise_density_m_s2_sqrt_hz * noise_.accel_noise_density_m_s2_sqrt_hz / dt_s;
  // Coefficient-wise products (lazyProduct): at 9 x 9 Eigen's general product packs its
  // operands for a blocked kernel, which cost more than the arithmetic once per IMU sample.
  const Matrix9 AP = A.lazyProduct(covariance_);
  covariance_ = AP.lazyProduct(A.transpose());
  covariance_ += (var_g * B_g).lazyProduct(B_g.transpose());
  covariance_ += (var_a * B_a).lazyProduct(B_a.transpose());

  // Bias Jacobians (Forster Appendix B, eq. 69-71, with the midpoint rotation, whose right
  // perturbation by a gyro bias change d is (R_half^T J_R_bg - Jr_half dt / 2) d); p and v use
  // the values before this step.
  const Eigen::Matrix3d J_mid_bg = R_half.transpose() * d_.J_R_bg - 0.5 * Jr_half * dt_s;
  d_.J_p_ba += d_.J_v_ba * dt_s - 0.5 * dR_mid * dt2;
  d_.J_p_bg += d_.J_v_bg * dt_s - 0.5 * dR_mid_a_hat * J_mid_bg * dt2;
  d_.J_v_ba -= dR_mid * dt_s;
  d_.J_v_bg -= dR_mid_a_hat * J_mid_bg * dt_s;
  d_.J_R_bg = R_step.transpose() * d_.J_R_bg - Jr * dt_s;
  if (has_calibration_) {
    // The same recursion for the gyro's sensor errors (GyroCalibrationJacobians): the rate
    // changes by -G e with G = w^T (x) I3 where a bias change d changes it by -d.
    GyroCalibrationJacobians& c = calibration_;
    Eigen::Matrix<double, 3, 9> G;
    for (int k = 0; k < 3; ++k) G.middleCols<3>(3 * k) = w[k] * Eigen::Matrix3d::Identity();
    const Eigen::Matrix<double, 3, 9> J_mid = R_half.transpose() * c.J_R - 0.5 * dt_s * Jr_half * G;
    c.J_p += c.J_v * dt_s - 0.5 * dt2 * dR_mid_a_hat * J_mid;
    c.J_v -= dt_s * dR_mid_a_hat * J_mid;
    c.J_R = R_step.transpose() * c.J_R - dt_s * Jr * G;
  }

  // Deltas: p first, then v, then R (each uses the older values).
  d_.dp += d_.dv * dt_s + 0.5 * dR_mid * a * dt2;
  d_.dv += dR_mid * a * dt_s;
  d_.dq = (d_.dq * q_step).normalized();
  d_.dt_s += dt_s;
}

void IntegrateBetween(const ImuSample& a, const ImuSample& b, ImuPreintegration* pim) {
  pim->Integrate(NsToSeconds(b.t_ns - a.t_ns), 0.5 * (a.gyro_rad_s + b.gyro_rad_s),
                 0.5 * (a.accel_m_s2 + b.accel_m_s2));
}

ImuEarthTerms EarthTermsNear(const EarthModel& earth, const Eigen::Vector3d& p_w) {
  ImuEarthTerms terms;
  terms.omega_ie_w = earth.omega_ie_w();
  terms.gravity = earth.GravityNear(p_w);
  return terms;
}

void PredictBodyState(const ImuPreintegration& pim,
                      const ImuConfig& imu,
                      const ImuEarthTerms& earth,
                      const Eigen::Vector3d& gyro_start_rad_s,
                      const Eigen::Vector3d& gyro_end_rad_s,
                      const Eigen::Quaterniond& q_w_b_i,
                      const Eigen::Vector3d& p_w_b_i,
                      const Eigen::Vector3d& v_w_b_i,
                      const Eigen::Vector3d& bg,
                      const Eigen::Vector3d& ba,
                      Eigen::Quaterniond* q_w_b_j,
                      Eigen::Vector3d* p_w_b_j,
                      Eigen::Vector3d* v_w_b_j,
                      const double* gyro_calibration) {
  const Eigen::Vector3d& W = earth.omega_ie_w;
  const ImuKinematics<double> imu_i =
      BodyToImu<double>(q_w_b_i, p_w_b_i, v_w_b_i, bg, gyro_start_rad_s, imu, W);
  Eigen::Quaterniond dq;
  Eigen::Vector3d dv, dp;
  if (gyro_calibration != nullptr && pim.gyro_calibration() == nullptr) {
    throw std::invalid_argument(
        "PredictBodyState: a gyro calibration needs a preintegration with its Jacobians");
  }
  pim.deltas().Corrected<double>(bg, ba, pim.gyro_calibration(), gyro_calibration, &dq, &dv, &dp);
  const double dt = pim.deltas().dt_s;
  const Eigen::Matrix3d R_i = imu_i.q_w_i.toRotationMatrix();
  const Eigen::Matrix3d W_hat = Hat(W);
  // The mechanisation of ImuFactor solved for state j (see there):
  //   R_j = Exp(-W dt) R_i dR
  //   (I + [W]x dt) (p_j - p_i) = v_i dt + g dt^2 / 2 + R_i dp - [W]x R_i dp dt / 3
  //   v_j = v_i + g dt - 2 W x (p_j - p_i) + R_i dv - [W]x R_i (dt dv - dp)
  // with g at the midpoint of the interval; two passes settle it (g moves by 1.5e-6 m/s^2 per
  // metre of displacement, so the second pass changes p_j by ~1e-8 dt^2).
  const Eigen::Quaterniond q_w_i_j =
      (ExpQ(Eigen::Vector3d(-W * dt)) * imu_i.q_w_i * dq).normalized();
  const Eigen::Matrix3d A = Eigen::Matrix3d::Identity() + W_hat * dt;
  Eigen::Vector3d g = earth.gravity.At<double>(imu_i.p_w_i);
  Eigen::Vector3d dp_w = Eigen::Vector3d::Zero();
  for (int pass = 0; pass < 2; ++pass) {
    const Eigen::Vector3d b =
        imu_i.v_w_i * dt + 0.5 * g * dt * dt + R_i * dp - W_hat * (R_i * dp) * (dt / 3.0);
    dp_w = A.lu().solve(b);
    g = earth.gravity.At<double>(Eigen::Vector3d(imu_i.p_w_i + 0.5 * dp_w));
  }
  const Eigen::Vector3d p_w_i_j = imu_i.p_w_i + dp_w;
  const Eigen::Vector3d v_w_i_j =
      imu_i.v_w_i + g * dt - 2.0 * W.cross(dp_w) + R_i * dv - W_hat * (R_i * (dt * dv - dp));
  // Back to the body: invert BodyToImu at j.
  const Eigen::Quaterniond q_i_b = imu.q_b_i.conjugate();
  *q_w_b_j = (q_w_i_j * q_i_b).normalized();
  *p_w_b_j = p_w_i_j - (*q_w_b_j) * imu.p_b_i;
  const Eigen::Vector3d omega_b = imu.q_b_i * (gyro_end_rad_s - bg) - q_w_b_j->conjugate() * W;
  *v_w_b_j = v_w_i_j - (*q_w_b_j) * omega_b.cross(imu.p_b_i);
}

}  // namespace skerry
