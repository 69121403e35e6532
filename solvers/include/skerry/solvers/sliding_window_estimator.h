#pragma once
/// \file
/// The live estimator: keyframes at a fixed rate, a window of the most recent ones solved with
/// Ceres (Levenberg-Marquardt by default), older keyframes marginalised by Schur complement into
/// a linear prior. Feed measurements in time order; read the estimate of every keyframe as it is
/// made (a filter-like output) from outputs(), or the newest from Latest().
///
/// Public API in the spirit of GTSAM's FixedLagSmoother: AddImu/AddGnss in, estimates out; any
/// other sensor registers (RegisterSensor) and adds its measurement blocks (AddMeasurement,
/// sensor_block.h), each on a keyframe at its time (keyframe_policy.h).

#include <deque>
#include <map>
#include <memory>
#include <optional>
#include <vector>

#include "skerry/core/earth_model.h"
#include "skerry/core/measurements.h"
#include "skerry/core/sensor_config.h"
#include "skerry/io/estimate_io.h"
#include "skerry/solvers/estimator_config.h"
#include "skerry/solvers/gnss_fix_model.h"
#include "skerry/solvers/gnss_jump_test.h"
#include "skerry/solvers/innovation_gate.h"
#include "skerry/solvers/keyframe_policy.h"
#include "skerry/solvers/nav_graph.h"
#include "skerry/solvers/sensor_block.h"

namespace skerry {

class ImuPreintegration;

/// Statistics of one keyframe update.
struct UpdateStats {
  TimeNs t_ns = 0;
  double update_ms = 0.0;  ///< whole update (keyframe, gating, solve, marginalisation, covariance)
  double solve_ms = 0.0;   ///< Ceres solve alone (0 if no solve)
  int iterations = 0;      ///< Ceres iterations that tried a step (its iteration 0 is not one)
  bool solved = false;
  bool solve_usable = true;
};

/// What an estimator made and decided, in time order each: estimates (one per keyframe), update
/// statistics and fix decisions. A long run takes it over piece by piece
/// (NavigationEstimator::TakeFinal) so that the estimator need not keep it.
struct EstimatorHistory {
  std::vector<EstimateRecord> outputs;
  std::vector<UpdateStats> stats;
  std::vector<FixRecord> decisions;

  bool empty() const { return outputs.empty() && stats.empty() && decisions.empty(); }
  void clear() {
    outputs.clear();
    stats.clear();
    decisions.clear();
  }
};

struct GnssStats {
  int accepted = 0;
  int rejected = 0;
  /// Of the rejected: fixes inside the gate refused because a receiver's jump that opened the
  /// rejection streak explains them better (gnss_jump_test.h).
  int rejected_as_jump = 0;
  /// Fixes that re-initialised the window after gate_max_reject_s of rejections, or at once when
  /// the receiver came back from a jump the window had followed.
  int reacquired = 0;
  /// Of the reacquired: the receiver back from a jump the window had followed (gnss_jump_test.h).
  int reacquired_back_from_jump = 0;
  /// Jumps taken into the receiver's drift as a step (gnss.jump_as_drift_step).
  int drift_steps = 0;
  int dropped = 0;  ///< too late for the window, or before initialisation
  int heading_accepted = 0;
  int heading_rejected = 0;
  /// Position innovations of every gated fix (accepted or not): the count and their Gaussian
  /// log-likelihood sum of -(min(d2, kLikelihoodNisCap) + log det S + 3 log 2 pi) / 2, d2 the
  /// squared Mahalanobis distance. The cap bounds what one outlier costs; the sum ranks
  /// estimators started from different hypotheses on the same data (YawHypothesisBank).
  int innovations = 0;
  double log_likelihood = 0.0;
  /// Sum of d2 over the accepted fixes (NIS): its mean is 3 when the covariance matches the
  /// errors, a consistency check that needs no ground truth (Bar-Shalom et al. 2001, sec. 5.4.2).
  double nis_sum_accepted = 0.0;
  static constexpr double kLikelihoodNisCap = 25.0;

  /// Sums another engine's statistics into these (every field: keep in step with the above).
  GnssStats& operator+=(const GnssStats& a) {
    accepted += a.accepted;
    rejected += a.rejected;
    rejected_as_jump += a.rejected_as_jump;
    reacquired += a.reacquired;
    reacquired_back_from_jump += a.reacquired_back_from_jump;
    drift_steps += a.drift_steps;
    dropped += a.dropped;
    heading_accepted += a.heading_accepted;
    heading_rejected += a.heading_rejected;
    innovations += a.innovations;
    log_likelihood += a.log_likelihood;
    nis_sum_accepted += a.nis_sum_accepted;
    return *this;
  }
};

class SlidingWindowEstimator {
 public:
  /// `earth`: the Earth of the dataset (Dataset::Earth()); its frame is the world frame of every
  /// measurement and estimate.
  /// std::invalid_argument naming the key when `config` is wrong (ValidateEstimatorConfig).
  SlidingWindowEstimator(const EstimatorConfig& config,
                         const ImuConfig& imu,
                         const GnssConfig& gnss,
                         const EarthModel& earth);
  /// The same with a configuration its owner has checked (not checked again).
  SlidingWindowEstimator(const EstimatorConfig& config,
                         const ImuConfig& imu,
                         const GnssConfig& gnss,
                         const EarthModel& earth,
                         ConfigValidated);
  ~SlidingWindowEstimator();

  /// Sets the first state instead of initialising from GNSS (init.mode "given" or any mode).
  void SetInitialState(const NavState& state, const StateCovariance& covariance);

  /// Measurements must come in strictly increasing time order per sensor (std::invalid_argument
  /// otherwise). GnssFix::p_w must be filled (local ENU).
  void AddImu(const ImuSample& sample);
  void AddGnss(const GnssFix& fix);

  /// Registers a sensor; its id is the number of sensors registered before it.
  SensorId RegisterSensor(const SensorSpec& spec);
  /// A measurement block of a registered sensor, in time order per sensor (std::invalid_argument
  /// otherwise, or when the block does not fit its sensor: CheckMeasurement). Add it before the
  /// IMU samples past its time: it then gets a keyframe at its time. One that comes after the IMU
  /// has passed its time goes on the newest keyframe if within the merge tolerance of it, and is
  /// dropped (counted) otherwise; so is one from before the start.
  void AddMeasurement(const SensorMeasurement& measurement);
  const std::vector<SensorSpec>& sensors() const { return sensors_; }
  /// Per registered sensor.
  const std::vector<SensorStats>& sensor_stats() const { return sensor_stats_; }
  /// One per measurement given, in order (a pending one reads kDropped until decided).
  const std::vector<SensorRecord>& sensor_decisions() const { return sensor_decisions_; }
  /// Every measurement given, in order (the batch builds the same blocks from them).
  const std::vector<SensorMeasurement>& sensor_measurements() const { return sensor_log_; }
  /// A calibrated sensor's extrinsic now, with its covariance (6x6: rotation vector, position)
  /// when `covariance` is given and it can be computed; false for a sensor without one.
  bool SensorExtrinsic(SensorId sensor,
                       Eigen::Quaterniond* q_b_s,
                       Eigen::Vector3d* p_b_s,
                       Eigen::Matrix<double, 6, 6>* covariance = nullptr) const;
  /// An estimated sensor parameter now (SensorSpec::parameter_prior_sigma > 0), with its
  /// variance when `variance` is given (NaN when it cannot be computed); false for a sensor
  /// without one.
  bool SensorParameter(SensorId sensor, double* value, double* variance = nullptr) const;
  /// The estimated gyro calibration E now (GyroCalibrationJacobians; estimate_gyro_calibration)
  /// with its covariance (vec(E), column-major; NaN when it cannot be computed) when asked;
  /// false when the window does not estimate it.
  bool GyroCalibration(Eigen::Matrix3d* E, Eigen::Matrix<double, 9, 9>* covariance = nullptr) const;

  bool initialized() const { return initialized_; }
  /// The estimate of every keyframe, at the time it was made.
  const std::vector<EstimateRecord>& outputs() const { return outputs_; }
  const std::vector<UpdateStats>& update_stats() const { return stats_; }
  const GnssStats& gnss_stats() const { return gnss_stats_; }
  /// Decision for each fix passed to AddGnss, in order (position and heading).
  const std::vector<FixRecord>& fix_decisions() const { return fix_decisions_; }
  /// Moves the estimates, update statistics and fix decisions made for times before `t_ns` into
  /// `out` (appended) and forgets them: outputs(), update_stats() and fix_decisions() then begin
  /// after them. Returns the number of fix decisions moved.
  size_t TakeHistoryBefore(TimeNs t_ns, EstimatorHistory* out);
  /// The newest keyframe's estimate; false before initialisation.
  bool Latest(EstimateRecord* out) const;
  /// False when the estimate Latest gives is not finite (its state, or its covariance when it
  /// carries one); true before initialisation. Without Latest's copy: the watchdog asks at
  /// every measurement.
  bool LatestFinite() const;

  /// Restarts the window from its newest keyframe alone, with a Gaussian prior at the current
  /// estimate and the current marginal covariance (GNSS drift included): the same information,
  /// re-linearised now. With first-estimate Jacobians the marginalisation prior keeps the
  /// linearisation points keyframes had when they entered it; after a start far from the truth
  /// (a yaw hypothesis 15 deg off) those points are wrong for good, and this drops them. No-op
  /// before initialisation.
  void Rebase();
  /// Raises the newest heading variance (world yaw) to sigma_rad^2 if it is below: P + d e e^T,
  /// still positive definite. For a start whose heading is less certain than the window knows
  /// (YawHypothesisBank undecided). Only the newest covariance changes: call Rebase next to put
  /// it into the graph (the next solve would otherwise overwrite it).
  void WidenHeading(double sigma_rad);
  /// The graph (for inspection and for the batch smoother).
  const NavGraph& graph() const { return *graph_; }

 private:
  void TryInitialize();
  void Start(const NavState& state, const StateCovariance& covariance);
  /// First keyframe of an empty graph_: a state prior, and the GNSS drift's stationary prior.
  const Keyframe& StartGraph(const NavState& state,
                             const Eigen::Vector3d& gyro_rad_s,
                             const StateCovariance& covariance);
  void ProcessImu(const ImuSample& sample);
  void ProcessGnss(const GnssFix& fix);
  /// Closes a keyframe at `sample`'s time: on the grid, or for a measurement.
  void CloseKeyframe(const ImuSample& sample, bool on_grid);
  /// A new graph with the sensors' extrinsics in it (calibrated ones as graph_ knows them).
  std::unique_ptr<NavGraph> MakeGraph() const;
  /// Some registered sensor gates its blocks (the newest covariance is then needed).
  bool AnySensorGate() const;
  /// Queues measurement `index` of sensor_log_ for its keyframe (after the start).
  void QueueMeasurement(size_t index);
  /// Gates measurement `index` at keyframe `kf` with covariance P and adds its block; records the
  /// decision. True if a block went in.
  bool AttachMeasurement(size_t index, const Keyframe& kf, const GraphCovariance& P);
  /// Decides the queued measurements up to `kf`'s time (plus the merge tolerance): on `kf` when
  /// within the tolerance of it, dropped otherwise. True if a block went in.
  bool AttachDueMeasurements(const Keyframe& kf, const GraphCovariance& P);
  void DropMeasurement(size_t index);
  /// Gates a fix at keyframe `kf` with covariance P and adds its factors; records the decision
  /// in `record`. True if a factor went in.
  bool AttachFix(const GnssFix& fix,
                 const Keyframe& kf,
                 const GraphCovariance& P,
                 FixRecord* record);
  /// Position innovation of a fix at keyframe `kf` with covariance P (whitened; log_det_s is
  /// that of the innovation covariance in metres). `metric` (if given): the same in metres in
  /// the fix's local level frame, NaN when P gates nothing.
  Innovation FixInnovation(const GnssFix& fix,
                           const Keyframe& kf,
                           const GraphCovariance& P,
                           MetricInnovation* metric = nullptr) const;
  void AddFixFactor(const GnssFix& fix, const Keyframe& kf);
  /// Replaces the drift transition into the newest keyframe (`prev` to `next`, dt_s apart) by
  /// b_j = phi b_i + (1 - phi) J + s + w: J the jumps taken in so far (drift_stepped_m_), which do
  /// not decay, and s a step (covariance step_cov) into `next`. False (nothing changed) when
  /// step_cov whitens nothing.
  bool SetNewestDriftTransition(KeyframeId prev,
                                KeyframeId next,
                                double dt_s,
                                const Eigen::Vector3d& step_m,
                                const Eigen::Matrix3d& step_cov);
  /// A rejected fix at the newest keyframe `kf` (gnss.jump_as_drift_step): if the jump
  /// outstanding is ready to be a step (GnssJumpTest::Step), steps the receiver's drift into
  /// `kf` by it (the transition from the previous keyframe becomes a GnssDriftStepFactor, kf's
  /// drift and its covariance move with the step) and, if the fix is then inside the gate, keeps
  /// the step and returns true with the fix's innovation after it in `in` and `metric`;
  /// otherwise undoes everything and returns false.
  bool StepDriftAcrossJump(const GnssFix& fix,
                           const Keyframe& kf,
                           Innovation* in,
                           MetricInnovation* metric);
  /// True while GNSS is being accepted (a fix within gate_streak_max_gap_s before t): then the
  /// position is GNSS's and a sensor's relocation may turn the estimate, never move it.
  bool GnssHoldsPosition(TimeNs t) const;
  /// The record of a fix that never reached a keyframe.
  FixRecord DroppedFix(const GnssFix& fix) const;
  /// The newest keyframe's covariance from the graph (after a solve).
  void UpdateNewestCovariance();
  /// After every change of newest_cov_: keeps newest_cov_finite_ in step with it.
  void NewestCovarianceChanged();
  /// Restarts the window from the newest keyframe with an inflated covariance and adds `fix`:
  /// the position's and the GNSS drift's by the fix's innovation, the attitude's and velocity's
  /// by `motion_d2`'s (a chi-square in 3 degrees of freedom): negative for the fix's own (the
  /// window has drifted), 0 for none (the fix and the window differ by a receiver's jump alone,
  /// gnss_jump_test.h), or the window's own innovation before the receiver stepped back from a
  /// jump it had followed.
  void Reinitialize(const GnssFix& fix, double motion_d2);
  /// The newest covariance times lambda, the bias blocks capped at the dataset's bias priors.
  GraphCovariance InflatedCovariance(double lambda) const;
  /// A sensor's streak of rejected blocks ended in a re-acquisition on block `index` (gated
  /// d2 against the newest keyframe): restart there, relocated if the sensor can, with the block.
  void ReacquireSensor(size_t index, double d2);
  /// Block `index` came while the heading is too uncertain for its sensor
  /// (relocate_above_heading_sigma_rad): relocate and restart with it; false if the sensor could
  /// not locate the vessel (the block is then gated as usual).
  bool RelocateUncertain(size_t index);

  EstimatorConfig config_;
  ImuConfig imu_;
  GnssConfig gnss_;
  EarthModel earth_;
  std::unique_ptr<NavGraph> graph_;
  bool initialized_ = false;
  std::optional<std::pair<NavState, StateCovariance>> given_initial_;
  // Buffers before initialisation.
  std::deque<ImuSample> imu_buffer_;
  std::deque<GnssFix> gnss_buffer_;
  // Live integration state.
  std::unique_ptr<ImuPreintegration> pim_;
  ImuSample last_sample_;
  std::deque<ImuSample> recent_samples_;  ///< the last kKeyframeGyroWindowNs, for KeyframeGyro
  bool has_last_sample_ = false;
  TimeNs keyframe_period_ns_ = 100'000'000;
  std::deque<GnssFix> pending_fixes_;
  /// Newest keyframe's covariance in the graph's 18-D order (gating needs the GNSS bias block);
  /// outputs take the 15x15 top-left block.
  GraphCovariance newest_cov_ = GraphCovariance::Identity();
  /// Whether the 15x15 block of newest_cov_ (what outputs carry) is finite: the watchdog's
  /// LatestFinite asks after every measurement, newest_cov_ changes once per keyframe at most.
  bool newest_cov_finite_ = true;
  TimeNs last_imu_ns_ = std::numeric_limits<TimeNs>::min();
  TimeNs last_gnss_ns_ = std::numeric_limits<TimeNs>::min();
  TimeNs last_fix_accepted_ns_ = std::numeric_limits<TimeNs>::min();  ///< newest fix in the graph
  TimeNs reject_streak_start_ns_ = -1;  ///< first rejected fix of the current streak, or -1
  TimeNs last_rejected_ns_ = -1;        ///< newest rejected fix of the current streak
  GnssJumpTest jump_test_;              ///< a streak that began with a receiver's jump
  FactorId newest_drift_factor_ = -1;   ///< the drift transition into the newest keyframe, or -1
  bool newest_drift_stepped_ = false;   ///< that transition carries a jump already
  /// The jumps taken into the drift since the graph started, summed (world ENU), and their
  /// covariance: fixes accepted while it is significant are offset by a jump (across_jump).
  Eigen::Vector3d drift_stepped_m_ = Eigen::Vector3d::Zero();
  Eigen::Matrix3d drift_stepped_cov_ = Eigen::Matrix3d::Zero();
  std::optional<GnssFix> reacquisition_fix_;  ///< set by AttachFix, used after the keyframe's fixes
  double reacquire_motion_d2_ = -1.0;         ///< Reinitialize's motion_d2 for reacquisition_fix_
  double last_fix_d2_ = 0.0;                  ///< the position innovation of the previous fix
  std::vector<EstimateRecord> outputs_;
  std::vector<UpdateStats> stats_;
  GnssStats gnss_stats_;
  std::vector<FixRecord> fix_decisions_;
  double gate_pos_ = 0.0, gate_heading_ = 0.0;
  // Sensors beyond IMU and GNSS (sensor_block.h).
  KeyframePolicy policy_;
  std::vector<SensorSpec> sensors_;
  std::vector<SensorStats> sensor_stats_;
  std::vector<int> sensor_reject_streak_;    ///< per sensor: blocks rejected in a row
  bool sensor_reacquired_ = false;           ///< the graph was just restarted by a sensor
  std::vector<TimeNs> last_measurement_ns_;  ///< per sensor
  std::vector<SensorMeasurement> sensor_log_;
  std::vector<SensorRecord> sensor_decisions_;
  std::vector<size_t> measurement_buffer_;              ///< before the start: indices into the log
  std::multimap<TimeNs, size_t> pending_measurements_;  ///< after the start, by time
  bool solve_pending_ = false;  ///< a block went on an existing keyframe since the last solve
};

}  // namespace skerry
