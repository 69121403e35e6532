#include "skerry/sim/simulator.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <tuple>
#include <utility>
#include <vector>

#include "random.h"
#include "skerry/core/geodesy.h"
#include "skerry/core/gnss_event.h"

namespace skerry::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kRadToDeg = 180.0 / kPi;

// Sample times k / rate in ns, exact for rates that divide 1e9.
TimeNs SampleTimeNs(std::int64_t k, double rate_hz) {
  return static_cast<TimeNs>(std::llround(static_cast<double>(k) * 1e9 / rate_hz));
}

std::int64_t SampleCount(double duration_s, double rate_hz) {
  // Samples at k / rate for k = 0.. while t <= duration (a hair of slack for rounding).
  return static_cast<std::int64_t>(std::floor(duration_s * rate_hz + 1e-9)) + 1;
}

bool InWindow(double t_s, double start_s, double duration_s) {
  return t_s >= start_s && t_s < start_s + duration_s;
}

}  // namespace

ImuSample IdealImu(const BodyKinematics& kin,
                   const Eigen::Quaterniond& q_b_i,
                   const Eigen::Vector3d& p_b_i,
                   double gravity_m_s2) {
  const Eigen::Matrix3d R_w_b = kin.q_w_b.toRotationMatrix();
  const Eigen::Matrix3d R_b_i = q_b_i.toRotationMatrix();
  const Eigen::Matrix3d R_w_i = R_w_b * R_b_i;
  const Eigen::Vector3d& w = kin.omega_b;
  const Eigen::Vector3d a_w_i =
      kin.a_w + R_w_b * (kin.alpha_b.cross(p_b_i) + w.cross(w.cross(p_b_i)));
  const Eigen::Vector3d g_w(0.0, 0.0, -gravity_m_s2);
  ImuSample s;
  s.t_ns = SecondsToNs(kin.t_s);
  s.gyro_rad_s = R_b_i.transpose() * w;
  s.accel_m_s2 = R_w_i.transpose() * (a_w_i - g_w);
  return s;
}

Dataset Simulate(const ScenarioConfig& config, std::uint64_t seed) {
  if (!(config.duration_s > 0.0) || !(config.imu.rate_hz > 0.0) || !(config.gnss.rate_hz > 0.0) ||
      !(config.groundtruth_rate_hz > 0.0)) {
    throw std::invalid_argument("Simulate: duration and rates must be > 0");
  }
  const VesselMotion motion(config.trajectory, config.waves, config.duration_s, seed);
  const ImuModel& imu = config.imu;
  const Eigen::Quaterniond q_b_i = imu.q_b_i.normalized();

  Dataset ds;
  ds.name = config.name;
  ds.origin = config.origin;
  ds.imu.rate_hz = imu.rate_hz;
  ds.imu.noise = imu.errors.noise;
  ds.imu.q_b_i = q_b_i;
  ds.imu.p_b_i = imu.p_b_i;
  ds.imu.gyro_bias_prior_sigma_rad_s = imu.errors.gyro_bias_initial_sigma_rad_s;
  ds.imu.accel_bias_prior_sigma_m_s2 = imu.errors.accel_bias_initial_sigma_m_s2;
  ds.imu.gravity_m_s2 = imu.gravity_m_s2;
  ds.gnss.p_b_g = config.gnss.p_b_g;
  ds.gnss.baseline_b = config.gnss.baseline_b.normalized();
  ds.has_gnss = true;

  // --- IMU: ideal + bias + white noise; biases random-walk between samples. -----------------
  // Discrete white noise sigma = density * sqrt(rate); bias step sigma = rw density / sqrt(rate).
  Rng bias_rng(seed, RngStream::kImuBiasInitial);
  Rng noise_rng(seed, RngStream::kImuNoise);
  const ImuNoise& n = imu.errors.noise;
  const double sqrt_rate = std::sqrt(imu.rate_hz);
  const double sigma_gyro = n.gyro_noise_density_rad_s_sqrt_hz * sqrt_rate;
  const double sigma_accel = n.accel_noise_density_m_s2_sqrt_hz * sqrt_rate;
  const double sigma_bg_step = n.gyro_bias_random_walk_rad_s2_sqrt_hz / sqrt_rate;
  const double sigma_ba_step = n.accel_bias_random_walk_m_s3_sqrt_hz / sqrt_rate;
  Eigen::Vector3d bg = imu.errors.gyro_bias_initial_sigma_rad_s * bias_rng.Normal3();
  Eigen::Vector3d ba = imu.errors.accel_bias_initial_sigma_m_s2 * bias_rng.Normal3();

  const std::int64_t n_imu = SampleCount(config.duration_s, imu.rate_hz);
  ds.imu_samples.reserve(static_cast<std::size_t>(n_imu));
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> biases;  // per IMU sample
  biases.reserve(static_cast<std::size_t>(n_imu));
  for (std::int64_t k = 0; k < n_imu; ++k) {
    const TimeNs t_ns = SampleTimeNs(k, imu.rate_hz);
    ImuSample s = IdealImu(motion.At(NsToSeconds(t_ns)), q_b_i, imu.p_b_i, imu.gravity_m_s2);
    s.t_ns = t_ns;
    const Eigen::Vector3d white_g = noise_rng.Normal3();
    const Eigen::Vector3d white_a = noise_rng.Normal3();
    s.gyro_rad_s += bg + sigma_gyro * white_g;
    s.accel_m_s2 += ba + sigma_accel * white_a;
    ds.imu_samples.push_back(s);
    biases.emplace_back(bg, ba);
    bg += sigma_bg_step * bias_rng.Normal3();
    ba += sigma_ba_step * bias_rng.Normal3();
  }
  auto bias_at = [&](TimeNs t_ns) {
    // The bias of the last IMU sample at or before t (biases are held between samples).
    const double k = std::floor(NsToSeconds(t_ns) * imu.rate_hz + 1e-6);
    const auto idx = static_cast<std::size_t>(
        std::min(std::max(k, 0.0), static_cast<double>(biases.size() - 1)));
    return biases[idx];
  };

  // --- Ground truth and true states. ---------------------------------------------------------
  const std::int64_t n_gt = SampleCount(config.duration_s, config.groundtruth_rate_hz);
  ds.groundtruth.reserve(static_cast<std::size_t>(n_gt));
  ds.truth_states.reserve(static_cast<std::size_t>(n_gt));
  for (std::int64_t k = 0; k < n_gt; ++k) {
    const TimeNs t_ns = SampleTimeNs(k, config.groundtruth_rate_hz);
    const BodyKinematics kin = motion.At(NsToSeconds(t_ns));
    StampedPose pose;
    pose.t_ns = t_ns;
    pose.p_w_b = kin.p_w_b;
    pose.q_w_b = kin.q_w_b;
    ds.groundtruth.push_back(pose);
    NavState state;
    state.t_ns = t_ns;
    state.q_w_b = kin.q_w_b;
    state.p_w_b = kin.p_w_b;
    state.v_w = kin.v_w;
    std::tie(state.bg, state.ba) = bias_at(t_ns);
    ds.truth_states.push_back(state);
  }

  // --- GNSS. ---------------------------------------------------------------------------------
  // Every epoch draws its noise, drift step and heading noise whether or not it is emitted, so
  // outages and jumps never change the errors of the other fixes.
  const GnssModel& g = config.gnss;
  const LocalFrame frame(config.origin);
  Rng gnss_rng(seed, RngStream::kGnssNoise);
  Rng drift_rng(seed, RngStream::kGnssDrift);
  Rng heading_rng(seed, RngStream::kGnssHeading);
  const Eigen::Vector3d sigma_noise(g.noise_sigma_horizontal_m, g.noise_sigma_horizontal_m,
                                    g.noise_sigma_vertical_m);
  const Eigen::Vector3d sigma_drift(g.drift_sigma_horizontal_m, g.drift_sigma_horizontal_m,
                                    g.drift_sigma_vertical_m);
  const Eigen::Vector3d sigma_reported(g.reported_sigma_horizontal_m, g.reported_sigma_horizontal_m,
                                       g.reported_sigma_vertical_m);
  // First-order Gauss-Markov, exact discretisation: x+ = phi x + sigma sqrt(1 - phi^2) w,
  // started from its stationary distribution.
  const double phi = g.drift_tau_s > 0.0 ? std::exp(-1.0 / (g.rate_hz * g.drift_tau_s)) : 0.0;
  Eigen::Vector3d drift = sigma_drift.cwiseProduct(drift_rng.Normal3());
  const std::int64_t n_gnss = SampleCount(config.duration_s, g.rate_hz);
  ds.gnss_fixes.reserve(static_cast<std::size_t>(n_gnss));
  for (std::int64_t k = 0; k < n_gnss; ++k) {
    if (k > 0) {
      drift =
          phi * drift + std::sqrt(1.0 - phi * phi) * sigma_drift.cwiseProduct(drift_rng.Normal3());
    }
    const Eigen::Vector3d white = sigma_noise.cwiseProduct(gnss_rng.Normal3());
    const double heading_noise_deg = g.heading_sigma_deg * heading_rng.Normal();
    const TimeNs t_ns = SampleTimeNs(k, g.rate_hz);
    const double t_s = NsToSeconds(t_ns);
    bool in_outage = false;
    for (const GnssOutage& o : g.outages) in_outage |= InWindow(t_s, o.start_s, o.duration_s);
    if (in_outage) continue;

    const BodyKinematics kin = motion.At(t_s);
    const Eigen::Vector3d p_w_g = kin.p_w_b + kin.q_w_b * g.p_b_g;
    Eigen::Vector3d p = p_w_g + white + drift;
    for (const GnssJump& j : g.jumps) {
      if (InWindow(t_s, j.start_s, j.duration_s)) p += j.offset_enu_m;
    }
    GnssFix fix;
    fix.t_ns = t_ns;
    const Eigen::Vector3d llh = frame.ToGeodetic(p);
    fix.lat_deg = llh.x();
    fix.lon_deg = llh.y();
    fix.height_m = llh.z();
    fix.sigma_enu_m = sigma_reported;
    fix.p_w = p;
    if (g.dual_antenna_enabled) {
      const Eigen::Vector3d baseline_w = kin.q_w_b * ds.gnss.baseline_b;
      double heading = std::atan2(baseline_w.x(), baseline_w.y()) * kRadToDeg + heading_noise_deg;
      heading = std::fmod(heading, 360.0);
      if (heading < 0.0) heading += 360.0;
      fix.has_heading = true;
      fix.heading_deg = heading;
      fix.sigma_heading_deg = g.heading_sigma_deg;
    }
    ds.gnss_fixes.push_back(fix);
  }

  // --- Events, in time order of their start. -------------------------------------------------
  auto add_event = [&ds](double start_s, double duration_s, const char* type,
                         const Eigen::Vector3d& offset) {
    GnssEvent e;
    e.t_start_ns = SecondsToNs(start_s);
    e.t_end_ns = SecondsToNs(start_s + duration_s);
    e.type = type;
    e.offset_enu_m = offset;
    ds.events.push_back(e);
  };
  for (const GnssJump& j : g.jumps) add_event(j.start_s, j.duration_s, "jump", j.offset_enu_m);
  for (const GnssOutage& o : g.outages) {
    add_event(o.start_s, o.duration_s, "outage", Eigen::Vector3d::Zero());
  }
  std::stable_sort(ds.events.begin(), ds.events.end(), [](const GnssEvent& a, const GnssEvent& b) {
    return a.t_start_ns < b.t_start_ns;
  });
  return ds;
}

}  // namespace skerry::sim
