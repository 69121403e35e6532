#pragma once
/// \file
/// Start-up when nothing gives the heading (init.mode "align"): no dual-antenna heading, and a
/// course over ground that is not the heading (a multicopter, a hull whose IMU is mounted at an
/// unknown angle to its track) or not there yet (a vessel at rest at its berth).
///
/// A bank of sliding-window estimators, one per yaw hypothesis evenly spaced over 360 deg, each
/// with a yaw sigma of half the spacing, is fed the same measurements. Each scores its GNSS
/// position innovations by their Gaussian log-likelihood (GnssStats::log_likelihood); the
/// posterior weight of hypothesis k is proportional to exp(l_k) under a uniform prior: the
/// multiple-model adaptive estimation of Magill ("Optimal adaptive estimation of sampled
/// stochastic processes", IEEE Trans. Automatic Control 10(4), 1965), here over the unknown
/// initial yaw, the approach of multiple-model in-motion alignment. Once init.align_min_s has
/// passed and the hypotheses whose attitude now lies within kMergeDeg of the likeliest one hold
/// init.align_decide_mass of the weight, the likeliest estimator is kept and the others dropped.
/// Its outputs start at the beginning of the data. If init.align_max_s passes (or the data end)
/// first, the likeliest is kept with its heading variance raised to the mixture's second moment
/// about its heading: the kept window then says how little is known.
///
/// The first state: at rest (init.static_s > 0, or detected: rest_detection.h) the gyro bias is the
/// mean gyro over the rest period less the Earth's rate seen in that hypothesis' attitude (a
/// gyrocompass: the hypotheses differ in where they put the Earth's horizontal rate, 10 deg/h at 47
/// deg N, which a navigation-grade gyro resolves), and roll/pitch come from the mean specific
/// force, velocity zero; moving, the velocity comes from the first two fixes and roll/pitch from
/// the accelerometer averaged over init.attitude_window_s. The tilt is the smallest rotation taking
/// the measured "up" to the world z axis, so any IMU mounting works (the EuRoC IMU's x axis points
/// up).

#include <memory>
#include <optional>
#include <vector>

#include "skerry/solvers/sliding_window_estimator.h"

namespace skerry {

class YawHypothesisBank {
 public:
  /// Hypotheses whose attitudes end up closer than this count as one for the decision.
  static constexpr double kMergeDeg = 10.0;

  /// std::invalid_argument naming the key when `config` is wrong (ValidateEstimatorConfig).
  YawHypothesisBank(const EstimatorConfig& config,
                    const ImuConfig& imu,
                    const GnssConfig& gnss,
                    const EarthModel& earth);
  /// The same with a configuration its owner has checked: checked neither here nor in the
  /// hypotheses' windows.
  YawHypothesisBank(const EstimatorConfig& config,
                    const ImuConfig& imu,
                    const GnssConfig& gnss,
                    const EarthModel& earth,
                    ConfigValidated);

  /// Measurements in strictly increasing time order per sensor (std::invalid_argument
  /// otherwise), as for SlidingWindowEstimator.
  void AddImu(const ImuSample& sample);
  void AddGnss(const GnssFix& fix);
  /// Sensors beyond IMU and GNSS (sensor_block.h): registered on every hypothesis, before the
  /// first measurement; their blocks go to every hypothesis.
  SensorId RegisterSensor(const SensorSpec& spec);
  void AddMeasurement(const SensorMeasurement& measurement);

  /// Decides now for the likeliest hypothesis if no decision has been made (e.g. at the end of a
  /// recording shorter than init.align_min_s); false if the bank never started.
  bool DecideNow();

  bool decided() const { return winner_ != nullptr; }
  /// The estimator kept; nullptr before the decision.
  const SlidingWindowEstimator* winner() const { return winner_.get(); }
  /// Decisions for every fix given to the bank, in order: those it dropped before the hypotheses
  /// started, then the kept estimator's. Empty before the decision.
  std::vector<FixRecord> fix_decisions() const;
  /// After the decision: moves the history before `t_ns` (fix decisions: those dropped before
  /// the start, then the kept estimator's) into `out` as SlidingWindowEstimator does. Returns the
  /// number of the kept estimator's own fix decisions moved.
  size_t TakeHistoryBefore(TimeNs t_ns, EstimatorHistory* out);
  /// The kept estimator's first estimate's time (-1 before the decision or without one).
  TimeNs kept_start_t_ns() const { return kept_start_t_ns_; }
  /// Per hypothesis: start yaw (deg, world frame about up) and log-likelihood so far (at the
  /// decision, frozen then). Empty before the bank starts.
  struct HypothesisScore {
    double yaw0_deg = 0.0;
    double log_likelihood = 0.0;
    double weight = 0.0;
  };
  const std::vector<HypothesisScore>& scores() const { return scores_; }
  TimeNs decision_t_ns() const { return decision_t_ns_; }
  /// Index into scores() of the hypothesis kept; -1 before the decision.
  int kept() const { return kept_; }
  /// True when the kept hypothesis did not hold init.align_decide_mass (kept at align_max_s or
  /// at the end of the data): its heading sigma was widened to the bank's spread.
  bool undecided() const { return undecided_; }
  /// Undecided: the heading 1-sigma the kept window was widened to (the bank's spread); else 0.
  double widened_heading_sigma_rad() const { return widened_heading_sigma_rad_; }
  /// The rest period at the start the bank used (init.static_s, or detected when it is auto);
  /// negative before it is known.
  double static_s() const { return static_s_; }

 private:
  /// Builds the hypotheses once the buffered data allow it; true when started.
  bool TryStart();
  /// Log-likelihoods and posterior weights from the estimators; returns the likeliest.
  size_t UpdateScores();
  void MaybeDecide(TimeNs t_ns);
  /// Keeps hypothesis k; `undecided`: its heading sigma is widened to HeadingSpreadRad(k).
  void Keep(size_t k, TimeNs t_ns, bool undecided);
  /// The weight of the hypotheses whose attitude lies within kMergeDeg of hypothesis `best`'s.
  double MergedMass(size_t best) const;
  /// The bank's heading spread about hypothesis `best` (rad): the weighted second moment of the
  /// mixture about its heading.
  double HeadingSpreadRad(size_t best) const;

  EstimatorConfig config_;
  ImuConfig imu_;
  GnssConfig gnss_;
  EarthModel earth_;
  std::vector<FixRecord> dropped_before_start_;
  TimeNs kept_start_t_ns_ = -1;
  std::vector<ImuSample> imu_buffer_;
  std::vector<GnssFix> gnss_buffer_;
  std::vector<SensorSpec> sensors_;
  std::vector<SensorMeasurement> measurement_buffer_;  ///< before the hypotheses start
  TimeNs last_imu_ns_ = std::numeric_limits<TimeNs>::min();
  TimeNs last_gnss_ns_ = std::numeric_limits<TimeNs>::min();
  TimeNs t_start_ns_ = 0;
  std::vector<std::unique_ptr<SlidingWindowEstimator>> bank_;
  std::vector<HypothesisScore> scores_;
  std::unique_ptr<SlidingWindowEstimator> winner_;
  TimeNs decision_t_ns_ = -1;
  int kept_ = -1;
  bool undecided_ = false;
  double widened_heading_sigma_rad_ = 0.0;
  double static_s_ = -1.0;  ///< the rest period used (init.static_s or detected); < 0: not yet
  int64_t rest_blocks_seen_ = -1;  ///< complete rest-detection blocks at the last look
};

}  // namespace skerry
