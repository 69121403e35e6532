#pragma once
/// \file
/// Preintegrated IMU factor between two consecutive keyframes, on a round, rotating Earth.
///
/// In the Earth-fixed world frame w (earth_model.h) the IMU's attitude, velocity and position obey
///   dR/dt = R [omega_ib]x - [W]x R,   dv/dt = R f + g(p) - 2 W x v,   dp/dt = v
/// with W = omega_ie_w constant. Integrating over [t_i, t_j] (dt = t_j - t_i) with the
/// preintegrated dR, dv, dp of the measurements (Forster et al. T-RO 2017, eq. 33-35, 44):
///   R_j = Exp(-W dt) R_i dR            exactly, since W is constant in w;
///   int R f = R_i dv - [W]x R_i (dt dv - dp)
///                                      Exp(-W t) ~ I - [W]x t and int t dR f = dt dv - dp;
///   int 2 W x v = 2 W x (p_j - p_i)    exactly (int v = p_j - p_i);
///   double integrals: R_i dp - [W]x R_i dp dt/3 and W x (p_j - p_i) dt (trapezoid);
///   gravity at the midpoint, g((p_i + p_j) / 2), to first order about the start (LocalGravity).
/// Left out: (W dt)^2 terms (5e-11 at dt = 0.1 s) and the gravity gradient's curvature along the
/// interval (1e-12 m/s^2). The residual, with omega_i = R_i^T W and dp_w = p_j - p_i:
///
///   r = sqrt_info * [ r_R; r_v; r_p ],
///   r_R = Log( dR(bg)^T R_i^T Exp(W dt) R_j ),
///   r_v = R_i^T (v_j - v_i - g dt + 2 W x dp_w) + [omega_i]x (dt dv - dp) - dv(bg, ba),
///   r_p = R_i^T (dp_w - v_i dt - g dt^2/2 + W x dp_w dt) + [omega_i]x dp dt/3 - dp(bg, ba)
///
/// For W = 0 and constant g it is Forster eq. (45). The GTSAM analogue is
/// the first-order `omegaCoriolis` correction of NavState::correctPIM (which uses v_i dt for the
/// travelled distance and a constant gravity); here the Coriolis term uses the states' actual
/// displacement and gravity follows the position. The states are body states; R_i, p_i, v_i are
/// those of the IMU frame/point (BodyToImu, with the body rate relative to the Earth).
/// sqrt_info = L^-1 for the preintegration covariance cov = L L^T (lower triangular), computed
/// once at construction.
///
/// Parameter blocks: q_w_b(i)[4], p_w_b(i)[3], v_w(i)[3], bg(i)[3], ba(i)[3], q_w_b(j)[4],
/// p_w_b(j)[3], v_w(j)[3]. Biases are held constant over the interval (the bias random-walk
/// factor links bg/ba of i and j). A calibrated factor (CreateCalibrated) takes a ninth block,
/// the gyro's sensor errors e[9] (GyroCalibrationJacobians: scale factors and misalignment, one
/// value for the run), and corrects the deltas for them to first order as for the biases:
///   dR(bg, e) = dR Exp(J_R_bg dbg + J_R e),  dv(bg, ba, e) = ... + J_v e,  dp = ... + J_p e.
/// The lever-arm velocity's rate (BodyToImu) is left uncorrected: E omega x l is ~1e-5 m/s for
/// E ~ 1e-4, a 0.1 rad/s rate and a 1 m arm.
///
/// Jacobians. `Create` gives the residual with analytic Jacobians (EvaluateWithJacobians). Those
/// of r_R are Forster's Appendix C (Jacobians of the residual errors) for left, world-frame
/// rotation vectors theta (R <- Exp(theta) R) and the Earth's turn E = Exp(W dt):
///   d r_R / d theta_j = Jr^-1(r_R) R_j^T,   d r_R / d theta_i = -Jr^-1(r_R) R_j^T E^T,
///   d r_R / d bg      = -Jr^-1(r_R) Exp(r_R)^T Jr(J_R_bg dbg) J_R_bg      (with eq. 44);
/// r_v and r_p are linear in p, v and the corrected deltas and bilinear in R_i^T and W; the
/// lever arm enters through BodyToImu (imu_factor.cc derives each block). `CreateAutoDiff` gives
/// the same residual through Ceres' automatic differentiation of operator(): the reference the
/// analytic Jacobians are tested against (tests/factors/test_factor_jacobians.cc) and timed
/// against (bench/factor_benchmarks.cc).

#include <ceres/cost_function.h>

#include <array>
#include <memory>

#include "skerry/core/constant_product.h"
#include "skerry/core/so3.h"
#include "skerry/factors/imu_preintegration.h"

namespace skerry {

class ImuFactor {
 public:
  static constexpr int kResiduals = 9;

  /// `calibrated`: the factor takes the gyro's sensor errors as a ninth block (the
  /// preintegration must have their Jacobians: ImuPreintegration's gyro_calibration).
  ImuFactor(const ImuPreintegration& pim,
            const ImuConfig& imu,
            const Eigen::Vector3d& gyro_start_rad_s,
            const Eigen::Vector3d& gyro_end_rad_s,
            const ImuEarthTerms& earth,
            bool calibrated = false);

  template <typename T>
  bool operator()(const T* q_i_ptr,
                  const T* p_i_ptr,
                  const T* v_i_ptr,
                  const T* bg_i_ptr,
                  const T* ba_i_ptr,
                  const T* q_j_ptr,
                  const T* p_j_ptr,
                  const T* v_j_ptr,
                  T* residual_ptr) const {
    return Residual<T>(q_i_ptr, p_i_ptr, v_i_ptr, bg_i_ptr, ba_i_ptr, q_j_ptr, p_j_ptr, v_j_ptr,
                       nullptr, residual_ptr);
  }

  /// The residual; `e_ptr` the gyro's sensor errors of a calibrated factor (null: none).
  template <typename T>
  bool Residual(const T* q_i_ptr,
                const T* p_i_ptr,
                const T* v_i_ptr,
                const T* bg_i_ptr,
                const T* ba_i_ptr,
                const T* q_j_ptr,
                const T* p_j_ptr,
                const T* v_j_ptr,
                const T* e_ptr,
                T* residual_ptr) const {
    using Vec3 = Eigen::Matrix<T, 3, 1>;
    const Eigen::Map<const Eigen::Quaternion<T>> q_i(q_i_ptr);
    const Eigen::Map<const Vec3> p_i(p_i_ptr), v_i(v_i_ptr), bg(bg_i_ptr), ba(ba_i_ptr);
    const Eigen::Map<const Eigen::Quaternion<T>> q_j(q_j_ptr);
    const Eigen::Map<const Vec3> p_j(p_j_ptr), v_j(v_j_ptr);

    const Eigen::Vector3d& W = earth_.omega_ie_w;
    const ImuKinematics<T> ki = BodyToImu<T>(q_i, p_i, v_i, bg, gyro_start_rad_s_, imu_, W);
    const ImuKinematics<T> kj = BodyToImu<T>(q_j, p_j, v_j, bg, gyro_end_rad_s_, imu_, W);
    Eigen::Quaternion<T> dq;
    Vec3 dv, dp;
    deltas_.Corrected<T>(bg, ba, calibration_.get(), e_ptr, &dq, &dv, &dp);

    const T dt = T(deltas_.dt_s);
    const Vec3 dp_w = kj.p_w_i - ki.p_w_i;
    const Vec3 g_w = earth_.gravity.At<T>(Vec3(T(0.5) * (ki.p_w_i + kj.p_w_i)));
    const Vec3 W_x_dp = ConstantTimes<T>(Hat(W), dp_w);
    const Eigen::Quaternion<T> q_i_w = ki.q_w_i.conjugate();
    const Vec3 omega_i = q_i_w * W.cast<T>();
    Eigen::Matrix<T, 9, 1> r;
    r.template segment<3>(0) =
        LogQ<T>(dq.conjugate() * (q_i_w * ConstantTimes<T>(earth_turn_, kj.q_w_i)));
    r.template segment<3>(3) =
        q_i_w * (kj.v_w_i - ki.v_w_i - g_w * dt + T(2) * W_x_dp) + omega_i.cross(dt * dv - dp) - dv;
    r.template segment<3>(6) =
        q_i_w * (dp_w - ki.v_w_i * dt - T(0.5) * g_w * dt * dt + W_x_dp * dt) +
        omega_i.cross(dp) * (dt / T(3)) - dp;
    Eigen::Map<Eigen::Matrix<T, 9, 1>> residual(residual_ptr);
    residual = ConstantTimes<T>(sqrt_info(), r, /*lower_triangular=*/true);
    return true;
  }

  /// The residual in double with Jacobians by hand, in Ceres' layout: `parameters` the eight
  /// blocks (nine when calibrated), `jacobians` null or as many row-major 9 x size arrays (each
  /// may be null). Quaternion
  /// columns are ambient [x,y,z,w] and chosen so that, times the EigenQuaternionManifold's
  /// PlusJacobian, they give the tangent Jacobian; their component along q itself is zero.
  bool EvaluateWithJacobians(double const* const* parameters,
                             double* residual,
                             double** jacobians) const;

  /// Analytic Jacobians (EvaluateWithJacobians). The caller owns the returned cost function.
  static std::unique_ptr<ceres::CostFunction> Create(const ImuPreintegration& pim,
                                                     const ImuConfig& imu,
                                                     const Eigen::Vector3d& gyro_start_rad_s,
                                                     const Eigen::Vector3d& gyro_end_rad_s,
                                                     const ImuEarthTerms& earth);

  /// The same residual with Ceres' automatic differentiation of operator() (the reference).
  static std::unique_ptr<ceres::CostFunction> CreateAutoDiff(
      const ImuPreintegration& pim,
      const ImuConfig& imu,
      const Eigen::Vector3d& gyro_start_rad_s,
      const Eigen::Vector3d& gyro_end_rad_s,
      const ImuEarthTerms& earth);

  /// The factor with the gyro's sensor errors as a ninth block, analytic Jacobians; `pim` must
  /// carry their Jacobians (std::invalid_argument otherwise).
  static std::unique_ptr<ceres::CostFunction> CreateCalibrated(
      const ImuPreintegration& pim,
      const ImuConfig& imu,
      const Eigen::Vector3d& gyro_start_rad_s,
      const Eigen::Vector3d& gyro_end_rad_s,
      const ImuEarthTerms& earth);
  /// The same through automatic differentiation (the reference).
  static std::unique_ptr<ceres::CostFunction> CreateCalibratedAutoDiff(
      const ImuPreintegration& pim,
      const ImuConfig& imu,
      const Eigen::Vector3d& gyro_start_rad_s,
      const Eigen::Vector3d& gyro_end_rad_s,
      const ImuEarthTerms& earth);

  /// The lower-triangular square-root information L, L^T L = covariance^-1.
  Eigen::Matrix<double, 9, 9> sqrt_info() const;
  bool calibrated() const { return calibration_ != nullptr; }

 private:
  ImuDeltas deltas_;  ///< the preintegration without its covariance
  /// The gyro calibration Jacobians of a calibrated factor (null otherwise: 8 bytes, not 648,
  /// for the factors of a long batch that does not calibrate).
  std::shared_ptr<const GyroCalibrationJacobians> calibration_;
  ImuConfig imu_;
  Eigen::Vector3d gyro_start_rad_s_, gyro_end_rad_s_;
  ImuEarthTerms earth_;
  Eigen::Quaterniond earth_turn_;  ///< Exp(omega_ie_w dt): the Earth's turn over the interval
  /// sqrt_info()'s lower triangle, row by row (L(i, j), j <= i, at i (i + 1) / 2 + j): 45
  /// numbers where the full matrix takes 81, as a long batch keeps one factor per keyframe.
  std::array<double, 45> sqrt_info_lower_;
};

}  // namespace skerry
