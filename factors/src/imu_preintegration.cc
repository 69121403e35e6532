#include "skerry/factors/imu_preintegration.h"

#include <cmath>

#include "skerry/core/so3.h"

namespace skerry {

ImuPreintegration::ImuPreintegration(const ImuNoise& noise,
                                     const Eigen::Vector3d& bg_lin,
                                     const Eigen::Vector3d& ba_lin)
    : noise_(noise), bg_lin_(bg_lin), ba_lin_(ba_lin) {}

void ImuPreintegration::Integrate(double dt_s,
                                  const Eigen::Vector3d& gyro_rad_s,
                                  const Eigen::Vector3d& accel_m_s2) {
  if (!(dt_s > 0.0)) return;
  const Eigen::Vector3d w = gyro_rad_s - bg_lin_;
  const Eigen::Vector3d a = accel_m_s2 - ba_lin_;
  const double dt2 = dt_s * dt_s;
  const Eigen::Matrix3d dR = delta_q_.toRotationMatrix();
  const Eigen::Matrix3d dR_a_hat = dR * Hat(a);
  const Eigen::Vector3d phi = w * dt_s;
  const Eigen::Matrix3d R_step = ExpSO3(phi);
  const Eigen::Matrix3d Jr = RightJacobianSO3(phi);

  // Covariance of [dphi, dv, dp], Forster eq. (62)-(63) (A and B of the error dynamics).
  Matrix9 A = Matrix9::Identity();
  A.block<3, 3>(kR, kR) = R_step.transpose();
  A.block<3, 3>(kV, kR) = -dR_a_hat * dt_s;
  A.block<3, 3>(kP, kR) = -0.5 * dR_a_hat * dt2;
  A.block<3, 3>(kP, kV) = Eigen::Matrix3d::Identity() * dt_s;
  Eigen::Matrix<double, 9, 3> B_g = Eigen::Matrix<double, 9, 3>::Zero();
  Eigen::Matrix<double, 9, 3> B_a = Eigen::Matrix<double, 9, 3>::Zero();
  B_g.block<3, 3>(kR, 0) = Jr * dt_s;
  B_a.block<3, 3>(kV, 0) = dR * dt_s;
  B_a.block<3, 3>(kP, 0) = 0.5 * dR * dt2;
  // Discrete-time white-noise variances from continuous densities: sigma_d^2 = sigma_c^2 / dt.
  const double var_g =
      noise_.gyro_noise_density_rad_s_sqrt_hz * noise_.gyro_noise_density_rad_s_sqrt_hz / dt_s;
  const double var_a =
      noise_.accel_noise_density_m_s2_sqrt_hz * noise_.accel_noise_density_m_s2_sqrt_hz / dt_s;
  covariance_ = A * covariance_ * A.transpose() + var_g * B_g * B_g.transpose() +
                var_a * B_a * B_a.transpose();

  // Bias Jacobians, Forster Appendix B (eq. 69-71); p and v use the values before this step.
  J_p_ba_ += J_v_ba_ * dt_s - 0.5 * dR * dt2;
  J_p_bg_ += J_v_bg_ * dt_s - 0.5 * dR_a_hat * J_R_bg_ * dt2;
  J_v_ba_ -= dR * dt_s;
  J_v_bg_ -= dR_a_hat * J_R_bg_ * dt_s;
  J_R_bg_ = R_step.transpose() * J_R_bg_ - Jr * dt_s;

  // Deltas, Forster eq. (33)-(35): p first, then v, then R (each uses the older values).
  delta_p_ += delta_v_ * dt_s + 0.5 * dR * a * dt2;
  delta_v_ += dR * a * dt_s;
  delta_q_ = (delta_q_ * ExpQ(phi)).normalized();
  dt_s_ += dt_s;
}

void IntegrateBetween(const ImuSample& a, const ImuSample& b, ImuPreintegration* pim) {
  pim->Integrate(NsToSeconds(b.t_ns - a.t_ns), 0.5 * (a.gyro_rad_s + b.gyro_rad_s),
                 0.5 * (a.accel_m_s2 + b.accel_m_s2));
}

void PredictBodyState(const ImuPreintegration& pim,
                      const ImuConfig& imu,
                      const Eigen::Vector3d& gyro_start_rad_s,
                      const Eigen::Vector3d& gyro_end_rad_s,
                      const Eigen::Quaterniond& q_w_b_i,
                      const Eigen::Vector3d& p_w_b_i,
                      const Eigen::Vector3d& v_w_b_i,
                      const Eigen::Vector3d& bg,
                      const Eigen::Vector3d& ba,
                      Eigen::Quaterniond* q_w_b_j,
                      Eigen::Vector3d* p_w_b_j,
                      Eigen::Vector3d* v_w_b_j) {
  const ImuKinematics<double> imu_i =
      BodyToImu<double>(q_w_b_i, p_w_b_i, v_w_b_i, bg, gyro_start_rad_s, imu);
  Eigen::Quaterniond dq;
  Eigen::Vector3d dv, dp;
  pim.CorrectedDeltas<double>(bg, ba, &dq, &dv, &dp);
  const Eigen::Vector3d g_w(0.0, 0.0, -imu.gravity_m_s2);
  const double dt = pim.dt_s();
  // Forster eq. (38), in the IMU frame.
  const Eigen::Quaterniond q_w_i_j = (imu_i.q_w_i * dq).normalized();
  const Eigen::Vector3d v_w_i_j = imu_i.v_w_i + g_w * dt + imu_i.q_w_i * dv;
  const Eigen::Vector3d p_w_i_j =
      imu_i.p_w_i + imu_i.v_w_i * dt + 0.5 * g_w * dt * dt + imu_i.q_w_i * dp;
  // Back to the body: invert BodyToImu at j.
  const Eigen::Quaterniond q_i_b = imu.q_b_i.conjugate();
  *q_w_b_j = (q_w_i_j * q_i_b).normalized();
  *p_w_b_j = p_w_i_j - (*q_w_b_j) * imu.p_b_i;
  const Eigen::Vector3d omega_b = imu.q_b_i * (gyro_end_rad_s - bg);
  *v_w_b_j = v_w_i_j - (*q_w_b_j) * omega_b.cross(imu.p_b_i);
}

}  // namespace skerry
