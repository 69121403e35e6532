#include "skerry/solvers/sliding_window_estimator.h"

#include <spdlog/spdlog.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <iterator>
#include <optional>
#include <stdexcept>

#include "skerry/core/chi_square.h"
#include "skerry/core/heading.h"
#include "skerry/core/mahalanobis.h"
#include "skerry/core/so3.h"
#include "skerry/factors/gnss_drift_factor.h"
#include "skerry/factors/gnss_drift_step_factor.h"
#include "skerry/factors/imu_preintegration.h"
#include "skerry/factors/linear_prior_factor.h"
#include "skerry/factors/state_prior_factor.h"
#include "skerry/io/csv_reader.h"
#include "skerry/solvers/course_start.h"
#include "skerry/solvers/measurement_checks.h"
#include "skerry/solvers/motion_factors.h"

namespace skerry {

namespace {
constexpr double kDegToRad = M_PI / 180.0;
// A jump becomes a step in the drift only after it has explained at least this many fixes
// (beside gnss.jump_step_after_s): a mean over fewer is hardly better than the first step.
constexpr int kJumpStepMinFixes = 3;

double MsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

std::vector<BlockRef> KeyframeBlocks(KeyframeId id) {
  return {{id, Slot::kQ}, {id, Slot::kP}, {id, Slot::kV}, {id, Slot::kBg}, {id, Slot::kBa}};
}

StateCovariance NavBlock(const GraphCovariance& P) {
  return P.topLeftCorner<kStateDim, kStateDim>();
}
}  // namespace

SlidingWindowEstimator::SlidingWindowEstimator(const EstimatorConfig& config,
                                               const ImuConfig& imu,
                                               const GnssConfig& gnss,
                                               const EarthModel& earth)
    : SlidingWindowEstimator((ValidateEstimatorConfig(config), config),  // throws if it is wrong
                             imu,
                             gnss,
                             earth,
                             ConfigValidated()) {}

SlidingWindowEstimator::SlidingWindowEstimator(const EstimatorConfig& config,
                                               const ImuConfig& imu,
                                               const GnssConfig& gnss,
                                               const EarthModel& earth,
                                               ConfigValidated)
    : config_(config),
      imu_(imu),
      gnss_(gnss),
      earth_(earth),
      graph_(std::make_unique<NavGraph>(config.gnss_drift.enabled())),
      policy_(config.keyframe_rate_hz) {  // throws unless the rate's period is representable
  keyframe_period_ns_ = SecondsToNs(1.0 / config_.keyframe_rate_hz);
  if (config_.gnss_gate_probability > 0.0) {
    gate_pos_ = ChiSquareQuantile(config_.gnss_gate_probability, 3.0);
    gate_heading_ = ChiSquareQuantile(config_.gnss_gate_probability, 1.0);
  }
  MakeSolverOptions(config_.ceres);  // validate early
  if (EstimatesGyroCalibration(config_, imu_)) AddImuCalibration(graph_.get(), imu_);
}

SlidingWindowEstimator::~SlidingWindowEstimator() = default;

void SlidingWindowEstimator::SetInitialState(const NavState& state,
                                             const StateCovariance& covariance) {
  if (initialized_) throw std::logic_error("SetInitialState after initialisation");
  given_initial_ = std::make_pair(state, covariance);
}

void SlidingWindowEstimator::AddImu(const ImuSample& sample) {
  CheckImuSample(sample);
  if (sample.t_ns <= last_imu_ns_) {
    throw std::invalid_argument("IMU time does not increase at t=" +
                                std::to_string(NsToSeconds(sample.t_ns)));
  }
  last_imu_ns_ = sample.t_ns;
  if (!initialized_) {
    imu_buffer_.push_back(sample);
    TryInitialize();
    return;
  }
  ProcessImu(sample);
}

void SlidingWindowEstimator::AddGnss(const GnssFix& fix) {
  CheckGnssFix(fix);
  if (fix.t_ns <= last_gnss_ns_) {
    throw std::invalid_argument("GNSS time does not increase at t=" +
                                std::to_string(NsToSeconds(fix.t_ns)));
  }
  last_gnss_ns_ = fix.t_ns;
  if (!initialized_) {
    gnss_buffer_.push_back(fix);
    TryInitialize();
    return;
  }
  ProcessGnss(fix);
}

void SlidingWindowEstimator::TryInitialize() {
  if (imu_buffer_.empty()) return;
  const InitConfig& ic = config_.init;
  if (given_initial_) {
    // Start at the first IMU sample at or after the given time.
    while (!imu_buffer_.empty() && imu_buffer_.front().t_ns < given_initial_->first.t_ns) {
      imu_buffer_.pop_front();
    }
    if (imu_buffer_.empty()) return;
    NavState s = given_initial_->first;
    s.t_ns = imu_buffer_.front().t_ns;
    Start(s, given_initial_->second);
    return;
  }
  if (ic.mode == "given" || ic.mode == "skyline" || ic.mode == "lidar")
    return;  // waiting for SetInitialState
  if (gnss_buffer_.empty()) return;

  // Find the anchor fix and the heading.
  const bool want_heading = ic.mode == "heading" || ic.mode == "auto";
  const bool want_cog = ic.mode == "cog" || ic.mode == "auto";
  std::optional<GnssFix> anchor;
  double heading_rad = 0.0, yaw_sigma_rad = ic.yaw_sigma_deg * kDegToRad;
  Eigen::Vector3d v0 = Eigen::Vector3d::Zero();
  double velocity_sigma = ic.velocity_sigma_m_s;
  std::vector<GnssFix> course;  // mode cog: the fixes from the anchor to min_cog_distance_m on
  if (want_heading) {
    for (size_t k = 0; k < gnss_buffer_.size(); ++k) {
      const GnssFix& f = gnss_buffer_[k];
      if (!f.has_heading) continue;
      // The velocity from this fix and the next one: a moving vessel must not start at rest.
      if (k + 1 >= gnss_buffer_.size()) return;  // wait for the next fix
      const GnssFix& g = gnss_buffer_[k + 1];
      const double dt = NsToSeconds(g.t_ns - f.t_ns);
      if (dt > ic.max_cog_time_s) continue;
      v0 = (g.p_w - f.p_w) / dt;
      v0.z() = 0.0;
      velocity_sigma =
          std::hypot(ic.velocity_sigma_m_s,
                     (f.sigma_enu_m.head<2>().norm() + g.sigma_enu_m.head<2>().norm()) / dt);
      // Heading of the baseline -> heading of the body x axis (horizontal baseline assumed).
      // The baseline sits atan2(b_y, b_x) counter-clockwise (to port) of the bow in FLU, so its
      // heading is the body heading minus that angle. Both are from the local north at the fix.
      heading_rad =
          f.heading_deg * kDegToRad + std::atan2(gnss_.baseline_b.y(), gnss_.baseline_b.x());
      yaw_sigma_rad = std::max(f.sigma_heading_deg * kDegToRad * 3.0, 0.5 * kDegToRad);
      anchor = f;
      break;
    }
  }
  if (!anchor && want_cog) {
    while (gnss_buffer_.size() >= 2) {
      const GnssFix& a = gnss_buffer_.front();
      std::optional<GnssFix> b;
      for (size_t k = 1; k < gnss_buffer_.size(); ++k) {
        const GnssFix& c = gnss_buffer_[k];
        if (NsToSeconds(c.t_ns - a.t_ns) > ic.max_cog_time_s) break;
        if ((c.p_w - a.p_w).head<2>().norm() >= ic.min_cog_distance_m) {
          b = c;
          break;
        }
      }
      if (b) {
        for (const GnssFix& f : gnss_buffer_) {
          if (f.t_ns > b->t_ns) break;
          course.push_back(f);
        }
        anchor = a;
        break;
      }
      if (NsToSeconds(gnss_buffer_.back().t_ns - a.t_ns) > ic.max_cog_time_s) {
        // Never paired: the vessel did not move enough. Recorded, so that decisions stay one
        // per fix.
        fix_decisions_.push_back(DroppedFix(gnss_buffer_.front()));
        ++gnss_stats_.dropped;
        gnss_buffer_.pop_front();
      } else {
        break;
      }
    }
  }
  if (!anchor) return;
  // Need IMU data over the attitude window after the anchor.
  const TimeNs t_end = anchor->t_ns + SecondsToNs(ic.attitude_window_s);
  if (imu_buffer_.back().t_ns < t_end) return;
  while (!imu_buffer_.empty() && imu_buffer_.front().t_ns < anchor->t_ns) imu_buffer_.pop_front();
  if (imu_buffer_.empty()) return;
  Eigen::Vector3d f_mean = Eigen::Vector3d::Zero();
  int n = 0;
  for (const ImuSample& s : imu_buffer_) {
    if (s.t_ns > t_end) break;
    f_mean += s.accel_m_s2;
    ++n;
  }
  const Eigen::Vector3d up_b = (imu_.q_b_i * (f_mean / n)).normalized();
  if (!course.empty()) {
    // The course over ground with the gyro's turns along it taken out (course_start.h).
    if (imu_buffer_.back().t_ns < course.back().t_ns) return;  // wait for the IMU to catch up
    const Eigen::Matrix3d R_n_w = earth_.LocalLevel(anchor->p_w).transpose();
    std::vector<CourseFix> en;
    for (const GnssFix& f : course) {
      en.push_back({f.t_ns, (R_n_w * (f.p_w - anchor->p_w)).head<2>()});
    }
    std::vector<YawRate> rates;
    for (const ImuSample& m : imu_buffer_) {
      if (m.t_ns > course.back().t_ns) break;
      rates.push_back({m.t_ns, up_b.dot(imu_.q_b_i * m.gyro_rad_s)});
    }
    const CourseStart c = CourseAtFirstFix(
        en, rates, anchor->sigma_enu_m.head<2>().maxCoeff() * config_.gnss_sigma_scale,
        imu_.gyro_bias_prior_sigma_rad_s);
    heading_rad = c.heading_rad;
    yaw_sigma_rad = std::hypot(yaw_sigma_rad, c.sigma_rad);
    const Eigen::Vector3d dir_n(std::sin(heading_rad), std::cos(heading_rad), 0.0);
    v0 = c.speed_m_s * (R_n_w.transpose() * dir_n);
    v0.z() = 0.0;
    spdlog::debug("course start: {} fixes over {:.1f} s, turned {:.1f} deg, sigma {:.2f} deg",
                  course.size(), NsToSeconds(course.back().t_ns - course.front().t_ns),
                  c.turned_rad / kDegToRad, c.sigma_rad / kDegToRad);
  }
  const double roll = std::atan2(up_b.y(), up_b.z());
  const double pitch = std::atan2(-up_b.x(), std::hypot(up_b.y(), up_b.z()));

  // Roll, pitch and heading are relative to the local level at the anchor, which is turned from
  // w by the tilt of the vertical and the meridian convergence away from the origin.
  NavState s;
  s.t_ns = imu_buffer_.front().t_ns;
  s.q_w_b = (Eigen::Quaterniond(earth_.LocalLevel(anchor->p_w)) *
             QuaternionFromRollPitchHeading(roll, pitch, heading_rad))
                .normalized();
  s.p_w_b = anchor->p_w - s.q_w_b * gnss_.p_b_g;
  s.v_w = v0;
  StateCovariance P = StateCovariance::Zero();
  const double rp = ic.roll_pitch_sigma_deg * kDegToRad;
  P.diagonal().segment<3>(kRot) << rp * rp, rp * rp, yaw_sigma_rad * yaw_sigma_rad;
  P.diagonal().segment<3>(kPos) = config_.StartPositionVariance(anchor->sigma_enu_m);
  P.diagonal().segment<3>(kVel).setConstant(velocity_sigma * velocity_sigma);
  P.diagonal().segment<3>(kBg).setConstant(imu_.gyro_bias_prior_sigma_rad_s *
                                           imu_.gyro_bias_prior_sigma_rad_s);
  P.diagonal().segment<3>(kBa).setConstant(imu_.accel_bias_prior_sigma_m_s2 *
                                           imu_.accel_bias_prior_sigma_m_s2);
  spdlog::debug("initialised at t={:.3f} heading {:.2f} deg", NsToSeconds(s.t_ns),
                HeadingDeg(s.q_w_b));
  Start(s, P);
}

const Keyframe& SlidingWindowEstimator::StartGraph(const NavState& state,
                                                   const Eigen::Vector3d& gyro_rad_s,
                                                   const StateCovariance& covariance) {
  // A (re)start from a state: innovations before it say nothing of the receiver now, and the
  // drift restarts from its stationary distribution, without the jumps it had taken in.
  jump_test_.Reset();
  newest_drift_factor_ = -1;
  newest_drift_stepped_ = false;
  drift_stepped_m_.setZero();
  drift_stepped_cov_.setZero();
  const Keyframe& kf = graph_->AddKeyframe(state, gyro_rad_s);
  graph_->AddFactor(FactorKind::kStatePrior, StatePriorFactor::Create(state, covariance), nullptr,
                    KeyframeBlocks(kf.id));
  newest_cov_.setZero();
  newest_cov_.topLeftCorner<kStateDim, kStateDim>() = covariance;
  if (config_.gnss_drift.enabled()) {
    // The drift starts from its stationary distribution N(0, diag(sigma_h^2, sigma_h^2,
    // sigma_v^2)).
    graph_->AddFactor(FactorKind::kGnssDriftPrior,
                      std::make_unique<GnssDriftPriorFactor>(config_.gnss_drift), nullptr,
                      {{kf.id, Slot::kGb}});
    newest_cov_.diagonal().segment<3>(kGraphGb) =
        config_.gnss_drift.StationarySigma().array().square();
  }
  NewestCovarianceChanged();
  return kf;
}

void SlidingWindowEstimator::Start(const NavState& state, const StateCovariance& covariance) {
  initialized_ = true;
  recent_samples_.assign(1, imu_buffer_.front());
  StartGraph(state, imu_buffer_.front().gyro_rad_s, covariance);
  outputs_.push_back({state, config_.compute_covariance, covariance});
  stats_.push_back({state.t_ns, 0.0, 0.0, 0, false, true});
  last_sample_ = imu_buffer_.front();
  has_last_sample_ = true;
  pim_ = std::make_unique<ImuPreintegration>(imu_.noise, state.bg, state.ba,
                                             graph_->has_imu_calibration());
  policy_.Start(state.t_ns);
  imu_buffer_.pop_front();
  // Replay what was buffered, in time order.
  std::deque<ImuSample> imu = std::move(imu_buffer_);
  std::deque<GnssFix> gnss = std::move(gnss_buffer_);
  imu_buffer_.clear();
  gnss_buffer_.clear();
  for (const GnssFix& f : gnss) {
    if (f.t_ns < state.t_ns - keyframe_period_ns_ / 2) {
      fix_decisions_.push_back(DroppedFix(f));
      ++gnss_stats_.dropped;
    } else {
      pending_fixes_.push_back(f);
    }
  }
  std::vector<size_t> measurements = std::move(measurement_buffer_);
  measurement_buffer_.clear();
  for (size_t index : measurements) QueueMeasurement(index);
  solve_pending_ |= AttachDueMeasurements(graph_->newest(), newest_cov_);
  for (const ImuSample& s : imu) ProcessImu(s);
}

void SlidingWindowEstimator::ProcessGnss(const GnssFix& fix) { pending_fixes_.push_back(fix); }

void SlidingWindowEstimator::ProcessImu(const ImuSample& sample) {
  // recent_samples_ holds recorded samples only; an interpolated one counts for the keyframe
  // at its time alone (CloseKeyframe), as in the batch.
  auto advance = [&](const ImuSample& to, bool recorded) {
    if (to.t_ns <= last_sample_.t_ns) return;
    IntegrateBetween(last_sample_, to, pim_.get());
    last_sample_ = to;
    if (!recorded) return;
    recent_samples_.push_back(to);
    while (recent_samples_.front().t_ns <= to.t_ns - kKeyframeGyroWindowNs) {
      recent_samples_.pop_front();
    }
  };
  // Measurements up to this sample first: each on a keyframe at its time, the preintegration
  // split there (keyframe_policy.h).
  while (!pending_measurements_.empty() && pending_measurements_.begin()->first <= sample.t_ns) {
    const TimeNs t = pending_measurements_.begin()->first;
    if (t <= graph_->newest().t_ns + policy_.merge_tolerance_ns()) {
      solve_pending_ |= AttachDueMeasurements(graph_->newest(), newest_cov_);
      continue;
    }
    if (t < last_sample_.t_ns) {  // behind the integration already: no keyframe can be made
      DropMeasurement(pending_measurements_.begin()->second);
      pending_measurements_.erase(pending_measurements_.begin());
      continue;
    }
    advance(InterpolateSample(last_sample_, sample, t), t == sample.t_ns);
    CloseKeyframe(last_sample_, /*on_grid=*/false);
  }
  advance(sample, true);
  if (policy_.GridDue(sample.t_ns) && sample.t_ns > graph_->newest().t_ns) {
    CloseKeyframe(sample, /*on_grid=*/true);
  }
}

SensorId SlidingWindowEstimator::RegisterSensor(const SensorSpec& spec) {
  const SensorId id = static_cast<SensorId>(sensors_.size());
  sensors_.push_back(spec);
  sensor_stats_.emplace_back();
  sensor_reject_streak_.push_back(0);
  last_measurement_ns_.push_back(std::numeric_limits<TimeNs>::min());
  AddSensorExtrinsic(graph_.get(), id, spec);
  AddSensorParameter(graph_.get(), id, spec);
  return id;
}

bool SlidingWindowEstimator::AnySensorGate() const {
  return std::any_of(sensors_.begin(), sensors_.end(),
                     [](const SensorSpec& s) { return s.gate_probability > 0.0; });
}

std::unique_ptr<NavGraph> SlidingWindowEstimator::MakeGraph() const {
  auto graph = std::make_unique<NavGraph>(config_.gnss_drift.enabled());
  for (size_t k = 0; k < sensors_.size(); ++k) {
    const SensorId id = static_cast<SensorId>(k);
    // A calibrated extrinsic keeps what it has learnt: the new graph's prior is its estimate
    // and marginal covariance in the old one (the spec's prior when that cannot be computed).
    Eigen::Matrix<double, 6, 6> cov;
    if (graph_ && sensors_[k].calibrate && graph_->has_extrinsic(id) &&
        graph_->ExtrinsicCovariance(id, &cov)) {
      AddSensorExtrinsic(graph.get(), id, sensors_[k], &graph_->extrinsic(id), &cov);
    } else {
      AddSensorExtrinsic(graph.get(), id, sensors_[k]);
    }
    // An estimated parameter likewise.
    double variance = 0.0;
    if (graph_ && graph_->has_sensor_parameter(id) && graph_->sensor_parameter(id).estimated &&
        graph_->SensorParameterVariance(id, &variance)) {
      AddSensorParameter(graph.get(), id, sensors_[k], graph_->sensor_parameter(id).value,
                         &variance);
    } else {
      AddSensorParameter(graph.get(), id, sensors_[k]);
    }
  }
  // The gyro's calibration likewise.
  if (EstimatesGyroCalibration(config_, imu_)) {
    Eigen::Matrix<double, 9, 9> cov;
    if (graph_ && graph_->has_imu_calibration() && graph_->ImuCalibrationCovariance(&cov)) {
      AddImuCalibration(graph.get(), imu_, &graph_->imu_calibration(), &cov);
    } else {
      AddImuCalibration(graph.get(), imu_);
    }
  }
  return graph;
}

bool SlidingWindowEstimator::GyroCalibration(Eigen::Matrix3d* E,
                                             Eigen::Matrix<double, 9, 9>* covariance) const {
  if (!graph_ || !graph_->has_imu_calibration()) return false;
  *E = Eigen::Map<const Eigen::Matrix3d>(graph_->imu_calibration().value);
  if (covariance != nullptr && !graph_->ImuCalibrationCovariance(covariance)) {
    covariance->setConstant(std::numeric_limits<double>::quiet_NaN());
  }
  return true;
}

bool SlidingWindowEstimator::SensorExtrinsic(SensorId sensor,
                                             Eigen::Quaterniond* q_b_s,
                                             Eigen::Vector3d* p_b_s,
                                             Eigen::Matrix<double, 6, 6>* covariance) const {
  if (sensor < 0 || static_cast<size_t>(sensor) >= sensors_.size() ||
      !graph_->has_extrinsic(sensor)) {
    return false;
  }
  const Extrinsic& e = graph_->extrinsic(sensor);
  *q_b_s = e.q_b_s();
  *p_b_s = e.p_b_s();
  if (covariance != nullptr && !graph_->ExtrinsicCovariance(sensor, covariance)) {
    covariance->setConstant(std::numeric_limits<double>::quiet_NaN());
  }
  return true;
}

bool SlidingWindowEstimator::SensorParameter(SensorId sensor,
                                             double* value,
                                             double* variance) const {
  if (sensor < 0 || static_cast<size_t>(sensor) >= sensors_.size() ||
      !graph_->has_sensor_parameter(sensor)) {
    return false;
  }
  *value = graph_->sensor_parameter(sensor).value[0];
  if (variance != nullptr && !graph_->SensorParameterVariance(sensor, variance)) {
    *variance = std::numeric_limits<double>::quiet_NaN();
  }
  return true;
}

void SlidingWindowEstimator::AddMeasurement(const SensorMeasurement& m) {
  if (m.sensor < 0 || static_cast<size_t>(m.sensor) >= sensors_.size()) {
    throw std::invalid_argument("AddMeasurement: sensor " + std::to_string(m.sensor) +
                                " is not registered");
  }
  CheckMeasurement(sensors_[m.sensor], m, &last_measurement_ns_[m.sensor]);
  const size_t index = sensor_log_.size();
  sensor_log_.push_back(m);
  sensor_decisions_.push_back({m.sensor, m.t_ns, SensorDecision::kDropped, 0, 0.0});
  if (!initialized_) {
    measurement_buffer_.push_back(index);
    return;
  }
  // The IMU is past its time already: on the newest keyframe when within the merge tolerance of
  // it, on a keyframe made now at the newest sample when within the tolerance of that; dropped
  // otherwise (the preintegration cannot be split in the past).
  if (m.t_ns <= last_sample_.t_ns) {
    const TimeNs newest_t = graph_->newest().t_ns;
    if (policy_.Merges(m.t_ns, newest_t)) {
      QueueMeasurement(index);
      solve_pending_ |= AttachDueMeasurements(graph_->newest(), newest_cov_);
    } else if (policy_.Merges(m.t_ns, last_sample_.t_ns) && last_sample_.t_ns > newest_t) {
      QueueMeasurement(index);
      CloseKeyframe(last_sample_, /*on_grid=*/false);
    } else {
      DropMeasurement(index);
    }
    return;
  }
  QueueMeasurement(index);
}

void SlidingWindowEstimator::QueueMeasurement(size_t index) {
  pending_measurements_.emplace(sensor_log_[index].t_ns, index);
}

void SlidingWindowEstimator::DropMeasurement(size_t index) {
  sensor_decisions_[index].decision = SensorDecision::kDropped;
  ++sensor_stats_[sensor_log_[index].sensor].dropped;
}

bool SlidingWindowEstimator::AttachDueMeasurements(const Keyframe& kf, const GraphCovariance& P) {
  bool added = false;
  sensor_reacquired_ = false;
  // After a sensor's re-acquisition the graph (and kf with it) is new: the rest wait for the
  // next keyframe.
  while (!sensor_reacquired_ && !pending_measurements_.empty() &&
         pending_measurements_.begin()->first <= kf.t_ns + policy_.merge_tolerance_ns()) {
    const auto [t, index] = *pending_measurements_.begin();
    pending_measurements_.erase(pending_measurements_.begin());
    if (policy_.Merges(t, kf.t_ns)) {
      added |= AttachMeasurement(index, kf, P);
    } else {
      DropMeasurement(index);  // older than the keyframe it could have had
    }
  }
  return added;
}

bool SlidingWindowEstimator::AttachMeasurement(size_t index,
                                               const Keyframe& kf,
                                               const GraphCovariance& P) {
  const SensorSpec& spec = sensors_[sensor_log_[index].sensor];
  if (!PrepareMeasurement(spec, &sensor_log_[index], kf.state(), kf.gyro_rad_s,
                          BlockConsumer::kWindow)) {
    DropMeasurement(index);  // the frontend cannot make the block at this keyframe
    return false;
  }
  const SensorMeasurement& m = sensor_log_[index];
  SensorRecord& record = sensor_decisions_[index];
  SensorStats& stats = sensor_stats_[m.sensor];
  std::vector<const double*> fixed;
  if (spec.has_extrinsic) {
    for (const BlockRef& b : ExtrinsicBlocks(m.sensor)) fixed.push_back(graph_->BlockValue(b));
  }
  // The gate holds the sensor's blocks at their estimates (conditional on them, as the
  // covariances are), but for an estimated parameter's own variance: a map number the window has
  // not learnt yet (a crest offset still at its prior) widens the innovation rather than having
  // the frames that would teach it rejected.
  std::vector<double> fixed_variances(fixed.size(), 0.0);
  if (spec.has_parameter) {
    fixed.push_back(graph_->BlockValue(SensorParameterBlock(m.sensor)));
    double variance = 0.0;
    if (!graph_->SensorParameterVariance(m.sensor, &variance)) variance = 0.0;
    fixed_variances.push_back(variance);
  }
  const bool heading_uncertain =
      spec.relocate_above_heading_sigma_rad > 0.0 &&
      std::sqrt(std::max(0.0, P(kRot + 2, kRot + 2))) > spec.relocate_above_heading_sigma_rad;
  const bool position_uncertain =
      spec.relocate_above_position_sigma_m > 0.0 &&
      std::sqrt(
          std::max(0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(P.block<2, 2>(kPos, kPos))
                            .eigenvalues()(1))) > spec.relocate_above_position_sigma_m;
  if (spec.relocate && (heading_uncertain || position_uncertain) && &kf == &graph_->newest() &&
      RelocateUncertain(index)) {
    return true;
  }
  Innovation in;
  bool evaluated = false;
  const bool gated_ok = BlockInnovation(*m.cost, m.slots, fixed, kf, P, &in, &evaluated,
                                        spec.gate_space, m.gate_scale, fixed_variances);
  if (!evaluated) {
    DropMeasurement(index);  // the cost cannot be evaluated at this keyframe
    return false;
  }
  record.dim = gated_ok ? in.dim : m.cost->num_residuals();
  record.d2 = gated_ok ? in.d2 : 0.0;  // S not positive definite: nothing to gate against
  if (spec.gate_probability > 0.0 && gated_ok &&
      in.d2 > ChiSquareQuantile(spec.gate_probability, record.dim)) {
    int& streak = sensor_reject_streak_[m.sensor];
    ++streak;
    if (spec.reacquire_after_rejections > 0 && streak >= spec.reacquire_after_rejections &&
        &kf == &graph_->newest()) {
      streak = 0;
      ReacquireSensor(index, in.d2);
      return true;
    }
    record.decision = SensorDecision::kRejectedByGate;
    ++stats.rejected;
    return false;
  }
  sensor_reject_streak_[m.sensor] = 0;
  record.decision = SensorDecision::kAccepted;
  ++stats.accepted;
  stats.nis_per_dof_sum_accepted += record.d2 / record.dim;
  graph_->AddSharedFactor(FactorKind::kSensor, m.cost, MakeLoss(spec.loss),
                          SensorBlocks(spec, m, kf.id));
  return true;
}

Innovation SlidingWindowEstimator::FixInnovation(const GnssFix& fix,
                                                 const Keyframe& kf,
                                                 const GraphCovariance& P,
                                                 MetricInnovation* metric) const {
  const TiedFix tied = TieFix(fix, kf, gnss_, imu_, earth_, config_.gnss_sigma_scale);
  const std::unique_ptr<ceres::CostFunction> cost = GnssPositionCost(fix, tied);
  Innovation in;
  if (!BlockInnovation(*cost, {Slot::kQ, Slot::kP, Slot::kV, Slot::kGb}, kf, P, &in)) {
    // A covariance that is not positive definite: nothing to gate against.
    in.dim = 3;
    in.d2 = 0.0;
    in.r.resize(0);
  }
  if (metric != nullptr) {
    // The factor whitens the local-level residual by the sigmas (GnssPositionFactor).
    if (in.r.size() == 3 && in.S.rows() == 3) {
      const auto sigma = tied.sigma_enu_m.asDiagonal();
      metric->y = sigma * in.r;
      metric->S = sigma * in.S * sigma;
      metric->R = tied.sigma_enu_m.cwiseAbs2().asDiagonal();
    } else {
      metric->y.setConstant(std::numeric_limits<double>::quiet_NaN());
    }
  }
  // log det of the innovation covariance in metres: whitening divided it by det R = prod sigma^2.
  in.log_det_s += 2.0 * tied.sigma_enu_m.array().log().sum();
  return in;
}

void SlidingWindowEstimator::AddFixFactor(const GnssFix& fix, const Keyframe& kf) {
  last_fix_accepted_ns_ = std::max(last_fix_accepted_ns_, fix.t_ns);
  const TiedFix tied = TieFix(fix, kf, gnss_, imu_, earth_, config_.gnss_sigma_scale);
  AddGnssPositionFactor(graph_.get(), fix, tied, kf.id, config_);
}

void SlidingWindowEstimator::Reinitialize(const GnssFix& fix, double motion_d2) {
  // The fixes have been rejected for gate_max_reject_s: the estimate has drifted away from them
  // by more than its covariance admits (an overconfident covariance after a linearisation
  // failure, a wrong bias, or a GNSS offset that has lasted too long to call a jump). Restart the
  // window from its newest estimate with the covariance scaled by lambda = d2 / 3, so that this
  // fix becomes a typical (chi2_3-mean) innovation, as a fading-memory filter does on divergence
  // (Fagin 1964; Brown & Hwang, "Introduction to Random Signals and Applied Kalman Filtering",
  // 4th ed., sec. 9.5). Only the navigation states and the GNSS drift are scaled: the fixes say
  // that the position (and the velocity and attitude that carried it there) are off, not what the
  // IMU's biases are. Scaling the biases too (capped at the dataset's bias priors) forgot what the
  // run had learned about them: on a MEMS IMU the gyro bias went back to its prior and the heading
  // wandered by degrees for minutes after a re-acquisition and into the next outage (harbour-
  // consumer, docs/results.md). The biases keep their covariance and their cross terms scale by
  // sqrt(lambda): a congruence, positive definite as before. A bias that is truly wrong still
  // shows in the innovations once the window has the fixes again (test_reacquisition.cc: from
  // 1.3 km off after an outage on a consumer IMU, back to 2 m within 60 s).
  // `motion_d2` 0: the window and the fix differ by a receiver's jump (gnss_jump_test.h: the
  // receiver back from a jump the window followed, or a jump that has lasted gate_max_reject_s).
  // The window's attitude, velocity and biases were carried by the IMU and are not in question:
  // only the position and the GNSS drift are scaled. A positive `motion_d2` is how far the window
  // itself had drifted from the receiver it followed: the attitude and velocity scale by that,
  // and the jump's part of this fix's innovation goes to the position alone (with the
  // attitude's and velocity's own scaling it would go through their correlation with the
  // position: 6 m/s of velocity for the 18 m of harbour-consumer seed 11's step back).
  const Keyframe& kf = graph_->newest();
  MetricInnovation metric;
  const double d2 = FixInnovation(fix, kf, newest_cov_, &metric).d2;
  const double lambda = std::max(1.0, d2 / 3.0);
  // Re-acquired on a jumped fix, the window follows the jump from now on (gnss_jump_test.h);
  // StartGraph forgets the rest.
  GnssJumpTest jump_test = jump_test_;
  jump_test.Reacquired(metric, gate_pos_);
  Eigen::Matrix<double, kGraphStateDim, 1> scale =
      Eigen::Matrix<double, kGraphStateDim, 1>::Constant(std::sqrt(lambda));
  scale.segment<3>(kBg).setOnes();
  scale.segment<3>(kBa).setOnes();
  const double motion_lambda = motion_d2 >= 0.0 ? std::max(1.0, motion_d2 / 3.0) : lambda;
  scale.segment<3>(kRot).setConstant(std::sqrt(motion_lambda));
  scale.segment<3>(kVel).setConstant(std::sqrt(motion_lambda));
  const GraphCovariance P = scale.asDiagonal() * newest_cov_ * scale.asDiagonal();
  const NavState s = kf.state();
  const Eigen::Vector3d gyro = kf.gyro_rad_s;
  if (motion_d2 >= 0.0) {
    spdlog::info(
        "t={:.3f}: GNSS and the window differ by a receiver's jump, window "
        "re-initialised (position covariance x {:.3g}, attitude and velocity x {:.3g})",
        NsToSeconds(fix.t_ns), lambda, motion_lambda);
  } else {
    spdlog::info(
        "t={:.3f}: GNSS rejected for {:.0f} s, window re-initialised (covariance x {:.3g})",
        NsToSeconds(fix.t_ns), config_.gnss_gate_max_reject_s, lambda);
  }

  // The GNSS drift restarts from its stationary distribution, as at the start.
  graph_ = MakeGraph();
  AddFixFactor(fix, StartGraph(s, gyro, P.topLeftCorner<kStateDim, kStateDim>()));
  jump_test_ = jump_test;
}

bool SlidingWindowEstimator::GnssHoldsPosition(TimeNs t) const {
  return last_fix_accepted_ns_ != std::numeric_limits<TimeNs>::min() &&
         NsToSeconds(t - last_fix_accepted_ns_) <= config_.gnss_gate_streak_max_gap_s;
}

GraphCovariance SlidingWindowEstimator::InflatedCovariance(double lambda) const {
  GraphCovariance P = lambda * newest_cov_;
  Eigen::Matrix<double, kGraphStateDim, 1> scale = Eigen::Matrix<double, kGraphStateDim, 1>::Ones();
  for (int i = 0; i < 3; ++i) {
    const double cap_bg = imu_.gyro_bias_prior_sigma_rad_s;
    const double cap_ba = imu_.accel_bias_prior_sigma_m_s2;
    const double s_bg = std::sqrt(P(kBg + i, kBg + i)), s_ba = std::sqrt(P(kBa + i, kBa + i));
    if (s_bg > cap_bg && cap_bg > 0.0) scale[kBg + i] = cap_bg / s_bg;
    if (s_ba > cap_ba && cap_ba > 0.0) scale[kBa + i] = cap_ba / s_ba;
  }
  return scale.asDiagonal() * P * scale.asDiagonal();  // a congruence: stays positive definite
}

void SlidingWindowEstimator::ReacquireSensor(size_t index, double d2) {
  // The sensor's blocks have been rejected reacquire_after_rejections times in a row: the
  // estimate has left what the sensor sees by more than its covariance admits. As for GNSS
  // (Reinitialize), restart from the newest estimate with the covariance scaled so that this
  // block is a typical innovation, lambda = d2 / dim; if the sensor can locate the vessel on its
  // own (relocate), its pose and covariance replace the estimate's first.
  const SensorMeasurement& m = sensor_log_[index];
  const SensorSpec& spec = sensors_[m.sensor];
  SensorRecord& record = sensor_decisions_[index];
  SensorStats& stats = sensor_stats_[m.sensor];
  const Keyframe& kf = graph_->newest();
  const double lambda = std::max(1.0, d2 / std::max(1, record.dim));
  GraphCovariance P = InflatedCovariance(lambda);
  NavState s = kf.state();
  const Eigen::Vector3d gyro = kf.gyro_rad_s;
  std::string how = fmt::format("covariance x {:.3g}", lambda);
  if (spec.relocate) {
    if (const std::optional<Relocation> r =
            spec.relocate(m, s, P.topLeftCorner<kStateDim, kStateDim>(), true)) {
      // The pose is the sensor's now (its orientation only while GNSS holds the position): no
      // correlation left with velocity and biases.
      const int n = GnssHoldsPosition(m.t_ns) ? 3 : 6;
      const Eigen::Matrix<double, 6, 6> c = 0.5 * (r->covariance + r->covariance.transpose());
      s.q_w_b = r->q_w_b.normalized();
      if (n == 6) s.p_w_b = r->p_w_b;
      P.middleRows(kRot, n).setZero();
      P.middleCols(kRot, n).setZero();
      P.block(kRot, kRot, n, n) = c.topLeftCorner(n, n);
      how = "relocated (" + r->reason +
            (n == 3 ? ", orientation only: GNSS holds the position" : "") + ")";
    }
  }
  spdlog::info("t={:.3f}: {} rejected {} times in a row, window re-initialised, {}",
               NsToSeconds(m.t_ns), spec.name, spec.reacquire_after_rejections, how);
  graph_ = MakeGraph();
  const Keyframe& nk = StartGraph(s, gyro, P.topLeftCorner<kStateDim, kStateDim>());
  graph_->AddSharedFactor(FactorKind::kSensor, m.cost, MakeLoss(spec.loss),
                          SensorBlocks(spec, m, nk.id));
  record.decision = SensorDecision::kAccepted;
  record.reacquired = true;
  ++stats.accepted;
  ++stats.reacquired;
  sensor_reacquired_ = true;
}

bool SlidingWindowEstimator::RelocateUncertain(size_t index) {
  // The estimate's heading is too uncertain for the sensor's narrow basin: the sensor locates
  // the vessel on its own around the estimate; its orientation (and its position, where it is
  // the better known) replaces the estimate's, correlations with the rest dropped, and the
  // window restarts there with the block.
  const SensorMeasurement& m = sensor_log_[index];
  const SensorSpec& spec = sensors_[m.sensor];
  const Keyframe& kf = graph_->newest();
  GraphCovariance P = newest_cov_;
  NavState s = kf.state();
  const Eigen::Vector3d gyro = kf.gyro_rad_s;
  const std::optional<Relocation> r =
      spec.relocate(m, s, P.topLeftCorner<kStateDim, kStateDim>(), false);
  if (!r) return false;
  const Eigen::Matrix<double, 6, 6> c = 0.5 * (r->covariance + r->covariance.transpose());
  s.q_w_b = r->q_w_b.normalized();
  P.middleRows<3>(kRot).setZero();
  P.middleCols<3>(kRot).setZero();
  P.block<3, 3>(kRot, kRot) = c.topLeftCorner<3, 3>();
  // The sensor's position too where it is the better known, or where the two disagree beyond
  // their joint uncertainty (chi-square, 2 DOF, 99.9 %): then the estimate's was wrong. Never
  // while GNSS holds the position: a camera's single-frame range is the weaker of the two, and
  // a wrong relocation must not override a receiver that is being accepted.
  const Eigen::Vector2d dp = (r->p_w_b - s.p_w_b).head<2>();
  const Eigen::Matrix2d joint = c.block<2, 2>(3, 3) + newest_cov_.block<2, 2>(kPos, kPos) +
                                1e-6 * Eigen::Matrix2d::Identity();
  // (A sensor whose relocation is a map alignment to decimetres may replace a drifting
  // receiver's position where it is the better known: relocate_position_over_gnss.)
  const bool better = c(3, 3) + c(4, 4) < P(kPos, kPos) + P(kPos + 1, kPos + 1);
  const bool disagree = dp.dot(joint.ldlt().solve(dp)) > 13.8;
  const bool position =
      GnssHoldsPosition(m.t_ns) ? spec.relocate_position_over_gnss && better : better || disagree;
  if (position) {
    s.p_w_b = r->p_w_b;
    P.middleRows<3>(kPos).setZero();
    P.middleCols<3>(kPos).setZero();
    P.block<3, 3>(kPos, kPos) = c.bottomRightCorner<3, 3>();
  }
  spdlog::info("t={:.3f}: {}: heading sigma {:.2f} deg, position sigma {:.2f} m, relocated ({}{})",
               NsToSeconds(m.t_ns), spec.name,
               std::sqrt(newest_cov_(kRot + 2, kRot + 2)) * 180.0 / M_PI,
               std::sqrt(newest_cov_(kPos, kPos) + newest_cov_(kPos + 1, kPos + 1)), r->reason,
               position ? ", position too" : "");
  graph_ = MakeGraph();
  const Keyframe& nk = StartGraph(s, gyro, P.topLeftCorner<kStateDim, kStateDim>());
  graph_->AddSharedFactor(FactorKind::kSensor, m.cost, MakeLoss(spec.loss),
                          SensorBlocks(spec, m, nk.id));
  SensorRecord& record = sensor_decisions_[index];
  record.dim = m.cost->num_residuals();
  record.decision = SensorDecision::kAccepted;
  record.reacquired = true;
  ++sensor_stats_[m.sensor].accepted;
  ++sensor_stats_[m.sensor].reacquired;
  sensor_reject_streak_[m.sensor] = 0;
  sensor_reacquired_ = true;
  return true;
}

void SlidingWindowEstimator::WidenHeading(double sigma_rad) {
  const double add = sigma_rad * sigma_rad - newest_cov_(kRot + 2, kRot + 2);
  if (!initialized_ || !(add > 0.0)) return;
  newest_cov_(kRot + 2, kRot + 2) += add;
  NewestCovarianceChanged();
}

void SlidingWindowEstimator::Rebase() {
  if (!initialized_) return;
  const Keyframe& kf = graph_->newest();
  const NavState s = kf.state();
  const Eigen::Vector3d gyro = kf.gyro_rad_s;
  const Eigen::Vector3d gb = kf.gnss_bias();
  const bool drift = config_.gnss_drift.enabled();
  const int dim = drift ? kGraphStateDim : kStateDim;
  const Eigen::MatrixXd P = newest_cov_.topLeftCorner(dim, dim);

  graph_ = MakeGraph();
  newest_drift_factor_ = -1;  // the newest keyframe is the first: no transition into it
  Keyframe& nk = graph_->AddKeyframe(s, gyro);
  std::vector<BlockRef> blocks = KeyframeBlocks(nk.id);
  std::vector<int> sizes = {4, 3, 3, 3, 3};
  std::vector<Eigen::VectorXd> x0 = {Eigen::Vector4d(s.q_w_b.coeffs()), s.p_w_b, s.v_w, s.bg, s.ba};
  if (drift) {
    std::copy_n(gb.data(), 3, nk.gb);
    blocks.push_back({nk.id, Slot::kGb});
    sizes.push_back(3);
    x0.emplace_back(gb);
  }
  // Information P^-1 at the current estimate: r = P^-1/2 (x (-) x0).
  const Eigen::MatrixXd H = P.ldlt().solve(Eigen::MatrixXd::Identity(dim, dim));
  auto prior = LinearPriorFactor::FromInformation(sizes, x0, 0.5 * (H + H.transpose()),
                                                  Eigen::VectorXd::Zero(dim));
  if (!prior) throw std::logic_error("Rebase: the newest covariance carries no information");
  graph_->AddFactor(FactorKind::kMarginalPrior, std::move(prior), nullptr, blocks);
}

bool SlidingWindowEstimator::AttachFix(const GnssFix& fix,
                                       const Keyframe& kf,
                                       const GraphCovariance& P,
                                       FixRecord* record) {
  record->t_ns = fix.t_ns;
  const bool use_heading = fix.has_heading && config_.use_gnss_heading;
  record->heading = use_heading ? HeadingDecision::kLeftOut : HeadingDecision::kNone;
  // Position: innovation gate y^T S^-1 y < chi2_3(p).
  MetricInnovation metric;
  Innovation in = FixInnovation(fix, kf, P, &metric);
  const double previous_d2 = last_fix_d2_;
  last_fix_d2_ = in.d2;
  ++gnss_stats_.innovations;
  gnss_stats_.log_likelihood -= 0.5 * (std::min(in.d2, GnssStats::kLikelihoodNisCap) +
                                       in.log_det_s + 3.0 * std::log(2.0 * M_PI));
  // A streak of rejections: broken by an accepted fix, or by a gap without fixes longer than
  // gate_streak_max_gap_s (an outage is not time spent rejecting).
  const bool in_streak =
      reject_streak_start_ns_ >= 0 &&
      NsToSeconds(fix.t_ns - last_rejected_ns_) <= config_.gnss_gate_streak_max_gap_s;
  const bool gated = gate_pos_ > 0.0 && in.d2 > gate_pos_;
  // Whether the receiver's jump outstanding explains the fix better (gnss_jump_test.h): then it
  // is refused, also inside the gate.
  bool as_jump = false;
  bool back_in_streak = false;  // the receiver stepped back from a jump the window followed
  if (in_streak && config_.gnss_jump_test) {
    back_in_streak = jump_test_.Observe(fix.t_ns, metric, gate_pos_);
    as_jump = jump_test_.Explains(metric, in.d2, gate_pos_);
  }
  const bool reject = gated || as_jump;
  bool stepped = false;
  if (reject) {
    bool back_from_jump = back_in_streak;
    if (!in_streak) {
      reject_streak_start_ns_ = fix.t_ns;
      back_from_jump =
          jump_test_.StreakStarted(fix.t_ns, metric, gate_pos_,
                                   config_.gnss_gate_streak_max_gap_s) == StreakStart::kBack &&
          config_.gnss_jump_test;
    }
    last_rejected_ns_ = fix.t_ns;
    if (back_from_jump ||
        NsToSeconds(fix.t_ns - reject_streak_start_ns_) > config_.gnss_gate_max_reject_s) {
      // The window re-initialises around this fix once the keyframe's factors are in (its
      // dual-antenna heading, if any, is left out: the next fixes bring theirs).
      record->position = FixDecision::kAcceptedOnReacquisition;
      reject_streak_start_ns_ = -1;
      ++gnss_stats_.reacquired;
      if (back_from_jump) ++gnss_stats_.reacquired_back_from_jump;
      reacquisition_fix_ = fix;
      // Back from a jump, or onto a jump that has lasted gate_max_reject_s (the fix is explained
      // by it): the window and the fix differ by the receiver's jump alone. When the receiver
      // stepped back inside a streak the window's own drift opened, the jumped fixes it took
      // pulled its velocity as well (harbour-consumer seed 11: 1.4 m/s; restarted on the
      // position alone, the window was rejected again within a second): the attitude and
      // velocity are then widened by how far off the window was from the jumped receiver it
      // followed, the previous fix's innovation, not by the jump's.
      reacquire_motion_d2_ = back_in_streak                ? previous_d2
                             : (back_from_jump || as_jump) ? 0.0
                                                           : -1.0;
      return false;
    }
    // The jump, once it has explained the streak long enough, taken into the receiver's drift:
    // this fix and the next are taken against it.
    stepped = config_.gnss_jump_as_drift_step && StepDriftAcrossJump(fix, kf, &in, &metric);
    if (!stepped) {
      record->position = FixDecision::kRejectedByGate;
      ++gnss_stats_.rejected;
      if (as_jump && !gated) ++gnss_stats_.rejected_as_jump;
      if (use_heading) ++gnss_stats_.heading_rejected;
      return false;
    }
  }
  reject_streak_start_ns_ = -1;
  if (stepped) {
    jump_test_.Absorbed(fix.t_ns, metric);
  } else {
    jump_test_.Accepted(fix.t_ns, metric, gate_pos_);
  }
  record->position = FixDecision::kAccepted;
  if (!drift_stepped_m_.isZero()) {
    // Offset by the jumps taken in, unless they have stepped back (their sum within the gate of
    // its covariance and two draws of the receiver's noise).
    const std::optional<double> d2_stepped =
        SquaredMahalanobis<3>(drift_stepped_m_, drift_stepped_cov_ + 2.0 * metric.R);
    record->across_jump = !d2_stepped || *d2_stepped > gate_pos_;
  }
  ++gnss_stats_.accepted;
  gnss_stats_.nis_sum_accepted += in.d2;
  AddFixFactor(fix, kf);
  if (use_heading) {
    const TiedFix tied = TieFix(fix, kf, gnss_, imu_, earth_, config_.gnss_sigma_scale);
    const std::unique_ptr<ceres::CostFunction> cost = GnssHeadingCost(fix, tied);
    Innovation hin;
    const bool gated = gate_heading_ > 0.0 && BlockInnovation(*cost, {Slot::kQ}, kf, P, &hin) &&
                       hin.d2 > gate_heading_;
    if (gated) {
      record->heading = HeadingDecision::kRejectedByGate;
      ++gnss_stats_.heading_rejected;
    } else {
      record->heading = HeadingDecision::kAccepted;
      ++gnss_stats_.heading_accepted;
      AddGnssHeadingFactor(graph_.get(), fix, tied, kf.id, config_);
    }
  }
  return true;
}

bool SlidingWindowEstimator::StepDriftAcrossJump(const GnssFix& fix,
                                                 const Keyframe& kf,
                                                 Innovation* in,
                                                 MetricInnovation* metric) {
  // One step per transition, into the newest keyframe only (the transitions before it have fixes
  // on both sides already).
  if (!config_.gnss_drift.enabled() || newest_drift_factor_ < 0 || newest_drift_stepped_ ||
      &kf != &graph_->newest() || graph_->num_keyframes() < 2) {
    return false;
  }
  JumpStep step;
  if (!jump_test_.Step(fix.t_ns, kJumpStepMinFixes, config_.gnss_jump_step_after_s, gate_pos_,
                       &step)) {
    return false;
  }
  const std::vector<KeyframeId> ids = graph_->keyframe_ids();
  const Keyframe& prev = graph_->keyframe(ids[ids.size() - 2]);
  Keyframe& nk = graph_->newest();
  // The innovations are in the fix's local level frame, the drift in the world's.
  const TiedFix tied = TieFix(fix, nk, gnss_, imu_, earth_, config_.gnss_sigma_scale);
  const Eigen::Vector3d step_w = tied.R_n_w.transpose() * step.step_m;
  // The jump's estimate shares the window's own error (its mean innovation is measured against
  // the window's prediction), so with its covariance alone the fixes after it would hand the
  // window back its own estimate as a measurement and count it twice. The drift after a jump is
  // taken as drawn anew from its stationary distribution, as at the start (StartGraph): what the
  // step says of the absolute position is then no more than a restarted drift says, and the fixes
  // after it keep their relative information. (On the matched IMU + GNSS harbour: ANEES 4.53 with
  // the estimate's covariance alone, 4.37 with the stationary part, 2.98 refusing the jump; the
  // rest is the drift's continuity the steps break, docs/results.md.)
  const Eigen::Matrix3d cov_w =
      tied.R_n_w.transpose() * step.cov * tied.R_n_w +
      Eigen::Matrix3d(config_.gnss_drift.StationarySigma().array().square().matrix().asDiagonal());
  const double dt_s = NsToSeconds(nk.t_ns - prev.t_ns);
  if (!SetNewestDriftTransition(prev.id, nk.id, dt_s, step_w, cov_w)) {
    return false;  // a covariance that whitens nothing: the fix stays refused
  }
  const Eigen::Vector3d gb_before = nk.gnss_bias();
  const GraphCovariance cov_before = newest_cov_;
  // b_j = phi (b_i - J) + J + s + w: the drift and its covariance move by the step, which is
  // independent of the rest.
  for (int a = 0; a < 3; ++a) nk.gb[a] += step_w[a];
  newest_cov_.block<3, 3>(kGraphGb, kGraphGb) += cov_w;
  NewestCovarianceChanged();
  MetricInnovation after;
  const Innovation in_after = FixInnovation(fix, nk, newest_cov_, &after);
  if (gate_pos_ > 0.0 && !(in_after.d2 <= gate_pos_)) {
    // Not explained after all: back to the transition without the step.
    SetNewestDriftTransition(prev.id, nk.id, dt_s, Eigen::Vector3d::Zero(),
                             Eigen::Matrix3d::Zero());
    std::copy_n(gb_before.data(), 3, nk.gb);
    newest_cov_ = cov_before;
    NewestCovarianceChanged();
    return false;
  }
  newest_drift_stepped_ = true;
  drift_stepped_m_ += step_w;
  drift_stepped_cov_ += cov_w;
  ++gnss_stats_.drift_steps;
  spdlog::info(
      "t={:.3f}: the receiver jumped by ({:.2f}, {:.2f}, {:.2f}) m east, north, up (over {} "
      "fixes): taken into its drift as a step",
      NsToSeconds(fix.t_ns), step_w.x(), step_w.y(), step_w.z(), step.fixes);
  *in = in_after;
  *metric = after;
  return true;
}

bool SlidingWindowEstimator::SetNewestDriftTransition(KeyframeId prev,
                                                      KeyframeId next,
                                                      double dt_s,
                                                      const Eigen::Vector3d& step_m,
                                                      const Eigen::Matrix3d& step_cov) {
  // b_j = phi b_i + (1 - phi) J + s + w (gnss_drift_step_factor.h with the step (1 - phi) J + s):
  // the jumps taken in so far, J, stay while the drift around them decays.
  const double phi = std::exp(-std::max(dt_s, 1e-6) / config_.gnss_drift.tau_s);
  const Eigen::Vector3d offset = (1.0 - phi) * drift_stepped_m_ + step_m;
  std::unique_ptr<ceres::CostFunction> cost;
  if (offset.isZero() && step_cov.isZero()) {
    cost = std::make_unique<GnssDriftFactor>(config_.gnss_drift, dt_s);
  } else {
    try {
      cost = std::make_unique<GnssDriftStepFactor>(config_.gnss_drift, dt_s, offset, step_cov);
    } catch (const std::invalid_argument&) {
      return false;
    }
  }
  graph_->RemoveFactor(newest_drift_factor_);
  newest_drift_factor_ = graph_->AddFactor(FactorKind::kGnssDrift, std::move(cost), nullptr,
                                           {{prev, Slot::kGb}, {next, Slot::kGb}});
  return true;
}

FixRecord SlidingWindowEstimator::DroppedFix(const GnssFix& fix) const {
  return DroppedFixRecord(fix, config_.use_gnss_heading);
}

void SlidingWindowEstimator::UpdateNewestCovariance() {
  GraphCovariance P;
  if (graph_->NewestCovariance(&P)) {
    newest_cov_ = P;
    NewestCovarianceChanged();
  }
}

void SlidingWindowEstimator::NewestCovarianceChanged() {
  newest_cov_finite_ = NavBlock(newest_cov_).allFinite();
}

void SlidingWindowEstimator::CloseKeyframe(const ImuSample& sample, bool on_grid) {
  const auto t_start = std::chrono::steady_clock::now();
  UpdateStats st;
  st.t_ns = sample.t_ns;
  const Keyframe& prev = graph_->newest();
  const KeyframeId prev_id = prev.id;
  const NavState si = prev.state();
  // Predict the new keyframe through the preintegration and add its factors.
  NavState sj = si;
  sj.t_ns = sample.t_ns;
  Eigen::Vector3d gyro_j;
  if (recent_samples_.back().t_ns == sample.t_ns) {
    gyro_j = KeyframeGyro(recent_samples_.begin(), recent_samples_.end());
  } else {  // a keyframe between two recorded samples: they and the interpolated one at its time
    std::vector<ImuSample> recent(recent_samples_.begin(), recent_samples_.end());
    recent.push_back(sample);
    gyro_j = KeyframeGyro(recent.begin(), recent.end());
  }
  const ImuEarthTerms earth_terms = EarthTermsNear(earth_, si.p_w_b);
  // With the gyro's calibration estimated, the prediction takes it as the IMU factor will.
  PredictBodyState(*pim_, imu_, earth_terms, prev.gyro_rad_s, gyro_j, si.q_w_b, si.p_w_b, si.v_w,
                   si.bg, si.ba, &sj.q_w_b, &sj.p_w_b, &sj.v_w,
                   graph_->has_imu_calibration() ? graph_->imu_calibration().value : nullptr);
  Keyframe& kf = graph_->AddKeyframe(sj, gyro_j);
  if (config_.gnss_drift.enabled()) {
    // The receiver's drift predicted as its model has it, b_j = phi b_i (gnss_drift_factor.h),
    // not zero: the gate weighs the keyframe's fixes against the drift the window has learnt.
    // Jumps taken in as steps, J, do not decay with it: b_j = phi (b_i - J) + J.
    const double phi = std::exp(-NsToSeconds(sj.t_ns - si.t_ns) / config_.gnss_drift.tau_s);
    for (int a = 0; a < 3; ++a) kf.gb[a] = phi * prev.gb[a] + (1.0 - phi) * drift_stepped_m_[a];
  }
  const KeyframeId id = kf.id;
  newest_drift_factor_ = AddMotionFactors(graph_.get(), prev_id, id, *pim_, imu_, prev.gyro_rad_s,
                                          gyro_j, earth_terms, config_.gnss_drift);
  newest_drift_stepped_ = false;
  if (newest_drift_factor_ >= 0 && !drift_stepped_m_.isZero()) {
    const double dt_s = NsToSeconds(sj.t_ns - si.t_ns);
    SetNewestDriftTransition(prev_id, id, dt_s, Eigen::Vector3d::Zero(), Eigen::Matrix3d::Zero());
  }
  const GraphCovariance prev_cov = newest_cov_;
  GraphCovariance P_new;
  if (graph_->PropagateCovariance(prev_id, id, newest_cov_, &P_new)) {
    newest_cov_ = P_new;
    NewestCovarianceChanged();
  }

  // Attach the fixes that are due, each to the nearer of the previous and the new keyframe and
  // gated with that keyframe's covariance. A fix more than half a period before the previous
  // keyframe came too late for the keyframe it belonged to and is dropped (counted). After a
  // re-acquisition fix the rest wait for the re-initialised graph (the next keyframe).
  bool measured = false;
  while (!reacquisition_fix_ && !pending_fixes_.empty() &&
         pending_fixes_.front().t_ns <= sample.t_ns) {
    const GnssFix fix = pending_fixes_.front();
    pending_fixes_.pop_front();
    if (fix.t_ns < si.t_ns - keyframe_period_ns_ / 2) {
      ++gnss_stats_.dropped;
      fix_decisions_.push_back(DroppedFix(fix));
      continue;
    }
    FixRecord record;
    const bool nearer_prev = (fix.t_ns - si.t_ns) < (sample.t_ns - fix.t_ns);
    measured |= nearer_prev ? AttachFix(fix, graph_->keyframe(prev_id), prev_cov, &record)
                            : AttachFix(fix, graph_->keyframe(id), newest_cov_, &record);
    fix_decisions_.push_back(record);
  }
  if (reacquisition_fix_) {
    Reinitialize(*reacquisition_fix_, reacquire_motion_d2_);
    reacquisition_fix_.reset();
    measured = true;
  }
  // Sensor blocks at this keyframe's time (a re-initialised graph's newest is this keyframe).
  measured |= AttachDueMeasurements(graph_->newest(), newest_cov_);
  measured |= solve_pending_;
  solve_pending_ = false;

  // Marginalise what leaves the window, then solve.
  while (static_cast<int>(graph_->num_keyframes()) > config_.window_keyframes ||
         (config_.window_s > 0.0 && graph_->num_keyframes() > 2 &&
          NsToSeconds(sample.t_ns - graph_->oldest().t_ns) > config_.window_s)) {
    graph_->MarginalizeOldest(config_.first_estimate_jacobians);
  }
  if (measured) {
    const auto t_solve = std::chrono::steady_clock::now();
    const ceres::Solver::Summary summary = graph_->Solve(config_.ceres);
    st.solve_ms = MsSince(t_solve);
    st.iterations = StepsTried(summary);
    st.solved = true;
    st.solve_usable = summary.IsSolutionUsable();
    // The gate and re-acquisition need the newest covariance whether or not outputs carry it.
    if (config_.compute_covariance || gate_pos_ > 0.0 || AnySensorGate()) {
      UpdateNewestCovariance();
    }
  }
  // Next interval, linearised at the newest bias estimate.
  const NavState newest = graph_->newest().state();
  pim_ = std::make_unique<ImuPreintegration>(imu_.noise, newest.bg, newest.ba,
                                             graph_->has_imu_calibration());
  policy_.Closed(sample.t_ns, on_grid);
  outputs_.push_back({newest, config_.compute_covariance, NavBlock(newest_cov_)});
  st.update_ms = MsSince(t_start);
  stats_.push_back(st);
}

namespace {

// Moves the elements of `from` stamped before `t_ns` (a prefix: they are in time order) to the
// end of `to`; returns how many.
template <typename T, typename Time>
size_t MovePrefixBefore(TimeNs t_ns, Time time_of, std::vector<T>* from, std::vector<T>* to) {
  const auto end =
      std::find_if(from->begin(), from->end(), [&](const T& x) { return time_of(x) >= t_ns; });
  const size_t n = static_cast<size_t>(end - from->begin());
  to->insert(to->end(), std::make_move_iterator(from->begin()), std::make_move_iterator(end));
  from->erase(from->begin(), end);
  return n;
}

}  // namespace

size_t SlidingWindowEstimator::TakeHistoryBefore(TimeNs t_ns, EstimatorHistory* out) {
  MovePrefixBefore(
      t_ns, [](const EstimateRecord& r) { return r.state.t_ns; }, &outputs_, &out->outputs);
  MovePrefixBefore(
      t_ns, [](const UpdateStats& u) { return u.t_ns; }, &stats_, &out->stats);
  return MovePrefixBefore(
      t_ns, [](const FixRecord& r) { return r.t_ns; }, &fix_decisions_, &out->decisions);
}

bool SlidingWindowEstimator::Latest(EstimateRecord* out) const {
  if (!initialized_) return false;
  *out = {graph_->newest().state(), config_.compute_covariance, NavBlock(newest_cov_)};
  return true;
}

bool SlidingWindowEstimator::LatestFinite() const {
  if (!initialized_) return true;
  const NavState s = graph_->newest().state();  // as Latest gives it (q normalised)
  return s.p_w_b.allFinite() && s.v_w.allFinite() && s.q_w_b.coeffs().allFinite() &&
         s.bg.allFinite() && s.ba.allFinite() &&
         (!config_.compute_covariance || newest_cov_finite_);
}

}  // namespace skerry
