#include "skerry/sim/simulator.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <tuple>
#include <utility>
#include <vector>

#include "random.h"
#include "skerry/core/gnss_event.h"
#include "skerry/sim/earth_motion.h"
#include "skerry/sim/harbour_world.h"

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

// (I + S + M): scale factors S = diag(N(0, ppm^2)), misalignment M with off-diagonals
// N(0, mrad^2) (small-angle non-orthogonality; Groves 2013, eq. 4.18).
Eigen::Matrix3d SensorMatrix(double scale_ppm, double misalignment_mrad, Rng* rng) {
  Eigen::Matrix3d m = Eigen::Matrix3d::Identity();
  for (int i = 0; i < 3; ++i) m(i, i) += scale_ppm * 1e-6 * rng->Normal();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      if (i != j) m(i, j) = misalignment_mrad * 1e-3 * rng->Normal();
    }
  }
  return m;
}

// A first-order Gauss-Markov process per axis, exact discretisation
// x+ = phi x + sigma sqrt(1 - phi^2) w (phi = exp(-dt / tau)), started stationary.
class GaussMarkov3 {
 public:
  GaussMarkov3(const Eigen::Vector3d& sigma, double tau_s, double dt_s, Rng* rng)
      : sigma_(sigma), phi_(tau_s > 0.0 ? std::exp(-dt_s / tau_s) : 0.0), rng_(rng) {
    Restart();
  }
  void Restart() { x_ = sigma_.cwiseProduct(rng_->Normal3()); }
  const Eigen::Vector3d& Step() {
    x_ = phi_ * x_ + std::sqrt(1.0 - phi_ * phi_) * sigma_.cwiseProduct(rng_->Normal3());
    return x_;
  }
  const Eigen::Vector3d& value() const { return x_; }

 private:
  Eigen::Vector3d sigma_;
  double phi_;
  Rng* rng_;
  Eigen::Vector3d x_;
};

}  // namespace

Dataset Simulate(const ScenarioConfig& config, std::uint64_t seed) {
  if (!(config.duration_s > 0.0) || !(config.imu.rate_hz > 0.0) || !(config.gnss.rate_hz > 0.0) ||
      !(config.groundtruth_rate_hz > 0.0)) {
    throw std::invalid_argument("Simulate: duration and rates must be > 0");
  }
  // Sample counts are integers (scenario.cc refuses more than 1e8 a stream from a file).
  for (const double rate : {config.imu.rate_hz, config.gnss.rate_hz, config.groundtruth_rate_hz}) {
    if (!(config.duration_s * rate <= 1e9)) {
      throw std::invalid_argument("Simulate: duration x rate above 1e9 samples");
    }
  }
  // Stamps must stay in order (the scenario parser says so to the user; this guards code that
  // builds a ScenarioConfig itself): jitter is cut at 3 sigma.
  if (!(6.0 * config.gnss.stamp_jitter_s < 1.0 / config.gnss.rate_hz)) {
    throw std::invalid_argument(
        "Simulate: gnss.stamp_jitter_s must be below a sixth of the period");
  }
  const VesselMotion motion(config.trajectory, config.waves, config.duration_s, seed);
  const EarthMotion earth(motion, config.origin, config.earth, config.duration_s);
  const ImuModel& imu = config.imu;
  const ImuErrorModel& err = imu.errors;
  const Eigen::Quaterniond q_b_i = imu.q_b_i.normalized();

  Dataset ds;
  ds.name = config.name;
  ds.origin = config.origin;
  ds.earth = config.earth;
  // What the user tells skerry: the datasheet model, never the errors drawn below.
  ds.imu.rate_hz = imu.rate_hz;
  ds.imu.noise = err.noise;
  ds.imu.q_b_i = q_b_i;
  ds.imu.p_b_i = imu.p_b_i;
  ds.imu.gyro_bias_prior_sigma_rad_s = err.gyro_bias_initial_sigma_rad_s;
  ds.imu.accel_bias_prior_sigma_m_s2 = err.accel_bias_initial_sigma_m_s2;
  // The sigmas the gyro's scale factors and misalignment are drawn from (SensorMatrix below).
  ds.imu.gyro_scale_factor_sigma_ppm = err.gyro_scale_factor_ppm;
  ds.imu.gyro_misalignment_sigma_mrad = err.gyro_misalignment_mrad;
  ds.gnss.p_b_g = config.gnss.p_b_g;
  ds.gnss.baseline_b = config.gnss.baseline_b.normalized();
  ds.has_gnss = true;

  // --- IMU: (I + S + M) ideal + bias + white noise. ------------------------------------------
  // Discrete white noise sigma = density * sqrt(rate); bias random-walk step sigma =
  // rw density / sqrt(rate).
  Rng bias_rng(seed, RngStream::kImuBiasInitial);
  Rng noise_rng(seed, RngStream::kImuNoise);
  Rng sensor_rng(seed, RngStream::kImuScaleMisalignment);
  const ImuNoise& n = err.noise;
  const double dt_imu = 1.0 / imu.rate_hz;
  const double sqrt_rate = std::sqrt(imu.rate_hz);
  const double sigma_gyro = n.gyro_noise_density_rad_s_sqrt_hz * sqrt_rate;
  const double sigma_accel = n.accel_noise_density_m_s2_sqrt_hz * sqrt_rate;
  const Eigen::Vector3d bg0 = err.gyro_bias_initial_sigma_rad_s * bias_rng.Normal3();
  const Eigen::Vector3d ba0 = err.accel_bias_initial_sigma_m_s2 * bias_rng.Normal3();
  const Eigen::Matrix3d gyro_matrix =
      SensorMatrix(err.gyro_scale_factor_ppm, err.gyro_misalignment_mrad, &sensor_rng);
  // SimulatedGyroMatrix draws the same: the gyro's matrix is the stream's first draw.
  const Eigen::Matrix3d accel_matrix =
      SensorMatrix(err.accel_scale_factor_ppm, err.accel_misalignment_mrad, &sensor_rng);
  const bool gauss_markov_bias = err.bias_instability_tau_s > 0.0;
  GaussMarkov3 gyro_wander(Eigen::Vector3d::Constant(err.gyro_bias_instability_rad_s),
                           err.bias_instability_tau_s, dt_imu, &bias_rng);
  GaussMarkov3 accel_wander(Eigen::Vector3d::Constant(err.accel_bias_instability_m_s2),
                            err.bias_instability_tau_s, dt_imu, &bias_rng);
  Eigen::Vector3d bg_rw = Eigen::Vector3d::Zero(), ba_rw = Eigen::Vector3d::Zero();
  const double sigma_bg_step = n.gyro_bias_random_walk_rad_s2_sqrt_hz / sqrt_rate;
  const double sigma_ba_step = n.accel_bias_random_walk_m_s3_sqrt_hz / sqrt_rate;

  const std::int64_t n_imu = SampleCount(config.duration_s, imu.rate_hz);
  ds.imu_samples.reserve(static_cast<std::size_t>(n_imu));
  std::vector<std::pair<Eigen::Vector3d, Eigen::Vector3d>> biases;  // per IMU sample
  biases.reserve(static_cast<std::size_t>(n_imu));
  for (std::int64_t k = 0; k < n_imu; ++k) {
    const TimeNs t_ns = SampleTimeNs(k, imu.rate_hz);
    const EarthKinematics ek = earth.At(NsToSeconds(t_ns));
    const BodyKinematics& kin = ek.body;
    const Eigen::Vector3d p_w_i = kin.p_w_b + kin.q_w_b * imu.p_b_i;
    ImuSample s = IdealImu(kin, q_b_i, imu.p_b_i, earth.omega_ie_w(), earth.GravityAt(p_w_i));
    s.t_ns = t_ns;
    const Eigen::Vector3d bg = bg0 + (gauss_markov_bias ? gyro_wander.value() : bg_rw);
    const Eigen::Vector3d ba = ba0 + (gauss_markov_bias ? accel_wander.value() : ba_rw);
    const Eigen::Vector3d white_g = noise_rng.Normal3();
    const Eigen::Vector3d white_a = noise_rng.Normal3();
    s.gyro_rad_s = gyro_matrix * s.gyro_rad_s + bg + sigma_gyro * white_g;
    s.accel_m_s2 = accel_matrix * s.accel_m_s2 + ba + sigma_accel * white_a;
    ds.imu_samples.push_back(s);
    biases.emplace_back(bg, ba);
    if (gauss_markov_bias) {
      gyro_wander.Step();
      accel_wander.Step();
    } else {
      bg_rw += sigma_bg_step * bias_rng.Normal3();
      ba_rw += sigma_ba_step * bias_rng.Normal3();
    }
  }
  auto bias_at = [&](TimeNs t_ns) {
    // The bias of the last IMU sample at or before t (biases are held between samples).
    const double k = std::floor(NsToSeconds(t_ns) * imu.rate_hz + 1e-6);
    const auto idx = static_cast<std::size_t>(
        std::min(std::max(k, 0.0), static_cast<double>(biases.size() - 1)));
    return biases[idx];
  };

  // --- Ground truth and true states (the additive biases; scale factor and misalignment
  // errors have no place in skerry's state). --------------------------------------------------
  const std::int64_t n_gt = SampleCount(config.duration_s, config.groundtruth_rate_hz);
  ds.groundtruth.reserve(static_cast<std::size_t>(n_gt));
  ds.truth_states.reserve(static_cast<std::size_t>(n_gt));
  for (std::int64_t k = 0; k < n_gt; ++k) {
    const TimeNs t_ns = SampleTimeNs(k, config.groundtruth_rate_hz);
    const BodyKinematics kin = earth.At(NsToSeconds(t_ns)).body;
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
  // Every epoch draws its noise, drift steps, multipath, stamp jitter and heading noise whether
  // or not it is emitted, so outages and jumps never change the errors of the other fixes.
  // Errors are along the local east, north and up at the antenna.
  const GnssModel& g = config.gnss;
  const LocalFrame frame(config.origin);
  Rng gnss_rng(seed, RngStream::kGnssNoise);
  Rng drift_rng(seed, RngStream::kGnssDrift);
  Rng heading_rng(seed, RngStream::kGnssHeading);
  Rng slow_rng(seed, RngStream::kGnssSlowDrift);
  Rng multipath_rng(seed, RngStream::kGnssMultipath);
  Rng timing_rng(seed, RngStream::kGnssTiming);
  auto hv = [](double h, double v) { return Eigen::Vector3d(h, h, v); };
  const Eigen::Vector3d sigma_noise = hv(g.noise_sigma_horizontal_m, g.noise_sigma_vertical_m);
  const Eigen::Vector3d sigma_reported =
      hv(g.reported_sigma_horizontal_m, g.reported_sigma_vertical_m);
  const double dt_gnss = 1.0 / g.rate_hz;
  GaussMarkov3 drift(hv(g.drift_sigma_horizontal_m, g.drift_sigma_vertical_m), g.drift_tau_s,
                     dt_gnss, &drift_rng);
  GaussMarkov3 slow(hv(g.slow_drift_sigma_horizontal_m, g.slow_drift_sigma_vertical_m),
                    g.slow_drift_tau_s, dt_gnss, &slow_rng);
  GaussMarkov3 multipath(hv(g.multipath_sigma_horizontal_m, g.multipath_sigma_vertical_m),
                         g.multipath_tau_s, dt_gnss, &multipath_rng);
  // Multipath bursts: exponential gaps (mean 1/rate) between exponential bursts, an alternating
  // renewal process; a share d / (1/rate + d) of the time is in a burst.
  std::vector<std::pair<double, double>> bursts;
  if (g.multipath_rate_per_hour > 0.0) {
    const double rate_s = g.multipath_rate_per_hour / 3600.0;
    double t = 0.0;
    while (true) {
      t += -std::log(1.0 - multipath_rng.Uniform()) / rate_s;
      if (t > config.duration_s) break;
      const double len = -std::log(1.0 - multipath_rng.Uniform()) * g.multipath_mean_duration_s;
      bursts.emplace_back(t, t + len);
      t += len;
    }
  }
  auto in_burst = [&bursts](double t) {
    return std::any_of(bursts.begin(), bursts.end(),
                       [t](const auto& b) { return t >= b.first && t < b.second; });
  };
  const TimeNs offset_ns = SecondsToNs(g.time_offset_s);
  const std::int64_t n_gnss = SampleCount(config.duration_s - g.time_offset_s, g.rate_hz);
  ds.gnss_fixes.reserve(static_cast<std::size_t>(std::max<std::int64_t>(n_gnss, 0)));
  bool was_in_burst = false;
  for (std::int64_t k = 0; k < n_gnss; ++k) {
    if (k > 0) {
      drift.Step();
      slow.Step();
    }
    const TimeNs t_meas_ns = offset_ns + SampleTimeNs(k, g.rate_hz);
    const double t_s = NsToSeconds(t_meas_ns);
    const bool burst = in_burst(t_s);
    if (burst && !was_in_burst) {
      multipath.Restart();
    } else if (burst) {
      multipath.Step();
    }
    was_in_burst = burst;
    const Eigen::Vector3d white = sigma_noise.cwiseProduct(gnss_rng.Normal3());
    const double heading_noise_deg = g.heading_sigma_deg * heading_rng.Normal();
    const double jitter_s = g.stamp_jitter_s * std::clamp(timing_rng.Normal(), -3.0, 3.0);
    bool in_outage = false;
    for (const GnssOutage& o : g.outages) in_outage |= InWindow(t_s, o.start_s, o.duration_s);
    if (in_outage) continue;

    const EarthKinematics ek = earth.At(t_s);
    const BodyKinematics& kin = ek.body;
    const Eigen::Vector3d p_w_g = kin.p_w_b + kin.q_w_b * g.p_b_g;
    Eigen::Vector3d e_enu = white + drift.value() + slow.value();
    if (burst) e_enu += multipath.value();
    for (const GnssJump& j : g.jumps) {
      if (InWindow(t_s, j.start_s, j.duration_s)) e_enu += j.offset_enu_m;
    }
    const Eigen::Matrix3d R_w_n = earth.LocalLevelAt(p_w_g);
    GnssFix fix;
    fix.t_ns = t_meas_ns + SecondsToNs(g.latency_s + jitter_s);
    // A fix stamped before the recording starts (jitter) or after it ends (latency) is not in it.
    if (fix.t_ns < 0 || fix.t_ns > SecondsToNs(config.duration_s)) continue;
    fix.p_w = p_w_g + R_w_n * e_enu;
    const Eigen::Vector3d llh = frame.ToGeodetic(fix.p_w);
    fix.lat_deg = llh.x();
    fix.lon_deg = llh.y();
    fix.height_m = llh.z();
    fix.sigma_enu_m = sigma_reported;
    if (g.dual_antenna_enabled) {
      const Eigen::Vector3d baseline_n = R_w_n.transpose() * (kin.q_w_b * ds.gnss.baseline_b);
      double heading = std::atan2(baseline_n.x(), baseline_n.y()) * kRadToDeg + heading_noise_deg;
      heading = std::fmod(heading, 360.0);
      if (heading < 0.0) heading += 360.0;
      fix.has_heading = true;
      fix.heading_deg = heading;
      fix.sigma_heading_deg = g.heading_sigma_deg;
    }
    ds.gnss_fixes.push_back(fix);
  }

  // --- The water surface: the vessel floats at the origin's ellipsoidal height plus the start
  // point's up (earth_motion.h keeps it there), up to the heave of the waves, whose mean is zero.
  // Not the starting height: that holds the heave at t = 0, a bias of up to its amplitude that
  // the estimator would be told to hold for the whole run.
  if (config.water_surface_enabled) {
    ds.water_surface =
        WaterSurfaceConfig{config.origin.height_m + config.trajectory.start_enu_m.z(),
                           config.water_surface_sigma_m, config.water_surface_rate_hz};
  }

  // --- Pose fixes of the frame s at T_b_s, off the keyframe grid, some of them gross. --------
  const PoseFixModel& pf = config.pose_fixes;
  if (pf.enabled) {
    ds.has_pose_fixes = true;
    ds.pose_fix_mount = pf.mount;
    Rng rng(seed, RngStream::kPoseFix);
    const double sh = pf.sigma_horizontal_m, sv = pf.sigma_vertical_m;
    const double sp_rad = pf.sigma_heading_deg / kRadToDeg;
    for (std::int64_t k = 0;; ++k) {
      const double t_s = pf.time_offset_s + static_cast<double>(k) / pf.rate_hz;
      if (t_s >= std::min(config.duration_s, pf.end_s)) break;
      // Every epoch draws the same numbers, in or out of [start_s, end_s).
      const Eigen::Vector3d white = rng.Normal3();
      const double white_heading = rng.Normal();
      const bool outlier = rng.Uniform() < pf.outlier_probability;
      const double out_angle = 2.0 * M_PI * rng.Uniform();
      const double out_scale = 1.0 + rng.Uniform();
      const double out_sign = rng.Uniform() < 0.5 ? -1.0 : 1.0;
      if (t_s < pf.start_s) continue;
      const BodyKinematics kin = earth.At(t_s).body;
      const Eigen::Vector3d p_w_s = kin.p_w_b + kin.q_w_b * pf.mount.p_b_s;
      const Eigen::Matrix3d R_w_n = earth.LocalLevelAt(p_w_s);
      const Eigen::Vector3d x_n =
          R_w_n.transpose() * (kin.q_w_b * (pf.mount.q_b_s * Eigen::Vector3d::UnitX()));
      PoseFix fix;
      fix.t_ns = SecondsToNs(t_s);
      fix.has_up = pf.kind == "enu" || pf.kind == "enuh";
      fix.has_heading = pf.kind == "enh" || pf.kind == "enuh";
      Eigen::Vector3d e_n(sh * white.x(), sh * white.y(), sv * white.z());
      double heading_err = sp_rad * white_heading;
      if (outlier) {
        e_n.head<2>() += pf.outlier_min_m * out_scale *
                         Eigen::Vector2d(std::cos(out_angle), std::sin(out_angle));
        heading_err += out_sign * out_scale * pf.outlier_heading_min_deg / kRadToDeg;
        ds.pose_fix_outliers.push_back(fix.t_ns);
      }
      // The errors are along the local east, north, up at the point; the fix is in w.
      fix.p_w = p_w_s + R_w_n * e_n;
      fix.heading_deg = (std::atan2(x_n.x(), x_n.y()) + heading_err) * kRadToDeg;
      fix.covariance = Eigen::Vector4d(sh * sh, sh * sh, sv * sv, sp_rad * sp_rad).asDiagonal();
      ds.pose_fixes.push_back(fix);
    }
  }

  // --- Cameras: their configuration and frame times; the images come from RenderCameraImages.
  const CameraModelSim& cm = config.camera;
  if (cm.enabled) {
    const std::vector<std::pair<std::string, double>> ring = {
        {"camera", 0.0}, {"camera_port", 90.0}, {"camera_aft", 180.0}, {"camera_starboard", -90.0}};
    const size_t n = cm.ring ? ring.size() : 1;
    for (size_t k = 0; k < n; ++k) {
      CameraConfig c;
      c.name = ring[k].first;
      c.file = c.name + ".csv";
      c.width_px = cm.width_px;
      c.height_px = cm.height_px;
      c.fx = c.fy = 0.5 * cm.width_px / std::tan(0.5 * cm.horizontal_fov_deg / kRadToDeg);
      c.cx = 0.5 * cm.width_px - 0.5;
      c.cy = 0.5 * cm.height_px - 0.5;
      c.distortion = cm.distortion;
      // Optical z along the body direction ring[k] (deg to port of the bow), x to its right,
      // y down, then pitched down about its x axis.
      Eigen::Matrix3d r_b_c;
      r_b_c << 0, 0, 1, -1, 0, 0, 0, -1, 0;
      c.T_b_c.q_b_s = Eigen::Quaterniond(
          Eigen::AngleAxisd(ring[k].second / kRadToDeg, Eigen::Vector3d::UnitZ()) * r_b_c *
          Eigen::AngleAxisd(cm.pitch_down_deg / kRadToDeg, Eigen::Vector3d::UnitX()));
      c.T_b_c.p_b_s = cm.p_b_c;
      std::vector<SensorFrame> frames;
      for (std::int64_t i = 0;; ++i) {
        const double t_s = cm.time_offset_s + static_cast<double>(i) / cm.rate_hz;
        if (t_s > config.duration_s || t_s >= cm.end_s) break;
        if (t_s < cm.start_s) continue;
        char file[32];
        std::snprintf(file, sizeof(file), "%06lld.png", static_cast<long long>(i));
        frames.push_back({SecondsToNs(t_s), file});
      }
      ds.cameras.push_back(c);
      ds.camera_frames.push_back(frames);
    }
  }
  if (config.dem)
    ds.dem =
        MapConfig{config.dem->path, "", config.dem->vertical_datum, std::nullopt, std::nullopt};

  // --- LiDAR: its mounting and scan times (each the start of a sweep that ends by the last
  // truth state); the scans come from RenderLidarScans, the harbour's photograph from
  // RenderAerialImage.
  // The harbour is built here once only to refuse, before any rendering, boats that do not fit.
  if (config.harbour.enabled) BuildHarbour(config.harbour, seed);
  const LidarModelSim& lm = config.lidar;
  if (lm.enabled) {
    if (!config.harbour.enabled) {
      throw std::invalid_argument("Simulate: a lidar needs a harbour to scan");
    }
    if (!(lm.write_rate_hz > 0.0) || !(lm.rotation_rate_hz >= lm.write_rate_hz)) {
      throw std::invalid_argument(
          "Simulate: lidar rates must be > 0, the rotation at least the write rate");
    }
    LidarConfig l;
    l.name = "lidar";
    l.file = l.name + ".csv";
    l.T_b_l = lm.T_b_l;
    std::vector<SensorFrame> scans;
    const double last_truth_s = NsToSeconds(ds.truth_states.back().t_ns);
    for (std::int64_t i = 0;; ++i) {
      const double t_s = lm.time_offset_s + static_cast<double>(i) / lm.write_rate_hz;
      if (t_s + 1.0 / lm.rotation_rate_hz > last_truth_s || t_s >= lm.end_s) break;
      if (t_s < lm.start_s) continue;
      char file[32];
      std::snprintf(file, sizeof(file), "%06lld.pcd", static_cast<long long>(i));
      scans.push_back({SecondsToNs(t_s), file});
    }
    ds.lidars.push_back(l);
    ds.lidar_scans.push_back(scans);
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

Eigen::Matrix3d SimulatedGyroMatrix(const ImuErrorModel& errors, std::uint64_t seed) {
  Rng sensor_rng(seed, RngStream::kImuScaleMisalignment);
  return SensorMatrix(errors.gyro_scale_factor_ppm, errors.gyro_misalignment_mrad, &sensor_rng);
}

}  // namespace skerry::sim
