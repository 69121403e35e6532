#pragma once
/// \file
/// skerry's live estimator as a program embeds it and as `skerry run` uses it: the sliding window
/// (SlidingWindowEstimator) with its start-up and a watchdog around it.
///
/// Start-up. init.mode auto takes the heading from a dual-antenna fix, else from the course over
/// ground; when neither comes within init.max_cog_time_s of the first fix (a vessel at anchor, a
/// survey boat at 0.3 m/s, a hull whose IMU is mounted at an unknown angle) it falls back to
/// init.mode align (YawHypothesisBank, rest detected from the IMU) on everything received so far.
///
/// Watchdog. A window can lose the truth for good: a bias beyond its prior, a wrong noise model,
/// a start 15 deg off that the first-estimate Jacobians froze in. It then rejects nearly every fix
/// and re-acquisition (SlidingWindowEstimator: after gnss.gate_max_reject_s of rejections, a
/// restart from its newest estimate with an inflated covariance) cannot hold. The watchdog reads
/// the window's own statistics, no ground truth. After a re-acquisition it judges the fixes
/// decided since: watchdog.min_fixes or more of them with watchdog.rejected_share or more rejected
/// means the re-acquisition did not hold (a consistent window rejects 0.1 %). So do
/// watchdog.reacquisitions re-acquisitions within watchdog.window_s with fewer than min_fixes
/// fixes accepted between any two, and so does an estimate that is not finite. It then restarts the
/// estimator from the data (as at the start: a fresh window or bank on the last second of IMU and
/// the fixes from then on) with the bias priors widened tenfold, up to watchdog.max_restarts
/// times; beyond that it stops (status kDiverged) and says why. Estimates before a restart are
/// kept; those from the lock-out that began the failed episode on are withdrawn, and none are made
/// before the new start.

#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "skerry/solvers/sliding_window_estimator.h"
#include "skerry/solvers/yaw_hypothesis_bank.h"

namespace skerry {

/// What the watchdog and the start-up did, in order.
struct EstimatorEvent {
  enum class Kind { kFellBackToAlign, kRestarted, kGaveUp };
  TimeNs t_ns = 0;
  Kind kind = Kind::kRestarted;
  std::string reason;
};

class NavigationEstimator {
 public:
  enum class Status { kStarting, kRunning, kDiverged };

  /// std::invalid_argument naming the key when `config` is wrong (ValidateEstimatorConfig,
  /// checked here once: the windows and alignments of its restarts take it as checked).
  NavigationEstimator(const EstimatorConfig& config,
                      const ImuConfig& imu,
                      const GnssConfig& gnss,
                      const EarthModel& earth);
  ~NavigationEstimator();

  /// A given first state (init.mode given, or any mode); before the first measurement.
  void SetInitialState(const NavState& state, const StateCovariance& covariance);

  /// Measurements in strictly increasing time order per sensor (std::invalid_argument
  /// otherwise), as for SlidingWindowEstimator. Ignored once the status is kDiverged.
  void AddImu(const ImuSample& sample);
  void AddGnss(const GnssFix& fix);
  /// Sensors beyond IMU and GNSS (sensor_block.h): register before the first measurement of any
  /// kind (std::logic_error otherwise); add their blocks in time order per sensor. An engine
  /// restarted by the watchdog gets the blocks from then on, as it gets the fixes.
  SensorId RegisterSensor(const SensorSpec& spec);
  void AddMeasurement(const SensorMeasurement& measurement);
  const std::vector<SensorSpec>& sensors() const { return sensors_; }
  /// Per registered sensor, counted from sensor_decisions() (a block no engine decided counts
  /// as dropped).
  std::vector<SensorStats> sensor_stats() const;
  /// Every block given and the decision about it, in order (a block given to no engine that ran
  /// to the end, or still waiting for its keyframe, reads kDropped).
  const std::vector<SensorMeasurement>& sensor_measurements() const { return sensor_log_; }
  std::vector<SensorRecord> sensor_decisions() const;
  /// The running engine's estimate of a calibrated sensor's extrinsic (SlidingWindowEstimator).
  bool SensorExtrinsic(SensorId sensor,
                       Eigen::Quaterniond* q_b_s,
                       Eigen::Vector3d* p_b_s,
                       Eigen::Matrix<double, 6, 6>* covariance = nullptr) const;
  /// The running engine's estimate of a sensor's parameter (SlidingWindowEstimator).
  bool SensorParameter(SensorId sensor, double* value, double* variance = nullptr) const;
  /// The running engine's gyro calibration (SlidingWindowEstimator::GyroCalibration).
  bool GyroCalibration(Eigen::Matrix3d* E, Eigen::Matrix<double, 9, 9>* covariance = nullptr) const;

  Status status() const { return status_; }
  /// Why the status is kDiverged (empty otherwise).
  const std::string& failure() const { return failure_; }
  const std::vector<EstimatorEvent>& events() const { return events_; }

  /// The newest estimate; false before the start (or while an align bank has not decided).
  bool Latest(EstimateRecord* out) const;
  /// Every estimate made, in time order, one per keyframe: those of estimators stopped by a
  /// restart, then the running one's (an align bank's once it has decided, from its start).
  std::vector<EstimateRecord> outputs() const;
  std::vector<UpdateStats> update_stats() const;
  /// Summed over every estimator that ran.
  GnssStats gnss_stats() const;
  /// One decision per fix given, in order.
  std::vector<FixRecord> fix_decisions() const;

  /// For a long run (a day at sea): moves into `out` (appended) the estimates, update statistics
  /// and fix decisions that are final, those older than anything the watchdog may still withdraw
  /// or an engine redo, and forgets them, so that memory does not grow with the run. outputs(),
  /// update_stats() and fix_decisions() then return only what is left; after Finish() all of it
  /// is final. The pieces, concatenated, are what those would have returned without it.
  void TakeFinal(EstimatorHistory* out);

  /// At the end of the data: an align bank that has not decided keeps its likeliest hypothesis.
  void Finish();

  /// The align bank now running (nullptr if the engine is a single window).
  const YawHypothesisBank* bank() const { return bank_.get(); }

 private:
  ImuConfig EngineImu() const;
  void StartEngine();
  void FeedEngine(const ImuSample* sample, const GnssFix* fix);
  void FeedEngine(size_t measurement);
  void Step(TimeNs t_ns);
  const SlidingWindowEstimator* Running() const;
  void MaybeFallBackToAlign(TimeNs t_ns);
  void Watch(TimeNs t_ns);
  void Restart(TimeNs t_ns, const std::string& reason);
  /// Moves the running engine's estimates (finite ones before `lost_since_ns` and `before_ns`,
  /// each if >= 0), stats and decisions to the committed ones.
  void Commit(TimeNs lost_since_ns, TimeNs before_ns = -1);
  TimeNs LostSince() const;

  EstimatorConfig config_;
  ImuConfig imu_;
  GnssConfig gnss_;
  EarthModel earth_;
  Status status_ = Status::kStarting;
  std::string failure_;
  std::vector<EstimatorEvent> events_;

  // The engine: one window, or a bank of them while aligning.
  std::unique_ptr<SlidingWindowEstimator> window_;
  std::unique_ptr<YawHypothesisBank> bank_;
  bool aligning_ = false;    ///< the engine is (or was started as) a bank
  std::string engine_mode_;  ///< the init.mode the running engine was started with
  int restarts_ = 0;
  double bias_prior_scale_ = 1.0;
  std::vector<GnssFix> engine_fixes_;  ///< fixes given to the running engine
  // Sensors beyond IMU and GNSS: every block given (sensor_log_), its decision once an engine
  // that ran has committed it, and which blocks the running engine was given, in order.
  std::vector<SensorSpec> sensors_;
  std::vector<TimeNs> last_measurement_ns_;
  std::vector<SensorMeasurement> sensor_log_;
  std::vector<SensorRecord> sensor_records_;  ///< one per sensor_log_ entry
  std::vector<size_t> engine_measurements_;   ///< indices into sensor_log_
  std::vector<size_t> measurements_unstarted_;

  // What stopped engines left: their estimates, stats and decisions.
  std::vector<EstimateRecord> committed_outputs_;
  std::vector<UpdateStats> committed_stats_;
  GnssStats committed_gnss_;
  std::vector<FixRecord> committed_decisions_;
  TimeNs last_committed_output_ns_ = std::numeric_limits<TimeNs>::min();
  bool finished_ = false;

  // Data kept for a fall-back or a restart, bounded.
  /// Starting: the last 60 s; running: the last second. A deque: trimmed at every sample (a
  /// vector's erase at the front moved the whole second, 11 kB, per sample).
  std::deque<ImuSample> recent_imu_;
  std::vector<GnssFix> fixes_unstarted_;  ///< given while nothing has started: the last 60 s
  TimeNs first_fix_ns_ = -1;
  TimeNs last_imu_ns_ = std::numeric_limits<TimeNs>::min();
  TimeNs last_gnss_ns_ = std::numeric_limits<TimeNs>::min();

  // Watchdog state over the running engine.
  struct FixOutcome {
    TimeNs t_ns;
    bool rejected;
  };
  std::vector<FixOutcome> recent_outcomes_;  ///< since the last re-acquisition
  std::vector<TimeNs> reacquisitions_;       ///< within watchdog.window_s
  std::vector<TimeNs> lockout_starts_;       ///< the first rejection before each of them
  TimeNs streak_start_ns_ = -1;              ///< first fix of the current rejection streak
  TimeNs last_decided_ns_ = -1;              ///< the newest fix decided
  size_t seen_decisions_ = 0;
};

}  // namespace skerry
