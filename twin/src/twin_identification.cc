#include "skerry/twin/twin_identification.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <utility>
#include <vector>

#include "median.h"
#include "skerry/core/input_error.h"
#include "skerry/io/atomic_file.h"
#include "skerry/sim/earth_field.h"
#include "skerry/sim/earth_motion.h"

namespace skerry {
namespace {

constexpr double kRadToDeg = 180.0 / 3.14159265358979323846;

using twin_internal::Median;

// The white-noise sigma of a series from its first differences: 1.4826 MAD / sqrt(2) (the MAD of
// a normal sample; differencing removes what changes slowly and doubles the white variance).
// Its 1-sigma: the MAD's asymptotic efficiency of 0.37 gives sd ~ 1.65 sigma / sqrt(2 n) ~
// 1.17 sigma / sqrt(n) (Rousseeuw & Croux 1993), for the n differences.
IdentifiedValue WhiteSigmaFromDifferences(const std::vector<double>& x) {
  IdentifiedValue out;
  if (x.size() < 10) return out;
  std::vector<double> d(x.size() - 1);
  for (size_t i = 0; i + 1 < x.size(); ++i) d[i] = x[i + 1] - x[i];
  const double med = Median(d);
  for (double& v : d) v = std::abs(v - med);
  out.value = 1.4826 * Median(d) / std::sqrt(2.0);
  out.sigma = 1.17 * out.value / std::sqrt(static_cast<double>(d.size()));
  out.identified = true;
  return out;
}

// The RMS over three axes with its sigma propagated (independent axes).
IdentifiedValue RmsOfAxes(const IdentifiedValue v[3]) {
  IdentifiedValue out;
  double ss = 0.0, var = 0.0;
  out.identified = true;
  for (int k = 0; k < 3; ++k) {
    ss += v[k].value * v[k].value;
    out.identified = out.identified && v[k].identified;
  }
  out.value = std::sqrt(ss / 3.0);
  if (out.value > 0.0) {
    // d rms / d v_k = v_k / (3 rms)
    for (int k = 0; k < 3; ++k) {
      const double g = v[k].value / (3.0 * out.value);
      var += g * g * v[k].sigma * v[k].sigma;
    }
  }
  out.sigma = std::sqrt(var);
  return out;
}

// Gross errors: a residual more than k robust scales from the median, horizontally (2-D, in
// units of the larger of the east and north scales) or vertically.
std::vector<bool> GrossErrors(const GnssResidualSeries& s, double k) {
  const size_t n = s.t_s.size();
  Eigen::Vector3d med, scale;
  for (int a = 0; a < 3; ++a) {
    std::vector<double> x(n);
    for (size_t i = 0; i < n; ++i) x[i] = s.e_enu_m[i][a];
    med[a] = Median(x);
    for (double& v : x) v = std::abs(v - med[a]);
    scale[a] = std::max(1.4826 * Median(x), 1e-3);
  }
  const double scale_h = std::max(scale.x(), scale.y());
  std::vector<bool> gross(n);
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector3d d = s.e_enu_m[i] - med;
    gross[i] = d.head<2>().norm() > k * scale_h || std::abs(d.z()) > k * scale.z();
  }
  return gross;
}

GrossErrorEpisodes Episodes(const GnssResidualSeries& s, const std::vector<bool>& gross) {
  GrossErrorEpisodes out;
  const size_t n = s.t_s.size();
  std::vector<double> gaps;
  for (size_t i = 1; i < n; ++i) gaps.push_back(s.t_s[i] - s.t_s[i - 1]);
  const double period = Median(gaps);
  Eigen::Vector3d med;
  for (int a = 0; a < 3; ++a) {
    std::vector<double> x(n);
    for (size_t i = 0; i < n; ++i) x[i] = s.e_enu_m[i][a];
    med[a] = Median(x);
  }
  std::vector<double> durations, h2, v2;
  for (size_t i = 0; i < n;) {
    if (!gross[i]) {
      ++i;
      continue;
    }
    size_t j = i;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    while (j < n && gross[j]) sum += s.e_enu_m[j++] - med;
    const Eigen::Vector3d mean = sum / static_cast<double>(j - i);
    durations.push_back(s.t_s[j - 1] - s.t_s[i] + period);
    h2.push_back(mean.head<2>().squaredNorm());
    v2.push_back(mean.z() * mean.z());
    out.fixes += static_cast<int>(j - i);
    i = j;
  }
  out.episodes = static_cast<int>(durations.size());
  const double span_h = (s.t_s.back() - s.t_s.front() + period) / 3600.0;
  const double N = out.episodes;
  // Poisson count: rate +- sqrt(N) / T (0 episodes: an upper scale of 1 / T).
  out.rate_per_hour = {N / span_h, std::sqrt(std::max(N, 1.0)) / span_h, true};
  if (out.episodes == 0) return out;
  double mean_d = 0.0, var_d = 0.0, ms_h = 0.0, ms_v = 0.0;
  for (size_t e = 0; e < durations.size(); ++e) {
    mean_d += durations[e] / N;
    ms_h += h2[e] / N;
    ms_v += v2[e] / N;
  }
  for (double d : durations) var_d += (d - mean_d) * (d - mean_d);
  // An exponential length's sd equals its mean: with one episode, that is its only sd.
  const double sd_d = out.episodes > 1 ? std::sqrt(var_d / (N - 1.0)) : mean_d;
  out.mean_duration_s = {mean_d, sd_d / std::sqrt(N), true};
  out.offset_horizontal_m = {std::sqrt(ms_h), std::sqrt(ms_h) / std::sqrt(2.0 * N), true};
  out.offset_vertical_m = {std::sqrt(ms_v), std::sqrt(ms_v) / std::sqrt(2.0 * N), true};
  return out;
}

double HeadingOf(const Eigen::Vector3d& v_n) { return std::atan2(v_n.x(), v_n.y()) * kRadToDeg; }

}  // namespace

GnssResidualSeries GnssResidualsAgainstTruth(const Dataset& real,
                                             const sim::SplineMotion& truth,
                                             std::vector<size_t>* fix_index) {
  const sim::EarthField earth(real.origin, real.earth);
  GnssResidualSeries series;
  if (fix_index != nullptr) fix_index->clear();
  for (size_t k = 0; k < real.gnss_fixes.size(); ++k) {
    const GnssFix& f = real.gnss_fixes[k];
    if (!truth.Covers(f.t_ns)) continue;
    const sim::BodyKinematics kin = truth.At(f.t_ns);
    const Eigen::Vector3d p_w_g = kin.p_w_b + kin.q_w_b * real.gnss.p_b_g;
    const Eigen::Vector3d v_w_g = kin.v_w + kin.q_w_b * kin.omega_b.cross(real.gnss.p_b_g);
    const Eigen::Matrix3d R_w_n = earth.LocalLevelAt(p_w_g);
    series.t_s.push_back(NsToSeconds(f.t_ns - truth.start_ns()));
    series.e_enu_m.push_back(R_w_n.transpose() * (f.p_w - p_w_g));
    series.v_enu_m_s.push_back(R_w_n.transpose() * v_w_g);
    if (fix_index != nullptr) fix_index->push_back(k);
  }
  return series;
}

void WriteGnssResidualsCsv(const std::string& path, const TwinIdentification& id) {
  AtomicFile file(path);
  std::ofstream& out = file.stream();
  out << "t,e_east,e_north,e_up,v_east,v_north,v_up,gross\n";
  const GnssResidualSeries& s = id.gnss_residuals;
  char line[256];
  for (size_t i = 0; i < s.t_s.size(); ++i) {
    std::snprintf(line, sizeof(line), "%.6f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%d\n", s.t_s[i],
                  s.e_enu_m[i].x(), s.e_enu_m[i].y(), s.e_enu_m[i].z(), s.v_enu_m_s[i].x(),
                  s.v_enu_m_s[i].y(), s.v_enu_m_s[i].z(), id.gnss_gross[i] ? 1 : 0);
    out << line;
  }
  file.Commit();
}

Dataset CropToTruth(const Dataset& real, const sim::SplineMotion& truth) {
  Dataset out;
  out.name = real.name;
  out.directory = real.directory;
  out.origin = real.origin;
  out.earth = real.earth;
  out.has_imu = real.has_imu;
  out.imu = real.imu;
  out.imu_path = real.imu_path;
  out.gnss = real.gnss;
  out.has_gnss = real.has_gnss;
  out.gnss_path = real.gnss_path;
  out.water_surface = real.water_surface;
  for (const ImuSample& s : real.imu_samples) {
    if (truth.Covers(s.t_ns)) out.imu_samples.push_back(s);
  }
  for (const GnssFix& f : real.gnss_fixes) {
    if (truth.Covers(f.t_ns)) out.gnss_fixes.push_back(f);
  }
  for (const StampedPose& p : real.groundtruth) {
    if (truth.Covers(p.t_ns)) out.groundtruth.push_back(p);
  }
  for (const NavState& s : real.truth_states) {
    if (truth.Covers(s.t_ns)) out.truth_states.push_back(s);
  }
  return out;
}

TwinIdentification IdentifyTwin(const Dataset& real,
                                const sim::SplineMotion& truth,
                                const TwinIdentifyOptions& options) {
  TwinIdentification id;
  const sim::EarthField earth(real.origin, real.earth);
  const std::string file = real.directory.empty() ? real.name : real.directory;

  // --- Timing, from every stamp of the recording. -------------------------------------------
  std::vector<std::int64_t> stamps;
  if (real.has_imu && real.imu_samples.size() >= 2) {
    for (const ImuSample& s : real.imu_samples) stamps.push_back(s.t_ns);
    id.imu_timing = AnalyseStreamTiming("imu", stamps);
  }
  stamps.clear();
  if (real.has_gnss && real.gnss_fixes.size() >= 2) {
    for (const GnssFix& f : real.gnss_fixes) stamps.push_back(f.t_ns);
    id.gnss_timing = AnalyseStreamTiming("gnss", stamps);
  }

  // --- IMU. -----------------------------------------------------------------------------------
  ImuIdentification& imu = id.imu;
  if (real.has_imu) {
    std::vector<double> rg[3], ra[3];
    for (const ImuSample& s : real.imu_samples) {
      if (!truth.Covers(s.t_ns)) continue;
      const sim::BodyKinematics kin = truth.At(s.t_ns);
      const NavState state = truth.StateAt(s.t_ns);
      const Eigen::Vector3d p_w_i = kin.p_w_b + kin.q_w_b * real.imu.p_b_i;
      const ImuSample ideal = sim::IdealImu(kin, real.imu.q_b_i, real.imu.p_b_i, earth.omega_ie_w(),
                                            earth.GravityAt(p_w_i));
      const Eigen::Vector3d eg = s.gyro_rad_s - ideal.gyro_rad_s - state.bg;
      const Eigen::Vector3d ea = s.accel_m_s2 - ideal.accel_m_s2 - state.ba;
      for (int k = 0; k < 3; ++k) {
        rg[k].push_back(eg[k]);
        ra[k].push_back(ea[k]);
      }
    }
    if (rg[0].empty()) {
      throw InputError(file, 0, "imu", "the batch trajectory covers no IMU sample");
    }
    imu.residual_samples = static_cast<long>(rg[0].size());
    const double rate = id.imu_timing ? id.imu_timing->rate_hz : real.imu.rate_hz;
    IdentifiedValue g[3], a[3];
    for (int k = 0; k < 3; ++k) {
      g[k] = WhiteSigmaFromDifferences(rg[k]);
      a[k] = WhiteSigmaFromDifferences(ra[k]);
      for (IdentifiedValue* v : {&g[k], &a[k]}) {
        v->value /= std::sqrt(rate);  // discrete sigma -> density
        v->sigma /= std::sqrt(rate);
      }
    }
    imu.residual_gyro_density = RmsOfAxes(g);
    imu.residual_accel_density = RmsOfAxes(a);
    imu.gyro_noise_density = imu.residual_gyro_density;
    imu.accel_noise_density = imu.residual_accel_density;
    imu.noise_source = "residuals";

    const std::vector<RestSegment> rests = FindRestSegments(real.imu_samples, options.min_rest_s);
    if (!rests.empty()) {
      imu.allan = AnalyseImuAtRest(real.imu_samples, rests.front());
      imu.gyro_bias_instability = imu.allan->gyro_combined.bias_instability;
      imu.accel_bias_instability = imu.allan->accel_combined.bias_instability;
      imu.gyro_random_walk = imu.allan->gyro_combined.random_walk;
      imu.accel_random_walk = imu.allan->accel_combined.random_walk;
      // A rest whose short-term curve is not white (a running engine's vibration, a hull in
      // waves) identifies no white density: the residuals' stands.
      if (options.imu_noise == "rest" && imu.allan->gyro_combined.white_density.identified &&
          imu.allan->accel_combined.white_density.identified) {
        imu.gyro_noise_density = imu.allan->gyro_combined.white_density;
        imu.accel_noise_density = imu.allan->accel_combined.white_density;
        imu.noise_source = "rest";
      }
    }
    id.model.imu.gyro_noise_density_rad_s_sqrt_hz = imu.gyro_noise_density.value;
    id.model.imu.accel_noise_density_m_s2_sqrt_hz = imu.accel_noise_density.value;
  }

  // --- GNSS: residuals in the local east, north, up at the antenna. ----------------------------
  if (real.has_gnss) {
    GnssResidualSeries series = GnssResidualsAgainstTruth(real, truth);
    std::vector<double> heading_residuals;
    for (const GnssFix& f : real.gnss_fixes) {
      if (!f.has_heading || !truth.Covers(f.t_ns)) continue;
      const sim::BodyKinematics kin = truth.At(f.t_ns);
      const Eigen::Vector3d p_w_g = kin.p_w_b + kin.q_w_b * real.gnss.p_b_g;
      const Eigen::Matrix3d R_w_n = earth.LocalLevelAt(p_w_g);
      const double h = HeadingOf(R_w_n.transpose() * (kin.q_w_b * real.gnss.baseline_b));
      heading_residuals.push_back(std::remainder(f.heading_deg - h, 360.0));
    }
    if (series.t_s.size() < 30) {
      throw InputError(file, 0, "gnss",
                       "the batch trajectory covers " + std::to_string(series.t_s.size()) +
                           " fixes; identifying a GNSS model needs at least 30");
    }
    id.gnss_gross = GrossErrors(series, options.gross_threshold_sigma);
    id.gross = Episodes(series, id.gnss_gross);
    GnssResidualSeries clean;
    for (size_t i = 0; i < series.t_s.size(); ++i) {
      if (id.gnss_gross[i]) continue;
      clean.t_s.push_back(series.t_s[i]);
      clean.e_enu_m.push_back(series.e_enu_m[i]);
      clean.v_enu_m_s.push_back(series.v_enu_m_s[i]);
    }
    if (clean.t_s.size() < 30) {
      throw InputError(file, 0, "gnss",
                       "only " + std::to_string(clean.t_s.size()) +
                           " fixes are not gross errors; identifying a GNSS model needs 30");
    }
    id.gnss = FitGnssErrorModel(clean, options.gnss);
    id.gnss_residuals = std::move(series);
    const GnssErrorModelFit& g = *id.gnss;
    sim::TwinGnssModel& m = id.model.gnss;
    m.latency_s = g.latency_s.identified ? std::max(0.0, g.latency_s.value) : 0.0;
    m.white_sigma_horizontal_m = g.white_sigma_horizontal_m.value;
    m.white_sigma_vertical_m = g.white_sigma_vertical_m.value;
    if (g.drift_tau_s.identified) {
      m.drift_sigma_horizontal_m = g.drift_sigma_horizontal_m.value;
      m.drift_sigma_vertical_m = g.drift_sigma_vertical_m.value;
      m.drift_tau_s = g.drift_tau_s.value;
    }
    if (id.gross.episodes > 0) {
      m.gross_rate_per_hour = id.gross.rate_per_hour.value;
      m.gross_mean_duration_s = id.gross.mean_duration_s.value;
      m.gross_offset_horizontal_m = id.gross.offset_horizontal_m.value;
      m.gross_offset_vertical_m = id.gross.offset_vertical_m.value;
    }
    if (!heading_residuals.empty()) {
      id.heading.samples = static_cast<int>(heading_residuals.size());
      const double med = Median(heading_residuals);
      std::vector<double> dev;
      for (double r : heading_residuals) dev.push_back(std::abs(r - med));
      id.heading.sigma_deg.value = 1.4826 * Median(dev);
      id.heading.sigma_deg.sigma =
          1.65 * id.heading.sigma_deg.value / std::sqrt(2.0 * heading_residuals.size());
      id.heading.sigma_deg.identified = heading_residuals.size() >= 10;
      m.heading_sigma_deg = id.heading.sigma_deg.value;
    }
  }
  return id;
}

}  // namespace skerry
