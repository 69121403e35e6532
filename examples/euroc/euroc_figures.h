#pragma once
/// \file
/// Figures of skerry on the real EuRoC MAV V1_01_easy recording (ADIS16448 IMU at 200 Hz, Vicon
/// ground truth with the IMU biases estimated alongside it). Shared by the report program
/// (examples/euroc/main.cc) and the test (tests/solvers/test_euroc_real_imu.cc), so that the
/// numbers the README shows are the numbers the test asserts.
///
/// 1. Preintegration: over every interval [t, t + 1 s] that starts on a ground-truth sample, the
///    real IMU samples are preintegrated with the ground-truth biases at t, the state at t + 1 s
///    is predicted from the ground-truth state at t (PredictBodyState), and compared with the
///    ground truth there.
/// 2. Fusion: position fixes made from the ground truth (white noise, fixed seed) are fused with
///    the real IMU by the sliding-window estimator, started from a perturbed attitude; the
///    attitude error (and the yaw against the estimator's own yaw sigma) is measured against the
///    ground truth, and the same for the batch smoother over the same data, which shows what the
///    data allow at all.
///
/// Frames: the Vicon world is taken as the local ENU frame `w` (z up, which the data confirm:
/// gravity along -z predicts the velocities to a few cm/s over 1 s). The EuRoC "body" is the
/// IMU itself (T_BS = identity in imu0_sensor.yaml); its x axis points roughly up while the MAV
/// hovers, so the heading of the body x axis (HeadingDeg) is ill-conditioned here: yaw errors are
/// taken as the world-z component of the rotation error vector instead.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>
#include <stdexcept>
#include <vector>

#include "skerry/core/geodesy.h"
#include "skerry/core/so3.h"
#include "skerry/eval/evaluation.h"
#include "skerry/factors/imu_preintegration.h"
#include "skerry/io/dataset.h"
#include "skerry/io/importers.h"
#include "skerry/solvers/estimator_config.h"
#include "skerry/solvers/pipeline.h"

namespace skerry::euroc {

inline constexpr double kRadToDeg = 180.0 / M_PI;
inline constexpr double kDegToRad = M_PI / 180.0;

/// Quantile q in [0, 1] (nearest rank on the sorted values); 0 for an empty set.
inline double Quantile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const double pos = q * static_cast<double>(values.size() - 1);
  const std::size_t lo = static_cast<std::size_t>(std::floor(pos));
  const std::size_t hi = std::min(lo + 1, values.size() - 1);
  const double s = pos - static_cast<double>(lo);
  return (1.0 - s) * values[lo] + s * values[hi];
}

/// Ground-truth state at t_ns: position, velocity and biases linear, attitude slerp, between
/// the neighbouring truth samples. False outside the span.
inline bool InterpolateTruth(const std::vector<NavState>& truth, TimeNs t_ns, NavState* out) {
  if (truth.empty() || t_ns < truth.front().t_ns || t_ns > truth.back().t_ns) return false;
  const auto it = std::upper_bound(truth.begin(), truth.end(), t_ns,
                                   [](TimeNs t, const NavState& s) { return t < s.t_ns; });
  const NavState& s0 = *std::prev(it);
  if (s0.t_ns == t_ns || it == truth.end()) {
    *out = s0;
    out->t_ns = t_ns;
    return true;
  }
  const NavState& s1 = *it;
  const double s = static_cast<double>(t_ns - s0.t_ns) / static_cast<double>(s1.t_ns - s0.t_ns);
  out->t_ns = t_ns;
  out->p_w_b = (1.0 - s) * s0.p_w_b + s * s1.p_w_b;
  out->v_w = (1.0 - s) * s0.v_w + s * s1.v_w;
  out->bg = (1.0 - s) * s0.bg + s * s1.bg;
  out->ba = (1.0 - s) * s0.ba + s * s1.ba;
  out->q_w_b = s0.q_w_b.slerp(s, s1.q_w_b).normalized();
  return true;
}

// ---------------------------------------------------------------------------------------------
// Ground-truth velocity frame.

/// RMS difference (m/s) between the ground-truth velocity and the central difference of the
/// ground-truth positions, taking the velocity as world-frame (`world`) or as body-frame
/// (`body`, rotated to the world by the truth attitude). The smaller one names the frame.
struct VelocityFrameCheck {
  double rms_world_m_s = 0.0;
  double rms_body_m_s = 0.0;
  int count = 0;
};

inline VelocityFrameCheck CheckTruthVelocityFrame(const std::vector<NavState>& truth) {
  VelocityFrameCheck out;
  double sum_w = 0.0, sum_b = 0.0;
  for (std::size_t k = 1; k + 1 < truth.size(); ++k) {
    const double dt = NsToSeconds(truth[k + 1].t_ns - truth[k - 1].t_ns);
    if (!(dt > 0.0) || dt > 0.2) continue;  // skip gaps
    const Eigen::Vector3d v_fd = (truth[k + 1].p_w_b - truth[k - 1].p_w_b) / dt;
    sum_w += (truth[k].v_w - v_fd).squaredNorm();
    sum_b += (truth[k].q_w_b * truth[k].v_w - v_fd).squaredNorm();
    ++out.count;
  }
  if (out.count > 0) {
    out.rms_world_m_s = std::sqrt(sum_w / out.count);
    out.rms_body_m_s = std::sqrt(sum_b / out.count);
  }
  return out;
}

// ---------------------------------------------------------------------------------------------
// 1. Preintegration over fixed intervals.

struct PreintegrationOptions {
  double interval_s = 1.0;
  /// Start an interval at every `start_every`-th ground-truth sample (1 = sliding, ~20 Hz).
  int start_every = 1;
  /// Both interval ends must have an IMU sample within this of the truth sample.
  double max_end_offset_s = 0.0026;
};

struct PreintegrationFigures {
  std::vector<double> rot_err_deg;  ///< |Log(R_pred R_true^T)|
  std::vector<double> vel_err_m_s;  ///< |v_pred - v_true|
  std::vector<double> pos_err_m;    ///< |p_pred - p_true|
  /// Mean signed velocity error (world, m/s): a gravity or frame mismatch shows up here.
  Eigen::Vector3d mean_vel_err_w = Eigen::Vector3d::Zero();
  double max_end_offset_s = 0.0;  ///< largest |t_imu - t_truth| at an interval end
};

/// Predicts, over each interval, the truth state at its end from the truth state at its start
/// through the real IMU samples between them (preintegrated at the truth biases at the start),
/// both ends on IMU samples, and the truth interpolated to those IMU times.
inline PreintegrationFigures MeasurePreintegration(
    const Dataset& data, const PreintegrationOptions& options = PreintegrationOptions()) {
  const std::vector<NavState>& truth = data.truth_states;
  const std::vector<ImuSample>& imu = data.imu_samples;
  if (truth.size() < 2 || imu.size() < 2) {
    throw std::invalid_argument("MeasurePreintegration: no ground truth or IMU");
  }
  const TimeNs interval_ns = SecondsToNs(options.interval_s);
  const TimeNs max_offset_ns = SecondsToNs(options.max_end_offset_s);
  // Index of the IMU sample nearest to t.
  auto nearest_imu = [&](TimeNs t) {
    auto it = std::lower_bound(imu.begin(), imu.end(), t,
                               [](const ImuSample& s, TimeNs x) { return s.t_ns < x; });
    if (it == imu.end()) return imu.size() - 1;
    if (it != imu.begin() && (t - std::prev(it)->t_ns) < (it->t_ns - t)) --it;
    return static_cast<std::size_t>(it - imu.begin());
  };

  const EarthModel earth = data.Earth();
  PreintegrationFigures out;
  Eigen::Vector3d sum_v = Eigen::Vector3d::Zero();
  for (std::size_t k = 0; k < truth.size(); k += std::max(options.start_every, 1)) {
    const TimeNs t0 = truth[k].t_ns;
    const TimeNs t1 = t0 + interval_ns;
    if (t1 > truth.back().t_ns) break;
    const std::size_t a = nearest_imu(t0);
    const std::size_t b = nearest_imu(t1);
    const TimeNs off_a = std::llabs(imu[a].t_ns - t0);
    const TimeNs off_b = std::llabs(imu[b].t_ns - t1);
    if (off_a > max_offset_ns || off_b > max_offset_ns || b <= a) continue;
    NavState si, sj;
    if (!InterpolateTruth(truth, imu[a].t_ns, &si) || !InterpolateTruth(truth, imu[b].t_ns, &sj)) {
      continue;
    }
    out.max_end_offset_s = std::max(out.max_end_offset_s, NsToSeconds(std::max(off_a, off_b)));

    ImuPreintegration pim(data.imu.noise, si.bg, si.ba);
    for (std::size_t m = a; m < b; ++m) IntegrateBetween(imu[m], imu[m + 1], &pim);
    Eigen::Quaterniond q_pred;
    Eigen::Vector3d p_pred, v_pred;
    PredictBodyState(pim, data.imu, EarthTermsNear(earth, si.p_w_b), imu[a].gyro_rad_s,
                     imu[b].gyro_rad_s, si.q_w_b, si.p_w_b, si.v_w, si.bg, si.ba, &q_pred, &p_pred,
                     &v_pred);
    out.rot_err_deg.push_back(LogQ(Eigen::Quaterniond(q_pred * sj.q_w_b.conjugate())).norm() *
                              kRadToDeg);
    out.vel_err_m_s.push_back((v_pred - sj.v_w).norm());
    out.pos_err_m.push_back((p_pred - sj.p_w_b).norm());
    sum_v += v_pred - sj.v_w;
  }
  if (!out.vel_err_m_s.empty()) out.mean_vel_err_w = sum_v / out.vel_err_m_s.size();
  return out;
}

// ---------------------------------------------------------------------------------------------
// 2. Fusion with position fixes made from the ground truth.

struct FusionOptions {
  double fix_rate_hz = 2.0;
  double fix_sigma_m = 0.5;  ///< white noise added per axis, and the sigma the fixes carry
  std::uint64_t seed = 20140625;
  /// Initial attitude error as a world-frame rotation vector (deg): about east, north, up.
  Eigen::Vector3d attitude_error_deg{2.0, -2.0, 5.0};
  double rot_prior_sigma_deg = 10.0;
  double pos_prior_sigma_m = 0.5;
  double vel_prior_sigma_m_s = 0.1;
  /// true: start from the truth biases with the dataset's bias prior sigmas; false: from zero
  /// biases with the loose sigmas below.
  bool truth_biases = true;
  /// > 0: no given first state; init.mode "align" (YawHypothesisBank) with the vehicle at rest
  /// for this long at the start: heading and gyro bias unknown (V1_01 stands still ~4 s).
  double align_static_s = 0.0;
  double loose_gyro_bias_sigma_rad_s = 0.1;
  double loose_accel_bias_sigma_m_s2 = 0.3;
  double skip_s = 10.0;     ///< convergence time left out of the figures
  bool with_batch = true;   ///< also run the batch smoother over the same data
  double duration_s = 0.0;  ///< 0 = the whole recording
};

struct FusionFigures {
  double rms_rot_deg = 0.0;        ///< RMS of |rot_err_w|
  double rms_tilt_deg = 0.0;       ///< RMS of the horizontal (east, north) part: roll/pitch
  double rms_yaw_deg = 0.0;        ///< RMS of the up part: heading
  double rms_yaw_sigma_deg = 0.0;  ///< RMS of the estimator's own yaw 1-sigma, sqrt(P(2,2))
  double anees_yaw = 0.0;          ///< average 1-DOF NEES of the yaw, 1 if consistent
  double max_rot_deg = 0.0;
  double rms_pos_m = 0.0;
  double anees_pose = 0.0;  ///< average 6-DOF NEES (rotation + position), 0 if none
  double anees_pos = 0.0;
  int nees_count = 0;
  int epochs = 0;  ///< keyframe estimates scored (after skip_s)
  int fixes = 0;
  GnssStats gnss;
  double wall_s = 0.0;
  double data_s = 0.0;
  Eigen::Vector3d first_bg = Eigen::Vector3d::Zero();  ///< first estimate's gyro bias
  Eigen::Vector3d final_bg = Eigen::Vector3d::Zero();  ///< last estimate's gyro bias
  Eigen::Vector3d final_bg_truth = Eigen::Vector3d::Zero();
  /// The batch smoother over the same data (SmoothBatch from the window's keyframes and fix
  /// decisions), scored the same way: what the data allow at all, given the whole recording.
  bool batch_usable = false;
  double batch_rms_tilt_deg = 0.0;
  double batch_rms_yaw_deg = 0.0;
  double batch_rms_yaw_sigma_deg = 0.0;
};

/// Attitude figures of `records` after `t_skip` against the ground truth: RMS of the tilt
/// (east/north part of the world rotation error), of the yaw (up part), of the yaw 1-sigma
/// and the average yaw NEES. Rotation covariances are world-frame (nav_state.h), so the yaw
/// variance is P(kRot + 2, kRot + 2).
struct AttitudeScore {
  double rms_rot_deg = 0.0, rms_tilt_deg = 0.0, rms_yaw_deg = 0.0, max_rot_deg = 0.0;
  double rms_yaw_sigma_deg = 0.0, anees_yaw = 0.0;
  EvaluationResult eval;
};

inline AttitudeScore ScoreAttitude(const std::vector<EstimateRecord>& records,
                                   const std::vector<StampedPose>& groundtruth,
                                   TimeNs t_skip) {
  std::vector<EstimateRecord> scored;
  for (const EstimateRecord& r : records) {
    if (r.state.t_ns >= t_skip) scored.push_back(r);
  }
  AttitudeScore out;
  out.eval = Evaluate(scored, groundtruth);
  double sum_rot = 0.0, sum_tilt = 0.0, sum_yaw = 0.0, sum_var = 0.0, sum_nees = 0.0;
  int n = 0, n_cov = 0;
  size_t k = 0;
  for (const EpochError& e : out.eval.epochs) {
    const Eigen::Vector3d r = e.rot_err_w * kRadToDeg;
    sum_rot += r.squaredNorm();
    sum_tilt += r.head<2>().squaredNorm();
    sum_yaw += r.z() * r.z();
    out.max_rot_deg = std::max(out.max_rot_deg, r.norm());
    ++n;
    while (k < scored.size() && scored[k].state.t_ns < e.t_ns) ++k;
    if (k < scored.size() && scored[k].state.t_ns == e.t_ns && scored[k].has_covariance) {
      const double var = scored[k].covariance(kRot + 2, kRot + 2);
      if (var > 0.0) {
        sum_var += var;
        sum_nees += e.rot_err_w.z() * e.rot_err_w.z() / var;
        ++n_cov;
      }
    }
  }
  if (n > 0) {
    out.rms_rot_deg = std::sqrt(sum_rot / n);
    out.rms_tilt_deg = std::sqrt(sum_tilt / n);
    out.rms_yaw_deg = std::sqrt(sum_yaw / n);
  }
  if (n_cov > 0) {
    out.rms_yaw_sigma_deg = std::sqrt(sum_var / n_cov) * kRadToDeg;
    out.anees_yaw = sum_nees / n_cov;
  }
  return out;
}

inline void AddTruthFixes(const FusionOptions& options, Dataset* data) {
  AddFixesFromGroundTruth(options.fix_rate_hz, options.fix_sigma_m, options.seed, data,
                          options.duration_s);
}

/// The given first state: truth position and velocity, truth attitude rotated by
/// `attitude_error_deg` (world frame), truth or zero biases; diagonal covariance.
inline EstimateRecord MakeInitialState(const Dataset& data, const FusionOptions& options) {
  const NavState& truth = data.truth_states.front();
  EstimateRecord initial;
  initial.state = truth;
  initial.state.q_w_b =
      (ExpQ(Eigen::Vector3d(options.attitude_error_deg * kDegToRad)) * truth.q_w_b).normalized();
  double sigma_bg = data.imu.gyro_bias_prior_sigma_rad_s;
  double sigma_ba = data.imu.accel_bias_prior_sigma_m_s2;
  if (!options.truth_biases) {
    initial.state.bg.setZero();
    initial.state.ba.setZero();
    sigma_bg = options.loose_gyro_bias_sigma_rad_s;
    sigma_ba = options.loose_accel_bias_sigma_m_s2;
  }
  const double sr = options.rot_prior_sigma_deg * kDegToRad;
  initial.has_covariance = true;
  initial.covariance.setZero();
  initial.covariance.diagonal().segment<3>(kRot).setConstant(sr * sr);
  initial.covariance.diagonal().segment<3>(kPos).setConstant(options.pos_prior_sigma_m *
                                                             options.pos_prior_sigma_m);
  initial.covariance.diagonal().segment<3>(kVel).setConstant(options.vel_prior_sigma_m_s *
                                                             options.vel_prior_sigma_m_s);
  initial.covariance.diagonal().segment<3>(kBg).setConstant(sigma_bg * sigma_bg);
  initial.covariance.diagonal().segment<3>(kBa).setConstant(sigma_ba * sigma_ba);
  return initial;
}

/// Runs the sliding window (RunWindow with a given first state) on the real IMU and the truth
/// fixes, and scores the attitude after `skip_s`.
inline FusionFigures MeasureFusion(Dataset data,
                                   EstimatorConfig config,
                                   const FusionOptions& options = FusionOptions()) {
  if (data.truth_states.empty()) throw std::invalid_argument("MeasureFusion: no ground truth");
  if (options.duration_s > 0.0) {
    const TimeNs t_end = data.truth_states.front().t_ns + SecondsToNs(options.duration_s);
    while (!data.imu_samples.empty() && data.imu_samples.back().t_ns > t_end) {
      data.imu_samples.pop_back();
    }
  }
  AddTruthFixes(options, &data);
  const EstimateRecord initial = MakeInitialState(data, options);
  WindowRun run;
  if (options.align_static_s > 0.0) {
    config.init.mode = "align";
    config.init.static_s = options.align_static_s;
    run = RunWindow(data, config);
  } else {
    config.init.mode = "given";
    run = RunWindow(data, config, {}, &initial);
  }

  const TimeNs t_skip = initial.state.t_ns + SecondsToNs(options.skip_s);
  const AttitudeScore window = ScoreAttitude(run.records, data.groundtruth, t_skip);
  const EvaluationResult& eval = window.eval;

  FusionFigures out;
  out.fixes = static_cast<int>(data.gnss_fixes.size());
  out.gnss = run.gnss;
  out.wall_s = run.wall_s;
  out.data_s = run.data_s;
  out.epochs = static_cast<int>(eval.epochs.size());
  out.rms_pos_m = eval.position3d.rmse;
  out.anees_pose = eval.anees_pose;
  out.anees_pos = eval.anees_pos;
  out.nees_count = eval.nees_count;
  out.rms_rot_deg = window.rms_rot_deg;
  out.rms_tilt_deg = window.rms_tilt_deg;
  out.rms_yaw_deg = window.rms_yaw_deg;
  out.max_rot_deg = window.max_rot_deg;
  out.rms_yaw_sigma_deg = window.rms_yaw_sigma_deg;
  out.anees_yaw = window.anees_yaw;
  if (options.with_batch && run.records.size() >= 2) {
    const BatchResult batch = SmoothBatch(data, config, run.records, run.decisions);
    out.batch_usable = batch.usable;
    const AttitudeScore b = ScoreAttitude(batch.records, data.groundtruth, t_skip);
    out.batch_rms_tilt_deg = b.rms_tilt_deg;
    out.batch_rms_yaw_deg = b.rms_yaw_deg;
    out.batch_rms_yaw_sigma_deg = b.rms_yaw_sigma_deg;
  }
  if (!run.records.empty()) {
    out.first_bg = run.records.front().state.bg;
    out.final_bg = run.records.back().state.bg;
    NavState t;
    if (InterpolateTruth(data.truth_states, run.records.back().state.t_ns, &t)) {
      out.final_bg_truth = t.bg;
    }
  }
  return out;
}

}  // namespace skerry::euroc
