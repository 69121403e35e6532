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
  // The transition is block lower-triangular with identities,
  //   A = [R_step^T 0 0; A_vr I 0; A_pr dt I I],
  // with A_vr = -dR_mid [a]x R_half^T dt and A_pr = dt/2 A_vr. The noise enters by
  //   B_g = [Jr dt; B_gv; dt/2 B_gv],  B_gv = -dR_mid [a]x Jr_half dt^2 / 2,
  //   B_a = [0; dR_mid dt; dt/2 dR_mid dt].
  // So A P A^T + B Q B^T is taken 3x3 block by block (the upper blocks, then mirrored): a third
  // of the dense 9x9 products' arithmetic, once per IMU sample in the window and again in the
  // batch.
  const Eigen::Matrix3d Rt = R_step.transpose();
  const Eigen::Matrix3d A_vr = -(dR_mid_a_hat * R_half.transpose()) * dt_s;
  const Eigen::Matrix3d A_pr = 0.5 * dt_s * A_vr;
  const Eigen::Matrix3d B_gr = Jr * dt_s;
  const Eigen::Matrix3d B_gv = -0.5 * dt2 * (dR_mid_a_hat * Jr_half);
  const Eigen::Matrix3d B_gp = 0.5 * dt_s * B_gv;
  const Eigen::Matrix3d B_av = dR_mid * dt_s;
  const Eigen::Matrix3d B_ap = 0.5 * dt_s * B_av;
  // Discrete-time white-noise variances from continuous densities: sigma_d^2 = sigma_c^2 / dt.
  const double var_g =
      noise_.gyro_noise_density_rad_s_sqrt_hz * noise_.gyro_noise_density_rad_s_sqrt_hz / dt_s;
  const double var_a =
      noise_.accel_noise_density_m_s2_sqrt_hz * noise_.accel_noise_density_m_s2_sqrt_hz / dt_s;
  {
    Matrix9& P = covariance_;
    const auto blk = [&P](int i, int j) -> Eigen::Matrix3d { return P.block<3, 3>(i, j); };
    const Eigen::Matrix3d P_rr = blk(kR, kR), P_rv = blk(kR, kV), P_rp = blk(kR, kP);
    const Eigen::Matrix3d P_vr = blk(kV, kR), P_vv = blk(kV, kV), P_vp = blk(kV, kP);
    const Eigen::Matrix3d P_pr = blk(kP, kR), P_pv = blk(kP, kV), P_pp = blk(kP, kP);
    // X = A P, row block by row block.
    const Eigen::Matrix3d X_rr = Rt * P_rr, X_rv = Rt * P_rv, X_rp = Rt * P_rp;
    const Eigen::Matrix3d X_vr = A_vr * P_rr + P_vr, X_vv = A_vr * P_rv + P_vv,
                          X_vp = A_vr * P_rp + P_vp;
    const Eigen::Matrix3d X_pr = A_pr * P_rr + dt_s * P_vr + P_pr;
    const Eigen::Matrix3d X_pv = A_pr * P_rv + dt_s * P_vv + P_pv;
    const Eigen::Matrix3d X_pp = A_pr * P_rp + dt_s * P_vp + P_pp;
    // X A^T + B_g Q_g B_g^T + B_a Q_a B_a^T, the upper blocks.
    const Eigen::Matrix3d N_rr = X_rr * Rt.transpose() + var_g * B_gr * B_gr.transpose();
    const Eigen::Matrix3d N_rv = X_rr * A_vr.transpose() + X_rv + var_g * B_gr * B_gv.transpose();
    const Eigen::Matrix3d N_rp =
        X_rr * A_pr.transpose() + dt_s * X_rv + X_rp + var_g * B_gr * B_gp.transpose();
    const Eigen::Matrix3d N_vv = X_vr * A_vr.transpose() + X_vv + var_g * B_gv * B_gv.transpose() +
                                 var_a * B_av * B_av.transpose();
    const Eigen::Matrix3d N_vp = X_vr * A_pr.transpose() + dt_s * X_vv + X_vp +
                                 var_g * B_gv * B_gp.transpose() + var_a * B_av * B_ap.transpose();
    const Eigen::Matrix3d N_pp = X_pr * A_pr.transpose() + dt_s * X_pv + X_pp +
                                 var_g * B_gp * B_gp.transpose() + var_a * B_ap * B_ap.transpose();
    P.block<3, 3>(kR, kR) = N_rr;
    P.block<3, 3>(kR, kV) = N_rv;
    P.block<3, 3>(kR, kP) = N_rp;
    P.block<3, 3>(kV, kR) = N_rv.transpose();
    P.block<3, 3>(kV, kV) = N_vv;
    P.block<3, 3>(kV, kP) = N_vp;
    P.block<3, 3>(kP, kR) = N_rp.transpose();
    P.block<3, 3>(kP, kV) = N_vp.transpose();
    P.block<3, 3>(kP, kP) = N_pp;
  }

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
