#pragma once
/// \file
/// On-manifold IMU preintegration.
///
/// Forster, Carlone, Dellaert, Scaramuzza, "On-Manifold Preintegration for Real-Time
/// Visual-Inertial Odometry", IEEE T-RO 33(1), 2017 (below: "Forster").
///
/// Preintegrated quantities live in the IMU frame `i` at the first keyframe:
///   dR_ij = prod_k Exp((w_k - bg) dt_k)                                   Forster eq. (33)
///   dv_ij = sum_k dR_ik' (a_k - ba) dt_k,   dR_ik' = dR_ik Exp((w_k - bg) dt_k / 2)
///   dp_ij = sum_k dv_ik dt_k + 1/2 dR_ik' (a_k - ba) dt_k^2
/// (the specific force rotated by the attitude at the middle of each step, a second-order rule
/// where Forster's eq. 34-35 take the start of the step)
/// with first-order bias corrections (eq. 44) and the 9x9 covariance of [dphi, dv, dp] propagated
/// from continuous-time noise densities (eq. 62-63, discrete sigma^2 = density^2 / dt).
/// Each step uses the average of two consecutive IMU samples (a trapezoidal rule on the
/// measurements) held over the step.
///
/// The preintegrated quantities are those of the IMU alone: the Earth's rotation, Coriolis and
/// gravity enter when an interval is tied to the world frame (PredictBodyState, ImuFactor), as
/// functions of the states, so the covariance and bias Jacobians here need no Earth terms
/// (ImuEarthTerms says why the one term that touches the measurements can be left out of them).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <iterator>
#include <stdexcept>

#include "skerry/core/constant_product.h"
#include "skerry/core/earth_model.h"
#include "skerry/core/measurements.h"
#include "skerry/core/sensor_config.h"
#include "skerry/core/so3.h"

namespace skerry {

/// First-order Jacobians of the deltas with respect to the gyro's sensor errors, for a gyro that
/// measures (I + E) omega + bg (E: the scale factors on its diagonal, the misalignment off it;
/// Groves, "Principles of GNSS, Inertial, and Multisensor Integrated Navigation Systems", 2nd
/// ed. 2013, eq. 4.18) with e = vec(E), column-major (E(r, c) at 3 c + r). The rate integrated
/// is w = gyro - bg_lin; the true one (I + E)^-1 w = w - E w to first order (E is 1e-6..1e-3),
/// so e enters each step as a rate change -E w = -(w^T (x) I3) e: the bias recursion of Forster
/// Appendix B with that 3 x 9 input in place of -I. Tangent as ImuDeltas' bias Jacobians.
struct GyroCalibrationJacobians {
  using Matrix39 = Eigen::Matrix<double, 3, 9>;
  Matrix39 J_R = Matrix39::Zero();
  Matrix39 J_v = Matrix39::Zero();
  Matrix39 J_p = Matrix39::Zero();
};

/// What an interval's residual needs of its preintegration: the deltas, the biases they were
/// integrated at and their first-order bias Jacobians (Forster eq. 44 and Appendix B), without
/// the covariance, which an IMU factor turns into its square-root information once. A factor
/// keeps these 62 numbers instead of the whole preintegration (half the memory per keyframe of a
/// long batch).
struct ImuDeltas {
  double dt_s = 0.0;
  Eigen::Quaterniond dq = Eigen::Quaterniond::Identity();
  Eigen::Vector3d dv = Eigen::Vector3d::Zero();
  Eigen::Vector3d dp = Eigen::Vector3d::Zero();
  Eigen::Vector3d bg_lin = Eigen::Vector3d::Zero(), ba_lin = Eigen::Vector3d::Zero();
  // Bias Jacobians, tangent: dR uses the right perturbation of dR_ij.
  Eigen::Matrix3d J_R_bg = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d J_v_bg = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d J_v_ba = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d J_p_bg = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d J_p_ba = Eigen::Matrix3d::Zero();

  /// Bias-corrected deltas, Forster eq. (44). Templated so Ceres Jets flow through.
  template <typename T>
  void Corrected(const Eigen::Matrix<T, 3, 1>& bg,
                 const Eigen::Matrix<T, 3, 1>& ba,
                 Eigen::Quaternion<T>* dq_out,
                 Eigen::Matrix<T, 3, 1>* dv_out,
                 Eigen::Matrix<T, 3, 1>* dp_out) const {
    Corrected<T>(bg, ba, nullptr, nullptr, dq_out, dv_out, dp_out);
  }

  /// The same, also corrected to first order for the gyro's sensor errors `e` (9 numbers, see
  /// GyroCalibrationJacobians) through `cal`, the interval's Jacobians; both null: none.
  template <typename T>
  void Corrected(const Eigen::Matrix<T, 3, 1>& bg,
                 const Eigen::Matrix<T, 3, 1>& ba,
                 const GyroCalibrationJacobians* cal,
                 const T* e,
                 Eigen::Quaternion<T>* dq_out,
                 Eigen::Matrix<T, 3, 1>* dv_out,
                 Eigen::Matrix<T, 3, 1>* dp_out) const {
    const Eigen::Matrix<T, 3, 1> dbg = bg - bg_lin.cast<T>();
    const Eigen::Matrix<T, 3, 1> dba = ba - ba_lin.cast<T>();
    Eigen::Matrix<T, 3, 1> dphi = ConstantTimes<T>(J_R_bg, dbg);
    *dv_out = dv.cast<T>() + ConstantTimes<T>(J_v_bg, dbg) + ConstantTimes<T>(J_v_ba, dba);
    *dp_out = dp.cast<T>() + ConstantTimes<T>(J_p_bg, dbg) + ConstantTimes<T>(J_p_ba, dba);
    if (cal != nullptr && e != nullptr) {
      const Eigen::Map<const Eigen::Matrix<T, 9, 1>> ev(e);
      dphi += ConstantTimes<T>(cal->J_R, ev);
      *dv_out += ConstantTimes<T>(cal->J_v, ev);
      *dp_out += ConstantTimes<T>(cal->J_p, ev);
    }
    *dq_out = ConstantTimes<T>(dq, ExpQ(dphi));
  }
};

class ImuPreintegration {
 public:
  using Matrix9 = Eigen::Matrix<double, 9, 9>;
  /// Indices of the 9-D preintegration error [dphi, dv, dp].
  enum : int { kR = 0, kV = 3, kP = 6 };

  /// `bg_lin`, `ba_lin`: biases (IMU frame) the preintegration is linearised at.
  /// `gyro_calibration`: also the Jacobians of the deltas with respect to the gyro's scale
  /// factors and misalignment (GyroCalibrationJacobians; 1.28x the time per sample,
  /// BM_Preintegrate_Interval_GyroCalibration).
  ImuPreintegration(const ImuNoise& noise,
                    const Eigen::Vector3d& bg_lin,
                    const Eigen::Vector3d& ba_lin,
                    bool gyro_calibration = false);

  /// Integrates one step of length dt_s with the (bias-uncorrected) measurement held over it.
  void Integrate(double dt_s, const Eigen::Vector3d& gyro_rad_s, const Eigen::Vector3d& accel_m_s2);

  /// The deltas, their bias Jacobians and linearisation biases (ImuDeltas; bias-corrected by
  /// ImuDeltas::Corrected, Forster eq. 44).
  const ImuDeltas& deltas() const { return d_; }
  const Matrix9& covariance() const { return covariance_; }
  /// The gyro calibration Jacobians, or null when not asked for at construction.
  const GyroCalibrationJacobians* gyro_calibration() const {
    return has_calibration_ ? &calibration_ : nullptr;
  }

 private:
  ImuNoise noise_;
  ImuDeltas d_;
  bool has_calibration_ = false;
  GyroCalibrationJacobians calibration_;
  Matrix9 covariance_ = Matrix9::Zero();
};

/// One step between two consecutive samples with the trapezoidal rule on the measurements: the
/// average of both samples is held over [a.t, b.t]. The one integration rule used in skerry.
void IntegrateBetween(const ImuSample& a, const ImuSample& b, ImuPreintegration* pim);

/// Samples averaged for the body rate at a keyframe (see KeyframeGyro).
constexpr TimeNs kKeyframeGyroWindowNs = 25'000'000;

/// Body rate at a keyframe for the lever-arm velocity term: the mean gyro of the samples in
/// (t - kKeyframeGyroWindowNs, t], t being the time of the last sample of [begin, end). One
/// sample's white noise (density * sqrt(rate): 4e-4 rad/s at 200 Hz for a MEMS part) times a
/// 1 m lever arm exceeds the preintegrated velocity sigma of a 0.1 s interval; the mean of five
/// samples does not, and its 10 ms lag is negligible at wave frequencies.
template <typename It>
Eigen::Vector3d KeyframeGyro(It begin, It end) {
  if (begin == end) throw std::invalid_argument("KeyframeGyro: no IMU sample");
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int n = 0;
  const TimeNs t = std::prev(end)->t_ns;
  for (It it = end; it != begin;) {
    --it;
    if (it->t_ns <= t - kKeyframeGyroWindowNs) break;
    sum += it->gyro_rad_s;
    ++n;
  }
  return sum / n;
}

/// Kinematic state of the IMU point and frame, derived from a body state (all in world ENU).
template <typename T>
struct ImuKinematics {
  Eigen::Quaternion<T> q_w_i;
  Eigen::Matrix<T, 3, 1> p_w_i;
  Eigen::Matrix<T, 3, 1> v_w_i;
};

/// What an IMU interval needs of the Earth, taken once near the interval's start: the Earth's
/// rotation rate in w and gravity to first order about the start (EarthModel::GravityNear).
///
/// With them the interval's mechanisation in the Earth-fixed frame w (earth_model.h) is exact up
/// to terms in (omega_ie dt)^2 ~ 5e-11 (dt = 0.1 s): see ImuFactor. The one Earth term that
/// multiplies preintegrated measurements, [omega_i]x (dt dv - dp) in the velocity residual,
/// scales their noise by 1 + O(omega_ie dt) = 1 + 7e-6, which the covariance leaves out.
struct ImuEarthTerms {
  Eigen::Vector3d omega_ie_w = Eigen::Vector3d::Zero();
  LocalGravity gravity;
};

/// The terms of an interval starting at p_w (the IMU point or the body origin: gravity changes
/// by 3e-6 m/s^2 per metre, so either will do).
ImuEarthTerms EarthTermsNear(const EarthModel& earth, const Eigen::Vector3d& p_w);

/// Body state -> IMU state: R_w_i = R_w_b R_b_i, p_w_i = p_w_b + R_w_b p_b_i,
/// v_w_i = v_w_b + R_w_b (omega_b x p_b_i) with omega_b = R_b_i (gyro - bg) - R_w_b^T omega_ie_w
/// the body's rate relative to the Earth-fixed world (the gyro also senses the Earth's turning).
template <typename T>
ImuKinematics<T> BodyToImu(const Eigen::Quaternion<T>& q_w_b,
                           const Eigen::Matrix<T, 3, 1>& p_w_b,
                           const Eigen::Matrix<T, 3, 1>& v_w_b,
                           const Eigen::Matrix<T, 3, 1>& bg,
                           const Eigen::Vector3d& gyro_rad_s,
                           const ImuConfig& imu,
                           const Eigen::Vector3d& omega_ie_w) {
  const Eigen::Matrix<T, 3, 1> p_b_i = imu.p_b_i.cast<T>();
  const Eigen::Matrix<T, 3, 1> omega_b =
      ConstantTimes<T>(Eigen::Matrix3d(imu.q_b_i.toRotationMatrix()), gyro_rad_s.cast<T>() - bg) -
      q_w_b.conjugate() * omega_ie_w.cast<T>();
  ImuKinematics<T> out;
  out.q_w_i = TimesConstant<T>(q_w_b, imu.q_b_i);
  out.p_w_i = p_w_b + q_w_b * p_b_i;
  out.v_w_i = v_w_b + q_w_b * omega_b.cross(p_b_i);
  return out;
}

/// Predicts body state j from body state i through a preintegration (Forster eq. 38 with the
/// bias-corrected deltas, in the Earth-fixed frame with the Earth terms of ImuFactor), mapping
/// through the IMU point at both ends. `gyro_end_rad_s` is the gyro measurement at t_j (for the
/// lever-arm velocity). Biases carry over unchanged. `gyro_calibration`: the gyro's sensor errors
/// e (GyroCalibrationJacobians) the deltas are corrected for, as a calibrated ImuFactor does
/// (null: none; non-null needs `pim` with their Jacobians). ImuFactor's residual at the
/// prediction is zero to ~1e-12.
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
                      const double* gyro_calibration = nullptr);

}  // namespace skerry
