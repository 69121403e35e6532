#include "skerry/solvers/yaw_hypothesis_bank.h"

#include <spdlog/spdlog.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "skerry/core/heading.h"
#include "skerry/core/so3.h"
#include "skerry/core/time_order.h"
#include "skerry/solvers/rest_detection.h"

namespace skerry {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kRestVelocitySigma = 0.1;  // m/s: "at rest" on a moored hull or a landed MAV

// Mean of the samples' gyro and accelerometer over [t0, t1], and the per-axis gyro spread.
struct ImuMean {
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero();
  Eigen::Vector3d accel = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_std = Eigen::Vector3d::Zero();
  int n = 0;
};

ImuMean MeanOver(const std::vector<ImuSample>& samples, TimeNs t0, TimeNs t1) {
  ImuMean m;
  Eigen::Vector3d sq = Eigen::Vector3d::Zero();
  for (const ImuSample& s : samples) {
    if (s.t_ns < t0 || s.t_ns > t1) continue;
    m.gyro += s.gyro_rad_s;
    m.accel += s.accel_m_s2;
    sq += s.gyro_rad_s.cwiseProduct(s.gyro_rad_s);
    ++m.n;
  }
  if (m.n > 0) {
    m.gyro /= m.n;
    m.accel /= m.n;
    m.gyro_std = (sq / m.n - m.gyro.cwiseProduct(m.gyro)).cwiseMax(0.0).cwiseSqrt();
  }
  return m;
}

}  // namespace

YawHypothesisBank::YawHypothesisBank(const EstimatorConfig& config,
                                     const ImuConfig& imu,
                                     const GnssConfig& gnss,
                                     const EarthModel& earth)
    : YawHypothesisBank((ValidateEstimatorConfig(config), config),  // throws if it is wrong
                        imu,
                        gnss,
                        earth,
                        ConfigValidated()) {}

YawHypothesisBank::YawHypothesisBank(const EstimatorConfig& config,
                                     const ImuConfig& imu,
                                     const GnssConfig& gnss,
                                     const EarthModel& earth,
                                     ConfigValidated)
    : config_(config), imu_(imu), gnss_(gnss), earth_(earth) {
  config_.init.mode = "given";  // the bank sets every hypothesis' first state
}

void YawHypothesisBank::AddImu(const ImuSample& sample) {
  if (sample.t_ns <= last_imu_ns_) {
    throw std::invalid_argument("IMU time does not increase at t=" +
                                std::to_string(NsToSeconds(sample.t_ns)));
  }
  last_imu_ns_ = sample.t_ns;
  if (winner_) {
    winner_->AddImu(sample);
    return;
  }
  if (bank_.empty()) {
    imu_buffer_.push_back(sample);
    TryStart();
    return;
  }
  int before = 0, after = 0;
  for (const auto& e : bank_) before += e->gnss_stats().innovations;
  for (const auto& e : bank_) e->AddImu(sample);
  for (const auto& e : bank_) after += e->gnss_stats().innovations;
  if (after != before) MaybeDecide(sample.t_ns);
}

void YawHypothesisBank::AddGnss(const GnssFix& fix) {
  if (fix.t_ns <= last_gnss_ns_) {
    throw std::invalid_argument("GNSS time does not increase at t=" +
                                std::to_string(NsToSeconds(fix.t_ns)));
  }
  last_gnss_ns_ = fix.t_ns;
  if (winner_) {
    winner_->AddGnss(fix);
    return;
  }
  if (bank_.empty()) {
    gnss_buffer_.push_back(fix);
    TryStart();
    return;
  }
  for (const auto& e : bank_) e->AddGnss(fix);
}

SensorId YawHypothesisBank::RegisterSensor(const SensorSpec& spec) {
  if (!bank_.empty() || winner_) {
    throw std::logic_error("YawHypothesisBank: sensors register before the hypotheses start");
  }
  sensors_.push_back(spec);
  return static_cast<SensorId>(sensors_.size() - 1);
}

void YawHypothesisBank::AddMeasurement(const SensorMeasurement& m) {
  if (winner_) {
    winner_->AddMeasurement(m);
  } else if (bank_.empty()) {
    measurement_buffer_.push_back(m);
  } else {
    for (const auto& e : bank_) e->AddMeasurement(m);
  }
}

bool YawHypothesisBank::TryStart() {
  const InitConfig& ic = config_.init;
  if (static_s_ < 0.0) {
    if (ic.static_s != InitConfig::kStaticAuto) {
      static_s_ = ic.static_s;
    } else {
      // Wait until the IMU shows whether (and how long) the vehicle is at rest at the start;
      // look again only when a rest-detection block has completed.
      if (imu_buffer_.empty()) return false;
      const int64_t blocks =
          (imu_buffer_.back().t_ns - imu_buffer_.front().t_ns) / SecondsToNs(kRestBlockS);
      if (blocks == rest_blocks_seen_) return false;
      rest_blocks_seen_ = blocks;
      const RestPeriod rest =
          DetectRestAtStart(imu_buffer_, imu_, earth_.Gravity(Eigen::Vector3d::Zero()).norm());
      if (!rest.decided) return false;
      static_s_ = rest.duration_s;
      spdlog::debug("align: {} at the start", static_s_ > 0.0
                                                  ? fmt::format("{:.1f} s at rest", static_s_)
                                                  : std::string("moving"));
    }
  }
  const double static_s = static_s_;
  if (static_s <= 0.0 && gnss_buffer_.empty() && imu_buffer_.size() > 1 &&
      imu_buffer_.back().t_ns - imu_buffer_.front().t_ns > SecondsToNs(2.0)) {
    // Moving start, no fix yet: only the last second can matter.
    const TimeNs t_keep = imu_buffer_.back().t_ns - SecondsToNs(1.0);
    imu_buffer_.erase(imu_buffer_.begin(),
                      std::lower_bound(imu_buffer_.begin(), imu_buffer_.end(), t_keep,
                                       [](const ImuSample& a, TimeNs t) { return a.t_ns < t; }));
  }
  if (imu_buffer_.empty() || gnss_buffer_.empty()) return false;
  const TimeNs t_imu0 = imu_buffer_.front().t_ns;
  NavState s0;
  StateCovariance P = StateCovariance::Zero();
  Eigen::Vector3d fix_p = Eigen::Vector3d::Zero(), fix_sigma = Eigen::Vector3d::Zero();
  ImuMean mean;
  if (static_s > 0.0) {
    // At rest over [t_imu0, t_imu0 + static_s]: wait until the IMU covers it.
    const TimeNs t_rest_end = t_imu0 + SecondsToNs(static_s);
    if (imu_buffer_.back().t_ns < t_rest_end) return false;
    int n_fix = 0;
    for (const GnssFix& f : gnss_buffer_) {
      if (f.t_ns > t_rest_end) break;
      fix_p += f.p_w;
      fix_sigma += f.sigma_enu_m;
      ++n_fix;
    }
    if (n_fix == 0) {  // no fix while at rest: the first one after it
      fix_p = gnss_buffer_.front().p_w;
      fix_sigma = gnss_buffer_.front().sigma_enu_m;
      spdlog::warn(
          "init.static_s: no GNSS fix in the first {:.1f} s, position from the fix at "
          "t={:.3f}",
          static_s, NsToSeconds(gnss_buffer_.front().t_ns));
    } else {
      fix_p /= n_fix;
      fix_sigma /= n_fix;
      double spread = 0.0;
      for (const GnssFix& f : gnss_buffer_) {
        if (f.t_ns > t_rest_end) break;
        spread = std::max(spread, (f.p_w - fix_p).head<2>().norm());
      }
      if (spread > 5.0 * fix_sigma.head<2>().norm() + 1.0) {
        spdlog::warn(
            "init.static_s: the fixes of the rest period spread over {:.1f} m; is the "
            "vehicle really at rest for {:.1f} s?",
            spread, static_s);
      }
    }
    mean = MeanOver(imu_buffer_, t_imu0, t_rest_end);
    if (mean.n == 0) mean = MeanOver(imu_buffer_, t_imu0, t_imu0);  // static_s < one period
    s0.t_ns = t_imu0;
    s0.v_w.setZero();
    s0.bg = mean.gyro;
    const Eigen::Vector3d sigma_bg =
        (3.0 * mean.gyro_std / std::sqrt(static_cast<double>(mean.n))).cwiseMax(1e-6);
    P.diagonal().segment<3>(kVel).setConstant(kRestVelocitySigma * kRestVelocitySigma);
    P.diagonal().segment<3>(kBg) = sigma_bg.array().square();
  } else {
    // Moving: the velocity from the first two fixes no further apart than max_cog_time_s.
    while (gnss_buffer_.size() >= 2 &&
           NsToSeconds(gnss_buffer_[1].t_ns - gnss_buffer_[0].t_ns) > ic.max_cog_time_s) {
      const GnssFix& f = gnss_buffer_.front();
      dropped_before_start_.push_back(DroppedFixRecord(f, config_.use_gnss_heading));
      gnss_buffer_.erase(gnss_buffer_.begin());
    }
    // IMU data before the first fix is never used: keep the buffer bounded while waiting.
    const TimeNs t_keep = gnss_buffer_.front().t_ns - SecondsToNs(1.0);
    if (imu_buffer_.front().t_ns < t_keep) {
      imu_buffer_.erase(imu_buffer_.begin(),
                        std::lower_bound(imu_buffer_.begin(), imu_buffer_.end(), t_keep,
                                         [](const ImuSample& a, TimeNs t) { return a.t_ns < t; }));
    }
    if (gnss_buffer_.size() < 2 || imu_buffer_.empty()) return false;
    const GnssFix& f = gnss_buffer_[0];
    const GnssFix& g = gnss_buffer_[1];
    const double dt = NsToSeconds(g.t_ns - f.t_ns);
    const TimeNs t_end = f.t_ns + SecondsToNs(ic.attitude_window_s);
    if (imu_buffer_.back().t_ns < t_end) return false;
    mean = MeanOver(imu_buffer_, f.t_ns, t_end);
    if (mean.n == 0) return false;
    fix_p = f.p_w;
    fix_sigma = f.sigma_enu_m;
    s0.t_ns = f.t_ns;
    s0.v_w = (g.p_w - f.p_w) / dt;
    s0.v_w.z() = 0.0;
    const double sv =
        std::hypot(ic.velocity_sigma_m_s,
                   (f.sigma_enu_m.head<2>().norm() + g.sigma_enu_m.head<2>().norm()) / dt);
    P.diagonal().segment<3>(kVel).setConstant(sv * sv);
    P.diagonal().segment<3>(kBg).setConstant(imu_.gyro_bias_prior_sigma_rad_s *
                                             imu_.gyro_bias_prior_sigma_rad_s);
  }
  // Tilt: the smallest rotation taking the measured up (the specific force, body frame) to the
  // local vertical at the fix (w's z turned by the curvature of the Earth away from the origin).
  const Eigen::Matrix3d R_w_n = earth_.LocalLevel(fix_p);
  const Eigen::Vector3d up_b = (imu_.q_b_i * mean.accel).normalized();
  const Eigen::Quaterniond q_tilt =
      Eigen::Quaterniond::FromTwoVectors(up_b, Eigen::Vector3d::UnitZ());
  const double rp = ic.roll_pitch_sigma_deg * kDeg;
  const int K = ic.align_hypotheses;
  const double sigma_yaw = M_PI / K;  // half the spacing
  P(kRot + 0, kRot + 0) = rp * rp;
  P(kRot + 1, kRot + 1) = rp * rp;
  P(kRot + 2, kRot + 2) = sigma_yaw * sigma_yaw;
  P.diagonal().segment<3>(kPos) = config_.StartPositionVariance(fix_sigma);
  P.diagonal().segment<3>(kBa).setConstant(imu_.accel_bias_prior_sigma_m_s2 *
                                           imu_.accel_bias_prior_sigma_m_s2);

  t_start_ns_ = s0.t_ns;
  scores_.assign(K, {});
  for (int k = 0; k < K; ++k) {
    const double yaw = 2.0 * M_PI * k / K;
    NavState s = s0;
    s.q_w_b =
        (Eigen::Quaterniond(R_w_n) * Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * q_tilt)
            .normalized();
    s.p_w_b = fix_p - s.q_w_b * gnss_.p_b_g;
    if (static_s > 0.0) {
      // At rest the gyro reads its bias plus the Earth's rate: R_i_w omega_ie_w in this attitude.
      s.bg = mean.gyro - (s.q_w_b * imu_.q_b_i).conjugate() * earth_.omega_ie_w();
    }
    auto e =
        std::make_unique<SlidingWindowEstimator>(config_, imu_, gnss_, earth_, ConfigValidated());
    e->SetInitialState(s, P);
    for (const SensorSpec& spec : sensors_) e->RegisterSensor(spec);
    // Before the IMU: each waits in the window until its keyframe (or is dropped at the start).
    for (const SensorMeasurement& m : measurement_buffer_) e->AddMeasurement(m);
    bank_.push_back(std::move(e));
    scores_[k].yaw0_deg = yaw / kDeg;
  }
  // Replay the buffers.
  ForEachInTimeOrder(
      imu_buffer_, gnss_buffer_,
      [this](const ImuSample& sample) {
        for (const auto& e : bank_) e->AddImu(sample);
      },
      [this](const GnssFix& fix) {
        for (const auto& e : bank_) e->AddGnss(fix);
      });
  const TimeNs t_last = imu_buffer_.back().t_ns;
  imu_buffer_.clear();
  gnss_buffer_.clear();
  measurement_buffer_.clear();
  spdlog::debug("align: {} yaw hypotheses from t={:.3f}", K, NsToSeconds(t_start_ns_));
  MaybeDecide(t_last);
  return true;
}

size_t YawHypothesisBank::UpdateScores() {
  size_t best = 0;
  for (size_t k = 0; k < bank_.size(); ++k) {
    scores_[k].log_likelihood = bank_[k]->gnss_stats().log_likelihood;
    if (scores_[k].log_likelihood > scores_[best].log_likelihood) best = k;
  }
  double sum = 0.0;
  for (HypothesisScore& h : scores_) {
    h.weight = std::exp(h.log_likelihood - scores_[best].log_likelihood);
    sum += h.weight;
  }
  for (HypothesisScore& h : scores_) h.weight /= sum;
  return best;
}

double YawHypothesisBank::MergedMass(size_t best) const {
  EstimateRecord rb;
  if (!bank_[best]->Latest(&rb)) return 0.0;
  double mass = 0.0;
  for (size_t k = 0; k < bank_.size(); ++k) {
    EstimateRecord rk;
    if (!bank_[k]->Latest(&rk)) continue;
    if (rk.state.q_w_b.angularDistance(rb.state.q_w_b) < kMergeDeg * kDeg)
      mass += scores_[k].weight;
  }
  return mass;
}

void YawHypothesisBank::MaybeDecide(TimeNs t_ns) {
  if (bank_.empty() || winner_) return;
  const double elapsed_s = NsToSeconds(t_ns - t_start_ns_);
  if (elapsed_s < config_.init.align_min_s) return;
  const size_t best = UpdateScores();
  EstimateRecord rb;
  if (!bank_[best]->Latest(&rb)) return;
  const double mass = MergedMass(best);
  if (mass >= config_.init.align_decide_mass || elapsed_s >= config_.init.align_max_s) {
    const bool undecided = mass < config_.init.align_decide_mass;
    if (undecided) {
      spdlog::warn(
          "align: no clear heading after {:.0f} s (mass {:.2f}); keeping the likeliest with its "
          "heading sigma widened to the bank's spread",
          elapsed_s, mass);
    }
    Keep(best, t_ns, undecided);
  }
}

double YawHypothesisBank::HeadingSpreadRad(size_t best) const {
  // The weighted RMS of the hypotheses' headings about the likeliest one's, each hypothesis'
  // own variance included: the second moment of the bank's mixture about the kept mean.
  EstimateRecord rb;
  if (!bank_[best]->Latest(&rb)) return 0.0;
  double second_moment = 0.0;
  for (size_t k = 0; k < bank_.size(); ++k) {
    EstimateRecord rk;
    if (!bank_[k]->Latest(&rk)) continue;
    const double d = std::remainder(
        (HeadingDeg(rk.state.q_w_b) - HeadingDeg(rb.state.q_w_b)) * kDeg, 2.0 * M_PI);
    const double own = rk.has_covariance ? rk.covariance(kRot + 2, kRot + 2) : 0.0;
    second_moment += scores_[k].weight * (d * d + own);
  }
  return std::sqrt(second_moment);
}

std::vector<FixRecord> YawHypothesisBank::fix_decisions() const {
  if (!winner_) return {};
  std::vector<FixRecord> all = dropped_before_start_;
  const std::vector<FixRecord>& kept = winner_->fix_decisions();
  all.insert(all.end(), kept.begin(), kept.end());
  return all;
}

size_t YawHypothesisBank::TakeHistoryBefore(TimeNs t_ns, EstimatorHistory* out) {
  if (!winner_) return 0;
  const auto end = std::find_if(dropped_before_start_.begin(), dropped_before_start_.end(),
                                [t_ns](const FixRecord& r) { return r.t_ns >= t_ns; });
  out->decisions.insert(out->decisions.end(), dropped_before_start_.begin(), end);
  const bool all_dropped_moved = end == dropped_before_start_.end();
  dropped_before_start_.erase(dropped_before_start_.begin(), end);
  if (!all_dropped_moved) return 0;  // the kept estimator's decisions come after these
  return winner_->TakeHistoryBefore(t_ns, out);
}

bool YawHypothesisBank::DecideNow() {
  if (winner_) return true;
  if (bank_.empty()) return false;
  const size_t best = UpdateScores();
  Keep(best, last_imu_ns_, MergedMass(best) < config_.init.align_decide_mass);
  return true;
}

void YawHypothesisBank::Keep(size_t k, TimeNs t_ns, bool undecided) {
  // Undecided (align_max_s passed, or the data ended), the heading is as uncertain as the bank's
  // spread says, not as the kept window alone believes: on a slow rover the likeliest of 12
  // hypotheses held 0.22 of the weight and was 100 deg off with 14 deg claimed.
  const double spread = undecided ? HeadingSpreadRad(k) : 0.0;
  winner_ = std::move(bank_[k]);
  bank_.clear();
  kept_start_t_ns_ = winner_->outputs().empty() ? -1 : winner_->outputs().front().state.t_ns;
  winner_->WidenHeading(spread);
  // Its marginalisation prior was linearised (first-estimate Jacobians) while its yaw was still
  // up to 15 deg off: re-linearise at the current estimate.
  winner_->Rebase();
  decision_t_ns_ = t_ns;
  kept_ = static_cast<int>(k);
  undecided_ = undecided;
  widened_heading_sigma_rad_ = spread;
  spdlog::info(
      "align: t={:.3f}: kept the estimator started at yaw {:.0f} deg (weight {:.3f}, {} "
      "hypotheses)",
      NsToSeconds(t_ns), scores_[k].yaw0_deg, scores_[k].weight, scores_.size());
}

}  // namespace skerry
