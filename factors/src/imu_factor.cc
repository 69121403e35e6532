#include "skerry/factors/imu_factor.h"

#include <ceres/autodiff_cost_function.h>
#include <ceres/sized_cost_function.h>

#include <Eigen/Cholesky>

#include "skerry/factors/factor_linearization.h"

namespace skerry {
namespace {

using Mat3 = Eigen::Matrix3d;
using Vec3 = Eigen::Vector3d;
using Mat93 = Eigen::Matrix<double, 9, 3>;
constexpr int kR = ImuPreintegration::kR, kV = ImuPreintegration::kV, kP = ImuPreintegration::kP;

/// Ceres' view of ImuFactor with the Jacobians by hand: a thin adapter, `Blocks` the sizes after
/// the first (eight blocks, or nine with the gyro's calibration).
template <int... Blocks>
class ImuCostFunctionOf final : public ceres::SizedCostFunction<9, 4, Blocks...> {
 public:
  explicit ImuCostFunctionOf(ImuFactor factor) : factor_(std::move(factor)) {}
  bool Evaluate(double const* const* parameters,
                double* residual,
                double** jacobians) const override {
    return factor_.EvaluateWithJacobians(parameters, residual, jacobians);
  }

 private:
  ImuFactor factor_;
};
using ImuCostFunction = ImuCostFunctionOf<3, 3, 3, 3, 4, 3, 3>;
using CalibratedImuCostFunction = ImuCostFunctionOf<3, 3, 3, 3, 4, 3, 3, 9>;

/// Writes a tangent Jacobian (left, world-frame rotation vector theta) of a quaternion block as
/// the ambient 9x4 Ceres expects: J_amb = 4 J_theta P^T with P = d(Exp(theta) q)/d theta
/// (QuaternionLeftPlusJacobian). P^T P = I/4, so J_amb P = J_theta (LinearizeResidual's
/// convention); the EigenQuaternionManifold's PlusJacobian is 2 P (its delta is half the angle),
/// so Ceres sees 2 J_theta = d r / d delta. P^T q = 0: no component along q.
void WriteQuaternionJacobian(const Mat93& J_theta, const double* q_xyzw, double* out) {
  Eigen::Map<Eigen::Matrix<double, 9, 4, Eigen::RowMajor>> J(out);
  J = 4.0 * J_theta * QuaternionLeftPlusJacobian(q_xyzw).transpose();
}

/// ImuFactor::Residual with nine blocks, for automatic differentiation.
struct CalibratedImuResidual {
  explicit CalibratedImuResidual(ImuFactor f) : factor(std::move(f)) {}
  ImuFactor factor;
  template <typename T>
  bool operator()(const T* q_i,
                  const T* p_i,
                  const T* v_i,
                  const T* bg,
                  const T* ba,
                  const T* q_j,
                  const T* p_j,
                  const T* v_j,
                  const T* e,
                  T* residual) const {
    return factor.Residual<T>(q_i, p_i, v_i, bg, ba, q_j, p_j, v_j, e, residual);
  }
};

void WriteJacobian(const Mat93& J, double* out) {
  Eigen::Map<Eigen::Matrix<double, 9, 3, Eigen::RowMajor>> J_out(out);
  J_out = J;
}

}  // namespace

ImuFactor::ImuFactor(const ImuPreintegration& pim,
                     const ImuConfig& imu,
                     const Eigen::Vector3d& gyro_start_rad_s,
                     const Eigen::Vector3d& gyro_end_rad_s,
                     const ImuEarthTerms& earth,
                     bool calibrated)
    : deltas_(pim.deltas()),
      imu_(imu),
      gyro_start_rad_s_(gyro_start_rad_s),
      gyro_end_rad_s_(gyro_end_rad_s),
      earth_(earth),
      earth_turn_(ExpQ(Eigen::Vector3d(earth.omega_ie_w * deltas_.dt_s))) {
  if (calibrated) {
    if (pim.gyro_calibration() == nullptr) {
      throw std::invalid_argument(
          "ImuFactor: a calibrated factor needs a preintegration with the gyro calibration "
          "Jacobians");
    }
    calibration_ = std::make_shared<const GyroCalibrationJacobians>(*pim.gyro_calibration());
  }
  // Whiten once: sqrt_info^T sqrt_info = cov^-1, sqrt_info = L^-1 for cov = L L^T. A tiny
  // diagonal floor keeps very short intervals well conditioned.
  Eigen::Matrix<double, 9, 9> cov = pim.covariance();
  cov.diagonal().array() += 1e-14;
  const Eigen::LLT<Eigen::Matrix<double, 9, 9>> llt(cov);
  const Eigen::Matrix<double, 9, 9> L =
      llt.matrixL().solve(Eigen::Matrix<double, 9, 9>::Identity());
  for (int i = 0, n = 0; i < 9; ++i) {
    for (int j = 0; j <= i; ++j) sqrt_info_lower_[n++] = L(i, j);
  }
}

Eigen::Matrix<double, 9, 9> ImuFactor::sqrt_info() const {
  Eigen::Matrix<double, 9, 9> L = Eigen::Matrix<double, 9, 9>::Zero();
  for (int i = 0, n = 0; i < 9; ++i) {
    for (int j = 0; j <= i; ++j) L(i, j) = sqrt_info_lower_[n++];
  }
  return L;
}

// The residual of operator() in double, then its Jacobians. Notation: body states (R_b, p_b,
// v_b) at i and j, the IMU's extrinsics R_bI = q_b_i and lever arm l_b = p_b_i; BodyToImu gives
// the IMU's R = R_b R_bI, p = p_b + R_b l_b, v = v_b + u with u = R_b (omega_b x l_b) and
// omega_b = R_bI (gyro - bg) - R_b^T W. Every rotation is perturbed on the left in the world,
// R_b <- Exp(theta) R_b, which moves R = R_b R_bI by the same Exp(theta).
bool ImuFactor::EvaluateWithJacobians(double const* const* parameters,
                                      double* residual,
                                      double** jacobians) const {
  const Eigen::Map<const Eigen::Quaterniond> qb_i(parameters[0]), qb_j(parameters[5]);
  const Eigen::Map<const Vec3> pb_i(parameters[1]), vb_i(parameters[2]);
  const Eigen::Map<const Vec3> bg(parameters[3]), ba(parameters[4]);
  const Eigen::Map<const Vec3> pb_j(parameters[6]), vb_j(parameters[7]);
  const Vec3& W = earth_.omega_ie_w;

  // The IMU's states (BodyToImu), and the world lever arm l and its velocity u they add.
  const ImuKinematics<double> ki =
      BodyToImu<double>(qb_i, pb_i, vb_i, bg, gyro_start_rad_s_, imu_, W);
  const ImuKinematics<double> kj =
      BodyToImu<double>(qb_j, pb_j, vb_j, bg, gyro_end_rad_s_, imu_, W);
  const Eigen::Quaterniond &q_i = ki.q_w_i, &q_j = kj.q_w_i;
  const Vec3 &p_i = ki.p_w_i, &p_j = kj.p_w_i, &v_i = ki.v_w_i, &v_j = kj.v_w_i;
  const Vec3 l_i = p_i - pb_i, l_j = p_j - pb_j, u_i = v_i - vb_i, u_j = v_j - vb_j;
  const Mat3 R_bI = imu_.q_b_i.toRotationMatrix();
  const Vec3& l_b = imu_.p_b_i;

  Eigen::Quaterniond dq;
  Vec3 dv, dp;
  const double* e = calibration_ ? parameters[8] : nullptr;
  deltas_.Corrected<double>(bg, ba, calibration_.get(), e, &dq, &dv, &dp);  // Forster eq. (44)
  Vec3 phi_b = deltas_.J_R_bg * (bg - deltas_.bg_lin);
  if (calibration_) phi_b += calibration_->J_R * Eigen::Map<const Eigen::Matrix<double, 9, 1>>(e);

  const double dt = deltas_.dt_s;
  const Vec3 dp_w = p_j - p_i;
  const Vec3 g_w = earth_.gravity.At<double>(Vec3(0.5 * (p_i + p_j)));
  const Mat3 W_hat = Hat(W);
  const Vec3 W_x_dp = W_hat * dp_w;
  const Mat3 Ri_T = q_i.toRotationMatrix().transpose();
  const Vec3 omega_i = Ri_T * W;
  const Vec3 c = dt * dv - dp;
  const Vec3 a_v = v_j - v_i - g_w * dt + 2.0 * W_x_dp;
  const Vec3 a_p = dp_w - v_i * dt - 0.5 * g_w * dt * dt + W_x_dp * dt;
  const Eigen::Quaterniond q_err = dq.conjugate() * (q_i.conjugate() * (earth_turn_ * q_j));
  Eigen::Matrix<double, 9, 1> r;
  r.segment<3>(kR) = LogQ<double>(q_err);
  r.segment<3>(kV) = Ri_T * a_v + omega_i.cross(c) - dv;
  r.segment<3>(kP) = Ri_T * a_p + omega_i.cross(dp) * (dt / 3.0) - dp;
  const Eigen::Matrix<double, 9, 9> sqrt_info_full = sqrt_info();
  const auto L = sqrt_info_full.triangularView<Eigen::Lower>();
  Eigen::Map<Eigen::Matrix<double, 9, 1>> whitened_r(residual);
  whitened_r = L * r;
  if (jacobians == nullptr) return true;

  // Partials of r with respect to the IMU's states (A_*) and the corrected deltas. With
  // [a]x b = -[b]x a and d(R_i^T a)/d theta_i = R_i^T [a]x, d omega_i / d theta_i = R_i^T [W]x.
  const Mat3 I = Mat3::Identity();
  const Mat3 Jr_inv = RightJacobianInverseSO3(r.segment<3>(kR));
  const Mat3 Rj_T = q_j.toRotationMatrix().transpose();
  const Mat3 G = earth_.gravity.dg_dp;  // g at the midpoint: d g / d p_i = d g / d p_j = G / 2
  const Mat3 Ri_T_W = Ri_T * W_hat;
  const Mat3 omega_hat = Hat(omega_i);

  Mat93 A_Ri, A_Rj, A_pi, A_pj, A_vi, A_vj, A_bg, A_ba;
  A_Ri << -Jr_inv * Rj_T * earth_turn_.toRotationMatrix().transpose(),
      Ri_T * Hat(a_v) - Hat(c) * Ri_T_W,  //
      Ri_T * Hat(a_p) - Hat(dp) * Ri_T_W * (dt / 3.0);
  A_Rj << Jr_inv * Rj_T, Mat3::Zero(), Mat3::Zero();
  A_pi << Mat3::Zero(), Ri_T * (-0.5 * dt * G - 2.0 * W_hat),
      Ri_T * (-I - 0.25 * dt * dt * G - dt * W_hat);
  A_pj << Mat3::Zero(), Ri_T * (-0.5 * dt * G + 2.0 * W_hat),
      Ri_T * (I - 0.25 * dt * dt * G + dt * W_hat);
  A_vi << Mat3::Zero(), -Ri_T, -dt * Ri_T;
  A_vj << Mat3::Zero(), Ri_T, Mat3::Zero();
  // The biases through the corrected deltas: d r_v / d dv = dt [omega_i]x - I,
  // d r_v / d dp = -[omega_i]x, d r_p / d dp = (dt / 3) [omega_i]x - I.
  const Mat3 rv_dv = dt * omega_hat - I, rp_dp = (dt / 3.0) * omega_hat - I;
  // d r_R / d phi_b for the rotation correction phi_b (Forster Appendix C, eq. 44).
  const Mat3 rR_phi = -Jr_inv * ExpSO3(r.segment<3>(kR)).transpose() * RightJacobianSO3(phi_b);
  A_bg << rR_phi * deltas_.J_R_bg, rv_dv * deltas_.J_v_bg - omega_hat * deltas_.J_p_bg,
      rp_dp * deltas_.J_p_bg;
  A_ba << Mat3::Zero(), rv_dv * deltas_.J_v_ba - omega_hat * deltas_.J_p_ba, rp_dp * deltas_.J_p_ba;

  // Through BodyToImu: d p / d theta = -[l]x; d u / d theta = -[u]x + [l]x [W]x (u turns with
  // R_b, and omega_b's Earth term moves by -R_b^T [W]x theta); d u / d bg = R_b [l_b]x R_bI.
  const auto body = [&](const Mat93& A_R, const Mat93& A_p, const Mat93& A_v, const Vec3& l,
                        const Vec3& u) -> Mat93 {
    return A_R - A_p * Hat(l) + A_v * (Hat(l) * W_hat - Hat(u));
  };
  const Mat3 l_b_hat_R_bI = Hat(l_b) * R_bI;
  const auto write = [&](int k, const Mat93& J) {
    if (jacobians[k] == nullptr) return;
    const Mat93 whitened = sqrt_info_full.lazyProduct(J);  // L J (zeros above the diagonal)
    if (k == 0 || k == 5) {
      WriteQuaternionJacobian(whitened, parameters[k], jacobians[k]);
    } else {
      WriteJacobian(whitened, jacobians[k]);
    }
  };
  write(0, body(A_Ri, A_pi, A_vi, l_i, u_i));
  write(1, A_pi);
  write(2, A_vi);
  write(3, Mat93(A_bg + A_vi * qb_i.toRotationMatrix() * l_b_hat_R_bI +
                 A_vj * qb_j.toRotationMatrix() * l_b_hat_R_bI));
  write(4, A_ba);
  write(5, body(A_Rj, A_pj, A_vj, l_j, u_j));
  write(6, A_pj);
  write(7, A_vj);
  if (calibration_ && jacobians[8] != nullptr) {
    // The gyro's sensor errors enter through the deltas exactly as the gyro bias does.
    const GyroCalibrationJacobians& c = *calibration_;
    Eigen::Matrix<double, 9, 9> A_e;
    A_e << rR_phi * c.J_R, rv_dv * c.J_v - omega_hat * c.J_p, rp_dp * c.J_p;
    Eigen::Map<Eigen::Matrix<double, 9, 9, Eigen::RowMajor>> J_e(jacobians[8]);
    J_e = sqrt_info_full.lazyProduct(A_e);
  }
  return true;
}

std::unique_ptr<ceres::CostFunction> ImuFactor::Create(const ImuPreintegration& pim,
                                                       const ImuConfig& imu,
                                                       const Eigen::Vector3d& gyro_start_rad_s,
                                                       const Eigen::Vector3d& gyro_end_rad_s,
                                                       const ImuEarthTerms& earth) {
  return std::make_unique<ImuCostFunction>(
      ImuFactor(pim, imu, gyro_start_rad_s, gyro_end_rad_s, earth));
}

std::unique_ptr<ceres::CostFunction> ImuFactor::CreateCalibrated(
    const ImuPreintegration& pim,
    const ImuConfig& imu,
    const Eigen::Vector3d& gyro_start_rad_s,
    const Eigen::Vector3d& gyro_end_rad_s,
    const ImuEarthTerms& earth) {
  return std::make_unique<CalibratedImuCostFunction>(
      ImuFactor(pim, imu, gyro_start_rad_s, gyro_end_rad_s, earth, /*calibrated=*/true));
}

std::unique_ptr<ceres::CostFunction> ImuFactor::CreateCalibratedAutoDiff(
    const ImuPreintegration& pim,
    const ImuConfig& imu,
    const Eigen::Vector3d& gyro_start_rad_s,
    const Eigen::Vector3d& gyro_end_rad_s,
    const ImuEarthTerms& earth) {
  return std::make_unique<
      ceres::AutoDiffCostFunction<CalibratedImuResidual, 9, 4, 3, 3, 3, 3, 4, 3, 3, 9>>(
      new CalibratedImuResidual(
          ImuFactor(pim, imu, gyro_start_rad_s, gyro_end_rad_s, earth, /*calibrated=*/true)));
}

std::unique_ptr<ceres::CostFunction> ImuFactor::CreateAutoDiff(
    const ImuPreintegration& pim,
    const ImuConfig& imu,
    const Eigen::Vector3d& gyro_start_rad_s,
    const Eigen::Vector3d& gyro_end_rad_s,
    const ImuEarthTerms& earth) {
  return std::make_unique<ceres::AutoDiffCostFunction<ImuFactor, 9, 4, 3, 3, 3, 3, 4, 3, 3>>(
      new ImuFactor(pim, imu, gyro_start_rad_s, gyro_end_rad_s, earth));
}

}  // namespace skerry
