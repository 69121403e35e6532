#include "skerry/sim/twin.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "random.h"
#include "skerry/core/geodesy.h"
#include "skerry/sim/earth_field.h"
#include "skerry/sim/earth_motion.h"

namespace skerry::sim {
namespace {

constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;

void CheckModelValue(double value, const char* name) {
  if (!(value >= 0.0) || !std::isfinite(value)) {
    throw std::invalid_argument(std::string("SimulateTwin: ") + name + " must be finite and >= 0");
  }
}

// floor(a / b) for b > 0 (C++ division truncates towards zero).
std::int64_t FloorDiv(std::int64_t a, std::int64_t b) {
  const std::int64_t q = a / b;
  return (a % b != 0 && a < 0) ? q - 1 : q;
}

}  // namespace

Dataset SimulateTwin(const Dataset& real,
                     const SplineMotion& truth,
                     const TwinModel& model,
                     std::uint64_t seed,
                     double truth_rate_hz) {
  const TwinImuModel& mi = model.imu;
  const TwinGnssModel& mg = model.gnss;
  CheckModelValue(mi.gyro_noise_density_rad_s_sqrt_hz, "imu gyro noise density");
  CheckModelValue(mi.accel_noise_density_m_s2_sqrt_hz, "imu accel noise density");
  CheckModelValue(mi.gyro_bias_random_walk_rad_s2_sqrt_hz, "imu gyro bias random walk");
  CheckModelValue(mi.accel_bias_random_walk_m_s3_sqrt_hz, "imu accel bias random walk");
  CheckModelValue(mg.white_sigma_horizontal_m, "gnss white sigma horizontal");
  CheckModelValue(mg.white_sigma_vertical_m, "gnss white sigma vertical");
  CheckModelValue(mg.drift_sigma_horizontal_m, "gnss drift sigma horizontal");
  CheckModelValue(mg.drift_sigma_vertical_m, "gnss drift sigma vertical");
  CheckModelValue(mg.gross_rate_per_hour, "gnss gross-error rate");
  CheckModelValue(mg.gross_mean_duration_s, "gnss gross-error duration");
  CheckModelValue(mg.gross_offset_horizontal_m, "gnss gross-error offset horizontal");
  CheckModelValue(mg.gross_offset_vertical_m, "gnss gross-error offset vertical");
  CheckModelValue(mg.latency_s, "gnss latency");
  CheckModelValue(mg.heading_sigma_deg, "gnss heading sigma");
  CheckModelValue(mg.solve_period_s, "gnss solve period");
  CheckModelValue(mg.solve_phase_s, "gnss solve phase");
  CheckModelValue(mg.solve_offset_sigma_m, "gnss solve offset sigma");
  CheckModelValue(mg.propagation_velocity_sigma_m_s, "gnss propagation velocity sigma");
  if (!(mg.drift_tau_s > 0.0) || !(mg.propagation_velocity_tau_s > 0.0) || !(truth_rate_hz > 0.0)) {
    throw std::invalid_argument(
        "SimulateTwin: drift tau, propagation velocity tau and truth rate must be > 0");
  }
  if (mg.solve_period_s > 0.0 && mg.solve_period_s < 1e-3) {
    throw std::invalid_argument("SimulateTwin: a solve period must be at least 1 ms");
  }

  Dataset twin;
  twin.name = real.name + "-twin";
  twin.origin = real.origin;
  twin.earth = real.earth;
  twin.has_imu = real.has_imu;
  twin.imu = real.imu;
  twin.gnss = real.gnss;
  twin.has_gnss = real.has_gnss;
  twin.water_surface = real.water_surface;
  const EarthField earth(real.origin, real.earth);
  const LocalFrame frame(real.origin);

  // --- IMU at the real stamps inside the truth's span. ---------------------------------------
  if (real.has_imu) {
    Rng noise(seed, RngStream::kImuNoise);
    Rng walk(seed, RngStream::kImuBiasInitial);
    const double rate = real.imu.rate_hz;
    const double sg = mi.gyro_noise_density_rad_s_sqrt_hz * std::sqrt(rate);
    const double sa = mi.accel_noise_density_m_s2_sqrt_hz * std::sqrt(rate);
    Eigen::Vector3d bg_walk = Eigen::Vector3d::Zero(), ba_walk = Eigen::Vector3d::Zero();
    TimeNs last = -1;
    for (const ImuSample& r : real.imu_samples) {
      if (!truth.Covers(r.t_ns)) continue;
      if (last >= 0) {
        // Random walk over the real interval: step sigma = density * sqrt(dt).
        const double dt = NsToSeconds(r.t_ns - last);
        bg_walk += mi.gyro_bias_random_walk_rad_s2_sqrt_hz * std::sqrt(dt) * walk.Normal3();
        ba_walk += mi.accel_bias_random_walk_m_s3_sqrt_hz * std::sqrt(dt) * walk.Normal3();
      }
      last = r.t_ns;
      const BodyKinematics kin = truth.At(r.t_ns);
      const NavState state = truth.StateAt(r.t_ns);
      const Eigen::Vector3d p_w_i = kin.p_w_b + kin.q_w_b * real.imu.p_b_i;
      ImuSample s =
          IdealImu(kin, real.imu.q_b_i, real.imu.p_b_i, earth.omega_ie_w(), earth.GravityAt(p_w_i));
      s.t_ns = r.t_ns;
      s.gyro_rad_s += state.bg + bg_walk + sg * noise.Normal3();
      s.accel_m_s2 += state.ba + ba_walk + sa * noise.Normal3();
      twin.imu_samples.push_back(s);
    }
  }

  // --- GNSS at the real stamps. ---------------------------------------------------------------
  if (real.has_gnss) {
    Rng white(seed, RngStream::kGnssNoise);
    Rng drift_rng(seed, RngStream::kGnssDrift);
    Rng heading_rng(seed, RngStream::kGnssHeading);
    Rng outlier_rng(seed, RngStream::kTwinGnssOutliers);
    const Eigen::Vector3d s_white(mg.white_sigma_horizontal_m, mg.white_sigma_horizontal_m,
                                  mg.white_sigma_vertical_m);
    const Eigen::Vector3d s_drift(mg.drift_sigma_horizontal_m, mg.drift_sigma_horizontal_m,
                                  mg.drift_sigma_vertical_m);
    Eigen::Vector3d drift = s_drift.cwiseProduct(drift_rng.Normal3());  // stationary start
    // Gross-error episodes over the fixes' span: an alternating renewal process.
    struct Episode {
      TimeNs start, end;
      Eigen::Vector3d offset;
    };
    std::vector<Episode> episodes;
    if (mg.gross_rate_per_hour > 0.0 && !real.gnss_fixes.empty()) {
      const double rate_s = mg.gross_rate_per_hour / 3600.0;
      const TimeNs first = real.gnss_fixes.front().t_ns, last_fix = real.gnss_fixes.back().t_ns;
      double t = 0.0;
      while (true) {
        t += -std::log(1.0 - outlier_rng.Uniform()) / rate_s;
        if (first + SecondsToNs(t) > last_fix) break;
        const double len = -std::log(1.0 - outlier_rng.Uniform()) * mg.gross_mean_duration_s;
        const double angle = 2.0 * M_PI * outlier_rng.Uniform();
        // Rayleigh length of RMS r: r sqrt(-ln(1 - u)).
        const double length =
            mg.gross_offset_horizontal_m * std::sqrt(-std::log(1.0 - outlier_rng.Uniform()));
        const Eigen::Vector3d offset(length * std::sin(angle), length * std::cos(angle),
                                     mg.gross_offset_vertical_m * outlier_rng.Normal());
        episodes.push_back({first + SecondsToNs(t), first + SecondsToNs(t + len), offset});
        t += len;
      }
      // At least one fix each: an episode between two fixes holds the next one.
      for (Episode& e : episodes) {
        const auto next = std::lower_bound(real.gnss_fixes.begin(), real.gnss_fixes.end(), e.start,
                                           [](const GnssFix& f, TimeNs v) { return f.t_ns < v; });
        if (next != real.gnss_fixes.end()) e.end = std::max(e.end, next->t_ns);
      }
    }
    // Solve and propagate: the current solution's index (k in phase + k period), its time, its
    // offset and its propagation velocity error. Its own stream, drawn only when on, so that a
    // model without it draws what it always drew.
    const bool solve = mg.solve_period_s > 0.0;
    Rng solve_rng(seed, RngStream::kTwinGnssSolve);
    const TimeNs solve_period_ns = solve ? SecondsToNs(mg.solve_period_s) : 1;
    const TimeNs solve_phase_ns = SecondsToNs(mg.solve_phase_s);
    bool solved = false;
    std::int64_t solution = 0;
    TimeNs t_solution = 0;
    Eigen::Vector2d solve_offset = Eigen::Vector2d::Zero(), v_err = Eigen::Vector2d::Zero();
    size_t episode = 0;
    TimeNs last = -1;
    const TimeNs latency_ns = SecondsToNs(mg.latency_s);
    for (const GnssFix& r : real.gnss_fixes) {
      if (!truth.Covers(r.t_ns)) continue;
      if (last >= 0) {
        const double phi = std::exp(-NsToSeconds(r.t_ns - last) / mg.drift_tau_s);
        drift =
            phi * drift + std::sqrt(1.0 - phi * phi) * s_drift.cwiseProduct(drift_rng.Normal3());
      }
      last = r.t_ns;
      // Every fix draws the same numbers whatever the model says, so that changing one
      // parameter (a calibration step) leaves the others' realisations alone.
      const Eigen::Vector3d w = white.Normal3();
      const double heading_noise = heading_rng.Normal();
      // The episode this fix falls in (episodes are in time order and do not overlap).
      while (episode < episodes.size() && episodes[episode].end < r.t_ns) ++episode;
      const bool gross = episode < episodes.size() && episodes[episode].start <= r.t_ns;
      const BodyKinematics kin = truth.At(r.t_ns - latency_ns);
      const Eigen::Vector3d p_w_g = kin.p_w_b + kin.q_w_b * real.gnss.p_b_g;
      Eigen::Vector3d e_n = s_white.cwiseProduct(w) + drift;
      if (gross) e_n += episodes[episode].offset;
      if (solve) {
        const std::int64_t k = FloorDiv(r.t_ns - solve_phase_ns, solve_period_ns);
        if (!solved || k != solution) {
          // A new solution: the velocity error stepped over the solutions since the last one
          // (x+ = phi x + sigma sqrt(1 - phi^2) w, phi = exp(-dt / tau); stationary at the
          // first), a fresh offset. The same four numbers per solution whatever the sigmas.
          const Eigen::Vector2d w_v(solve_rng.Normal(), solve_rng.Normal());
          const Eigen::Vector2d w_o(solve_rng.Normal(), solve_rng.Normal());
          const double phi = solved ? std::exp(-static_cast<double>(k - solution) *
                                               mg.solve_period_s / mg.propagation_velocity_tau_s)
                                    : 0.0;
          v_err =
              phi * v_err + mg.propagation_velocity_sigma_m_s * std::sqrt(1.0 - phi * phi) * w_v;
          solve_offset = mg.solve_offset_sigma_m * w_o;
          solved = true;
          solution = k;
          t_solution = solve_phase_ns + k * solve_period_ns;
        }
        e_n.head<2>() += solve_offset + v_err * NsToSeconds(r.t_ns - t_solution);
      }
      const Eigen::Matrix3d R_w_n = earth.LocalLevelAt(p_w_g);
      GnssFix fix;
      fix.t_ns = r.t_ns;
      fix.p_w = p_w_g + R_w_n * e_n;
      const Eigen::Vector3d llh = frame.ToGeodetic(fix.p_w);
      fix.lat_deg = llh.x();
      fix.lon_deg = llh.y();
      fix.height_m = llh.z();
      fix.sigma_enu_m = r.sigma_enu_m;
      if (r.has_heading) {
        const Eigen::Vector3d b_n = R_w_n.transpose() * (kin.q_w_b * real.gnss.baseline_b);
        double heading =
            std::atan2(b_n.x(), b_n.y()) * kRadToDeg + mg.heading_sigma_deg * heading_noise;
        heading = std::fmod(heading, 360.0);
        if (heading < 0.0) heading += 360.0;
        fix.has_heading = true;
        fix.heading_deg = heading;
        fix.sigma_heading_deg = r.sigma_heading_deg;
      }
      twin.gnss_fixes.push_back(fix);
    }
  }
  if (twin.imu_samples.empty() && twin.gnss_fixes.empty()) {
    throw std::invalid_argument("SimulateTwin: the truth does not overlap the recording");
  }

  // --- Ground truth over the truth's span. -----------------------------------------------------
  const TimeNs step = SecondsToNs(1.0 / truth_rate_hz);
  for (TimeNs t = truth.start_ns(); t <= truth.end_ns(); t += step) {
    const NavState s = truth.StateAt(t);
    twin.truth_states.push_back(s);
    StampedPose pose;
    pose.t_ns = t;
    pose.p_w_b = s.p_w_b;
    pose.q_w_b = s.q_w_b;
    twin.groundtruth.push_back(pose);
  }
  return twin;
}

}  // namespace skerry::sim
