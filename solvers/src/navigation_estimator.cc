#include "skerry/solvers/navigation_estimator.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "skerry/core/time_order.h"
#include "skerry/io/csv_reader.h"
#include "skerry/solvers/measurement_checks.h"

namespace skerry {

namespace {

// IMU kept before the start, for a fall-back to align (its rest detection looks at the start).
constexpr double kKeepBeforeStartS = 60.0;
// IMU replayed into an estimator restarted by the watchdog.
constexpr double kRestartImuS = 1.0;
// Bias priors are widened this much at each restart, up to the caps.
constexpr double kRestartBiasScale = 10.0;
constexpr double kMaxGyroBiasPriorRadS = 0.2;
constexpr double kMaxAccelBiasPriorMs2 = 1.0;

bool Finite(const EstimateRecord& r) {
  return r.state.p_w_b.allFinite() && r.state.v_w.allFinite() &&
         r.state.q_w_b.coeffs().allFinite() && r.state.bg.allFinite() && r.state.ba.allFinite() &&
         (!r.has_covariance || r.covariance.allFinite());
}

template <typename T>
void TrimBefore(TimeNs t_ns, std::vector<T>* v) {
  auto it = std::find_if(v->begin(), v->end(), [t_ns](const T& x) { return x.t_ns >= t_ns; });
  v->erase(v->begin(), it);
}

}  // namespace

NavigationEstimator::NavigationEstimator(const EstimatorConfig& config,
                                         const ImuConfig& imu,
                                         const GnssConfig& gnss,
                                         const EarthModel& earth)
    : config_((ValidateEstimatorConfig(config), config)),  // once: every restart builds from it
      imu_(imu),
      gnss_(gnss),
      earth_(earth) {
  aligning_ = config_.init.mode == "align";
  StartEngine();
}

NavigationEstimator::~NavigationEstimator() = default;

ImuConfig NavigationEstimator::EngineImu() const {
  ImuConfig imu = imu_;
  imu.gyro_bias_prior_sigma_rad_s =
      std::min(imu.gyro_bias_prior_sigma_rad_s * bias_prior_scale_,
               std::max(kMaxGyroBiasPriorRadS, imu.gyro_bias_prior_sigma_rad_s));
  imu.accel_bias_prior_sigma_m_s2 =
      std::min(imu.accel_bias_prior_sigma_m_s2 * bias_prior_scale_,
               std::max(kMaxAccelBiasPriorMs2, imu.accel_bias_prior_sigma_m_s2));
  return imu;
}

void NavigationEstimator::StartEngine() {
  window_.reset();
  bank_.reset();
  engine_fixes_.clear();
  engine_measurements_.clear();
  seen_decisions_ = 0;
  reacquisitions_.clear();
  lockout_starts_.clear();
  streak_start_ns_ = -1;
  last_decided_ns_ = -1;
  recent_outcomes_.clear();
  EstimatorConfig config = config_;
  // A restarted estimator has no given state: it starts from the data (a window that was given
  // its state in init.mode align, too; an aligning engine aligns again).
  if (restarts_ > 0 && !aligning_ &&
      (config.init.mode == "given" || config.init.mode == "align" ||
       config.init.mode == "skyline" || config.init.mode == "lidar")) {
    config.init.mode = "auto";
  }
  engine_mode_ = config.init.mode;
  if (aligning_) {
    bank_ =
        std::make_unique<YawHypothesisBank>(config, EngineImu(), gnss_, earth_, ConfigValidated());
    for (const SensorSpec& spec : sensors_) bank_->RegisterSensor(spec);
  } else {
    window_ = std::make_unique<SlidingWindowEstimator>(config, EngineImu(), gnss_, earth_,
                                                       ConfigValidated());
    for (const SensorSpec& spec : sensors_) window_->RegisterSensor(spec);
  }
}

SensorId NavigationEstimator::RegisterSensor(const SensorSpec& spec) {
  if (last_imu_ns_ != std::numeric_limits<TimeNs>::min() ||
      last_gnss_ns_ != std::numeric_limits<TimeNs>::min() || !sensor_log_.empty()) {
    throw std::logic_error("RegisterSensor after the first measurement");
  }
  sensors_.push_back(spec);
  last_measurement_ns_.push_back(std::numeric_limits<TimeNs>::min());
  if (window_) window_->RegisterSensor(spec);
  if (bank_) bank_->RegisterSensor(spec);
  return static_cast<SensorId>(sensors_.size() - 1);
}

void NavigationEstimator::AddMeasurement(const SensorMeasurement& m) {
  if (m.sensor < 0 || static_cast<size_t>(m.sensor) >= sensors_.size()) {
    throw std::invalid_argument("AddMeasurement: sensor " + std::to_string(m.sensor) +
                                " is not registered");
  }
  CheckMeasurement(sensors_[m.sensor], m, &last_measurement_ns_[m.sensor]);
  const size_t index = sensor_log_.size();
  sensor_log_.push_back(m);
  sensor_records_.push_back({m.sensor, m.t_ns, SensorDecision::kDropped, 0, 0.0});
  if (status_ == Status::kDiverged) return;  // its record reads kDropped
  if (status_ == Status::kStarting) {
    measurements_unstarted_.push_back(index);
    while (sensor_log_[measurements_unstarted_.front()].t_ns <
           m.t_ns - SecondsToNs(kKeepBeforeStartS)) {
      measurements_unstarted_.erase(measurements_unstarted_.begin());
    }
  }
  FeedEngine(index);
}

void NavigationEstimator::FeedEngine(size_t measurement) {
  engine_measurements_.push_back(measurement);
  if (window_) window_->AddMeasurement(sensor_log_[measurement]);
  if (bank_) bank_->AddMeasurement(sensor_log_[measurement]);
}

std::vector<SensorStats> NavigationEstimator::sensor_stats() const {
  // From the records, so that the counts and the decisions always agree: a block that no engine
  // decided (pending at a restart or at the end, given before any start, or after the estimator
  // gave up) reads kDropped and counts as dropped.
  std::vector<SensorStats> all(sensors_.size());
  for (const SensorRecord& r : sensor_decisions()) {
    SensorStats& st = all.at(r.sensor);
    switch (r.decision) {
      case SensorDecision::kAccepted:
        ++st.accepted;
        st.reacquired += r.reacquired;
        if (r.dim > 0) st.nis_per_dof_sum_accepted += r.d2 / r.dim;
        break;
      case SensorDecision::kRejectedByGate:
        ++st.rejected;
        break;
      case SensorDecision::kDropped:
        ++st.dropped;
        break;
    }
  }
  return all;
}

std::vector<SensorRecord> NavigationEstimator::sensor_decisions() const {
  std::vector<SensorRecord> all = sensor_records_;
  if (const SlidingWindowEstimator* w = Running()) {
    const std::vector<SensorRecord>& d = w->sensor_decisions();
    // The running engine was given engine_measurements_ in order; the bank's winner was given
    // them too (buffered before its start).
    for (size_t k = 0; k < d.size() && k < engine_measurements_.size(); ++k) {
      all[engine_measurements_[k]] = d[k];
    }
  }
  return all;
}

bool NavigationEstimator::SensorExtrinsic(SensorId sensor,
                                          Eigen::Quaterniond* q_b_s,
                                          Eigen::Vector3d* p_b_s,
                                          Eigen::Matrix<double, 6, 6>* covariance) const {
  const SlidingWindowEstimator* w = Running();
  return w != nullptr && w->SensorExtrinsic(sensor, q_b_s, p_b_s, covariance);
}

bool NavigationEstimator::SensorParameter(SensorId sensor, double* value, double* variance) const {
  const SlidingWindowEstimator* w = Running();
  return w != nullptr && w->SensorParameter(sensor, value, variance);
}

bool NavigationEstimator::GyroCalibration(Eigen::Matrix3d* E,
                                          Eigen::Matrix<double, 9, 9>* covariance) const {
  const SlidingWindowEstimator* w = Running();
  return w != nullptr && w->GyroCalibration(E, covariance);
}

void NavigationEstimator::SetInitialState(const NavState& state,
                                          const StateCovariance& covariance) {
  if (last_imu_ns_ != std::numeric_limits<TimeNs>::min() ||
      last_gnss_ns_ != std::numeric_limits<TimeNs>::min()) {
    throw std::logic_error("SetInitialState after the first measurement");
  }
  aligning_ = false;  // a given state needs no hypotheses
  StartEngine();
  window_->SetInitialState(state, covariance);
}

const SlidingWindowEstimator* NavigationEstimator::Running() const {
  if (window_ && window_->initialized()) return window_.get();
  if (bank_ && bank_->decided()) return bank_->winner();
  return nullptr;
}

void NavigationEstimator::FeedEngine(const ImuSample* sample, const GnssFix* fix) {
  if (sample != nullptr) {
    if (window_) window_->AddImu(*sample);
    if (bank_) bank_->AddImu(*sample);
  } else {
    engine_fixes_.push_back(*fix);
    if (window_) window_->AddGnss(*fix);
    if (bank_) bank_->AddGnss(*fix);
  }
}

void NavigationEstimator::AddImu(const ImuSample& sample) {
  CheckImuSample(sample);
  if (sample.t_ns <= last_imu_ns_) {
    throw std::invalid_argument("IMU time does not increase at t=" + FormatSeconds(sample.t_ns));
  }
  last_imu_ns_ = sample.t_ns;
  if (status_ == Status::kDiverged) return;
  recent_imu_.push_back(sample);
  const TimeNs keep_from =
      sample.t_ns - SecondsToNs(status_ == Status::kStarting ? kKeepBeforeStartS : kRestartImuS);
  while (recent_imu_.front().t_ns < keep_from) recent_imu_.pop_front();  // times increase
  FeedEngine(&sample, nullptr);
  Step(sample.t_ns);
}

void NavigationEstimator::AddGnss(const GnssFix& fix) {
  CheckGnssFix(fix);
  if (fix.t_ns <= last_gnss_ns_) {
    throw std::invalid_argument("GNSS time does not increase at t=" + FormatSeconds(fix.t_ns));
  }
  last_gnss_ns_ = fix.t_ns;
  if (status_ == Status::kDiverged) return;
  if (status_ == Status::kStarting) {
    fixes_unstarted_.push_back(fix);
    TrimBefore(fix.t_ns - SecondsToNs(kKeepBeforeStartS), &fixes_unstarted_);
    if (first_fix_ns_ < 0) first_fix_ns_ = fix.t_ns;
  }
  FeedEngine(nullptr, &fix);
  Step(fix.t_ns);
}

void NavigationEstimator::Step(TimeNs t_ns) {
  if (status_ == Status::kStarting) {
    if (Running() != nullptr) {
      status_ = Status::kRunning;
      fixes_unstarted_.clear();
      measurements_unstarted_.clear();
    } else {
      MaybeFallBackToAlign(t_ns);
      return;
    }
  }
  Watch(t_ns);
}

void NavigationEstimator::MaybeFallBackToAlign(TimeNs t_ns) {
  if (aligning_ || engine_mode_ != "auto" || first_fix_ns_ < 0 || !window_) return;
  const double waited_s = NsToSeconds(t_ns - first_fix_ns_);
  if (waited_s <= config_.init.max_cog_time_s + config_.init.attitude_window_s) return;
  // No dual-antenna heading and no course over ground: the heading must be found (align).
  double moved_m = 0.0;
  for (const GnssFix& f : fixes_unstarted_) {
    moved_m = std::max(moved_m, (f.p_w - fixes_unstarted_.front().p_w).head<2>().norm());
  }
  events_.push_back({t_ns, EstimatorEvent::Kind::kFellBackToAlign,
                     fmt::format("no dual-antenna heading and no course over ground {:.0f} s after "
                                 "the first fix (the fixes spread over {:.1f} m); init.mode align "
                                 "from here",
                                 waited_s, moved_m)});
  spdlog::info("t={}: {}", FormatSeconds(t_ns), events_.back().reason);
  aligning_ = true;
  StartEngine();
  // Everything received so far, to the bank (its rest detection looks at the first samples).
  const std::vector<ImuSample> imu(recent_imu_.begin(), recent_imu_.end());
  const std::vector<GnssFix> fixes = fixes_unstarted_;
  // The sensors' blocks first: they wait in the engine for their keyframes.
  const std::vector<size_t> measurements = measurements_unstarted_;
  for (size_t index : measurements) FeedEngine(index);
  ForEachInTimeOrder(
      imu, fixes, [this](const ImuSample& s) { FeedEngine(&s, nullptr); },
      [this](const GnssFix& f) { FeedEngine(nullptr, &f); });
}

void NavigationEstimator::Watch(TimeNs t_ns) {
  const SlidingWindowEstimator* w = Running();
  if (w == nullptr || !config_.watchdog.enabled) return;
  const WatchdogConfig& wd = config_.watchdog;
  if (!w->LatestFinite()) {
    Restart(t_ns, "the estimate is not finite");
    return;
  }
  const std::vector<FixRecord>& d = w->fix_decisions();
  for (; seen_decisions_ < d.size(); ++seen_decisions_) {
    const FixRecord& r = d[seen_decisions_];
    if (r.position == FixDecision::kDropped) continue;
    if (r.position == FixDecision::kAcceptedOnReacquisition) {
      // The previous re-acquisition held if min_fixes fixes were accepted after it before this
      // lock-out: the window had found the truth again, and lost it anew (a model error that
      // shows in a turn, a GNSS offset); the two are separate episodes, judged separately.
      int accepted = 0;
      for (const FixOutcome& o : recent_outcomes_) accepted += !o.rejected;
      if (!reacquisitions_.empty() && accepted >= wd.min_fixes) {
        reacquisitions_.clear();
        lockout_starts_.clear();
      }
      reacquisitions_.push_back(r.t_ns);
      // The lock-out that ended here began with the first fix of the streak.
      lockout_starts_.push_back(streak_start_ns_ >= 0 ? streak_start_ns_ : r.t_ns);
      streak_start_ns_ = -1;
      recent_outcomes_.clear();  // judged afresh from the re-acquisition on
      continue;
    }
    const bool rejected = r.position == FixDecision::kRejectedByGate;
    // A streak of rejections, broken by an accepted fix or by a gap without fixes (the window's
    // own rule: an outage is not time spent rejecting).
    const bool gap = last_decided_ns_ >= 0 &&
                     NsToSeconds(r.t_ns - last_decided_ns_) > config_.gnss_gate_streak_max_gap_s;
    last_decided_ns_ = r.t_ns;
    if (!rejected) {
      streak_start_ns_ = -1;
    } else if (streak_start_ns_ < 0 || gap) {
      streak_start_ns_ = r.t_ns;
    }
    recent_outcomes_.push_back({r.t_ns, rejected});
  }
  const TimeNs since = t_ns - SecondsToNs(wd.window_s);
  while (!reacquisitions_.empty() && reacquisitions_.front() < since) {
    reacquisitions_.erase(reacquisitions_.begin());
    lockout_starts_.erase(lockout_starts_.begin());
  }
  if (static_cast<int>(reacquisitions_.size()) >= wd.reacquisitions) {
    Restart(t_ns,
            fmt::format("{} re-acquisitions within {:.0f} s", reacquisitions_.size(), wd.window_s));
    return;
  }
  if (reacquisitions_.empty()) {
    recent_outcomes_.clear();
    return;
  }
  // Since the last re-acquisition (within window_s): did it hold?
  int rejected = 0;
  for (const FixOutcome& o : recent_outcomes_) rejected += o.rejected;
  const int n = static_cast<int>(recent_outcomes_.size());
  if (n >= wd.min_fixes && rejected >= wd.rejected_share * n) {
    Restart(t_ns, fmt::format("the re-acquisition at t={} did not hold: {} of the {} fixes since "
                              "were rejected",
                              FormatSeconds(reacquisitions_.back()), rejected, n));
  }
}

void NavigationEstimator::Commit(TimeNs lost_since_ns, TimeNs before_ns) {
  const std::vector<FixRecord> decisions =
      bank_ ? bank_->fix_decisions()
            : (window_ ? window_->fix_decisions() : std::vector<FixRecord>());
  if (const SlidingWindowEstimator* w = Running()) {
    // Estimates from when the window lost the truth on are withdrawn, so are those from a
    // non-finite one on and those the next engine will make again (from before_ns on): the
    // committed outputs stay finite and in time order.
    for (const EstimateRecord& r : w->outputs()) {
      if (lost_since_ns >= 0 && r.state.t_ns >= lost_since_ns) break;
      if (before_ns >= 0 && r.state.t_ns >= before_ns) break;
      if (!Finite(r)) break;
      if (r.state.t_ns <= last_committed_output_ns_) continue;
      committed_outputs_.push_back(r);
      last_committed_output_ns_ = r.state.t_ns;
    }
    const std::vector<UpdateStats>& st = w->update_stats();
    committed_stats_.insert(committed_stats_.end(), st.begin(), st.end());
    committed_gnss_ += w->gnss_stats();
    const std::vector<SensorRecord>& d = w->sensor_decisions();
    for (size_t k = 0; k < d.size() && k < engine_measurements_.size(); ++k) {
      sensor_records_[engine_measurements_[k]] = d[k];
    }
  }
  committed_decisions_.insert(committed_decisions_.end(), decisions.begin(), decisions.end());
  // Fixes the engine was given but had not decided (waiting for their keyframe): dropped.
  for (size_t k = decisions.size(); k < engine_fixes_.size(); ++k) {
    const GnssFix& f = engine_fixes_[k];
    committed_decisions_.push_back(DroppedFixRecord(f, config_.use_gnss_heading));
    ++committed_gnss_.dropped;
  }
}

TimeNs NavigationEstimator::LostSince() const {
  // The first lock-out of the episode the watchdog judged: the window had lost the truth by then.
  return lockout_starts_.empty() ? -1 : lockout_starts_.front();
}

void NavigationEstimator::Restart(TimeNs t_ns, const std::string& reason) {
  // The next engine starts on the IMU kept for a restart: its estimates replace ours from there.
  const bool again = restarts_ < config_.watchdog.max_restarts;
  Commit(LostSince(), again && !recent_imu_.empty() ? recent_imu_.front().t_ns : -1);
  if (!again) {
    status_ = Status::kDiverged;
    failure_ = fmt::format("the estimator diverged at t={} ({}) and {} restarts did not recover it",
                           FormatSeconds(t_ns), reason, restarts_);
    events_.push_back({t_ns, EstimatorEvent::Kind::kGaveUp, reason});
    spdlog::error("{}", failure_);
    window_.reset();
    bank_.reset();
    return;
  }
  ++restarts_;
  bias_prior_scale_ *= kRestartBiasScale;
  events_.push_back({t_ns, EstimatorEvent::Kind::kRestarted,
                     fmt::format("{}; restarted from the data with the bias priors widened {:g}x",
                                 reason, bias_prior_scale_)});
  spdlog::warn("t={}: {}", FormatSeconds(t_ns), events_.back().reason);
  status_ = Status::kStarting;
  first_fix_ns_ = -1;
  fixes_unstarted_.clear();
  measurements_unstarted_.clear();
  StartEngine();
  const std::vector<ImuSample> imu(recent_imu_.begin(), recent_imu_.end());
  for (const ImuSample& s : imu) FeedEngine(&s, nullptr);
}

void NavigationEstimator::TakeFinal(EstimatorHistory* out) {
  // What was committed (engines stopped by a restart) is final.
  out->outputs.insert(out->outputs.end(), committed_outputs_.begin(), committed_outputs_.end());
  out->stats.insert(out->stats.end(), committed_stats_.begin(), committed_stats_.end());
  out->decisions.insert(out->decisions.end(), committed_decisions_.begin(),
                        committed_decisions_.end());
  committed_outputs_.clear();
  committed_stats_.clear();
  committed_decisions_.clear();
  const TimeNs newest = std::max(last_imu_ns_, last_gnss_ns_);
  // Nothing measured yet (a given first state may have started the window): nothing made.
  if (Running() == nullptr || newest == std::numeric_limits<TimeNs>::min()) return;
  // The running engine's: a restart withdraws its estimates from the lock-out that began the
  // failed episode (LostSince) and redoes them from the IMU it keeps (recent_imu_); a lock-out
  // yet to be judged begins no earlier than the current rejection streak or the oldest fix not
  // yet decided. Before all of these, nothing changes any more.
  TimeNs horizon = std::numeric_limits<TimeNs>::max();
  if (!finished_) {
    horizon = newest - SecondsToNs(kRestartImuS);
    if (!recent_imu_.empty()) horizon = std::min(horizon, recent_imu_.front().t_ns);
    if (LostSince() >= 0) horizon = std::min(horizon, LostSince());
    if (streak_start_ns_ >= 0) horizon = std::min(horizon, streak_start_ns_);
    const size_t decided = bank_ ? bank_->fix_decisions().size() : window_->fix_decisions().size();
    if (decided < engine_fixes_.size()) horizon = std::min(horizon, engine_fixes_[decided].t_ns);
  }
  const size_t before = out->decisions.size();
  const size_t own =
      bank_ ? bank_->TakeHistoryBefore(horizon, out) : window_->TakeHistoryBefore(horizon, out);
  // The watchdog has seen every decision taken (it looks after each measurement); the fixes
  // given to the engine stay aligned with the decisions left.
  seen_decisions_ -= std::min(seen_decisions_, own);
  const size_t moved = out->decisions.size() - before;
  engine_fixes_.erase(engine_fixes_.begin(),
                      engine_fixes_.begin() + std::min(moved, engine_fixes_.size()));
}

void NavigationEstimator::Finish() {
  finished_ = true;
  if (status_ == Status::kDiverged) return;
  if (bank_ && !bank_->decided()) bank_->DecideNow();
  const TimeNs t_end = std::max(last_imu_ns_, last_gnss_ns_);
  Step(t_end);
  // The data end before the watchdog's usual evidence can gather: a re-acquisition followed by
  // a majority of rejections (at least kMinFixesAtEnd) is a window that has lost the truth.
  constexpr int kMinFixesAtEnd = 5;
  if (status_ != Status::kRunning || reacquisitions_.empty() || !config_.watchdog.enabled) return;
  int rejected = 0;
  for (const FixOutcome& o : recent_outcomes_) rejected += o.rejected;
  const int n = static_cast<int>(recent_outcomes_.size());
  if (n >= kMinFixesAtEnd && rejected >= config_.watchdog.rejected_share * n) {
    Commit(LostSince());
    status_ = Status::kDiverged;
    failure_ = fmt::format(
        "at the end of the data the estimator had diverged: the re-acquisition "
        "at t={} did not hold ({} of the {} fixes since were rejected)",
        FormatSeconds(reacquisitions_.back()), rejected, n);
    events_.push_back({t_end, EstimatorEvent::Kind::kGaveUp, failure_});
    window_.reset();
    bank_.reset();
  }
}

bool NavigationEstimator::Latest(EstimateRecord* out) const {
  const SlidingWindowEstimator* w = Running();
  return w != nullptr && w->Latest(out);
}

std::vector<EstimateRecord> NavigationEstimator::outputs() const {
  std::vector<EstimateRecord> all = committed_outputs_;
  if (const SlidingWindowEstimator* w = Running()) {
    all.insert(all.end(), w->outputs().begin(), w->outputs().end());
  }
  return all;
}

std::vector<UpdateStats> NavigationEstimator::update_stats() const {
  std::vector<UpdateStats> all = committed_stats_;
  if (const SlidingWindowEstimator* w = Running()) {
    all.insert(all.end(), w->update_stats().begin(), w->update_stats().end());
  }
  return all;
}

GnssStats NavigationEstimator::gnss_stats() const {
  GnssStats sum = committed_gnss_;
  if (const SlidingWindowEstimator* w = Running()) sum += w->gnss_stats();
  return sum;
}

std::vector<FixRecord> NavigationEstimator::fix_decisions() const {
  std::vector<FixRecord> all = committed_decisions_;
  const std::vector<FixRecord> running =
      bank_ ? bank_->fix_decisions()
            : (window_ ? window_->fix_decisions() : std::vector<FixRecord>());
  all.insert(all.end(), running.begin(), running.end());
  return all;
}

}  // namespace skerry
