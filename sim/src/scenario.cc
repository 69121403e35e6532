#include "skerry/sim/scenario.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <set>
#include <sstream>
#include <utility>

#include "skerry/core/format_number.h"
#include "skerry/core/input_error.h"
#include "skerry/core/time.h"

#ifndef SKERRY_SCENARIO_INSTALL_DIR
#define SKERRY_SCENARIO_INSTALL_DIR ""
#endif
#ifndef SKERRY_SCENARIO_SOURCE_DIR
#define SKERRY_SCENARIO_SOURCE_DIR ""
#endif

namespace skerry::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegPerSqrtHourToRadPerSqrtS = kPi / 180.0 / 60.0;  // ARW deg/sqrt(h)
constexpr double kDegPerHourToRadPerS = kPi / 180.0 / 3600.0;
constexpr double kMetrePerSecondPerSqrtHour = 1.0 / 60.0;  // VRW m/s/sqrt(h) -> m/s^2/sqrt(Hz)
constexpr double kMilliG = 9.80665e-3;                     // m/s^2
// The highest rate a scenario may give (a megahertz: above any sensor simulated here), and the
// most samples one stream may have (duration_s x rate: 1e8 IMU samples hold about 10 GB).
constexpr double kMaxRateHz = 1e6;
constexpr double kMaxSamples = 1e8;

std::string Join(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

std::string Index(const std::string& path, std::size_t i) {
  return path + "[" + std::to_string(i) + "]";
}

int LineOf(const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  return mark.is_null() ? 0 : mark.line + 1;
}

/// Typed access to a YAML tree that turns every problem into an InputError with file, line and
/// key path.
class Reader {
 public:
  explicit Reader(std::string file) : file_(std::move(file)) {}

  [[noreturn]] void Fail(const YAML::Node& node,
                         const std::string& path,
                         const std::string& message) const {
    throw InputError(file_, LineOf(node), path, message);
  }

  void ExpectMap(const YAML::Node& node, const std::string& path) const {
    if (!node.IsMap()) Fail(node, path, "expected a mapping");
  }

  void ExpectSequence(const YAML::Node& node, const std::string& path) const {
    if (!node.IsSequence()) Fail(node, path, "expected a sequence");
  }

  /// Rejects keys not in `allowed` (catches typos such as `duration: 10` for `duration_s`).
  void CheckKeys(const YAML::Node& map,
                 const std::string& path,
                 std::initializer_list<const char*> allowed) const {
    ExpectMap(map, path);
    for (const auto& kv : map) {
      if (!kv.first.IsScalar())
        Fail(kv.first, path.empty() ? "(document)" : path, "a key must be a plain name");
      const std::string key = kv.first.Scalar();
      const bool known =
          std::any_of(allowed.begin(), allowed.end(), [&key](const char* a) { return key == a; });
      if (!known) {
        std::string list;
        for (const char* a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
        Fail(kv.first, Join(path, key), "unknown key (expected one of: " + list + ")");
      }
    }
  }

  YAML::Node Required(const YAML::Node& map, const std::string& path, const char* key) const {
    const YAML::Node node = map[key];
    if (!node) Fail(map, Join(path, key), "missing required key");
    return node;
  }

  double Double(const YAML::Node& node, const std::string& path) const {
    if (!node.IsScalar()) Fail(node, path, "expected a number");
    double value = 0.0;
    try {
      value = node.as<double>();
    } catch (const YAML::Exception&) {
      Fail(node, path, "expected a number, got '" + node.Scalar() + "'");
    }
    if (!std::isfinite(value)) Fail(node, path, "must be finite");
    return value;
  }

  double Double(const YAML::Node& map, const std::string& path, const char* key) const {
    return InRange(map[key], Join(path, key), key,
                   Double(Required(map, path, key), Join(path, key)));
  }

  double Double(const YAML::Node& map,
                const std::string& path,
                const char* key,
                double fallback) const {
    return map[key] ? InRange(map[key], Join(path, key), key, Double(map[key], Join(path, key)))
                    : fallback;
  }

  /// The keys that are times or rates, wherever they stand, kept where skerry can count them:
  /// a time at most kMaxDurationS (TimeNs holds 292 years; 1e300 s was cast to an integer
  /// sample count, undefined behaviour), a rate between 1 / kMaxDurationS and kMaxRateHz.
  double InRange(const YAML::Node& node,
                 const std::string& path,
                 const std::string& key,
                 double v) const {
    static const std::set<std::string> kTimes = {
        "duration_s", "tau_s", "mean_duration_s", "offset_s", "latency_s", "stamp_jitter_s",
        "start_s",    "end_s", "time_offset_s",   "ramp_s",   "period_s"};
    static const std::set<std::string> kRates = {"rate_hz", "write_rate_hz", "rotation_rate_hz",
                                                 "groundtruth_rate_hz"};
    if (kTimes.count(key) > 0 && std::abs(v) > kMaxDurationS) {
      Fail(node, path, "must be within +-" + FormatNumber(kMaxDurationS) + " s");
    }
    // A rate that is not positive is its caller's to refuse, with its own words.
    if (kRates.count(key) > 0 && v > 0.0 && (v < 1.0 / kMaxDurationS || v > kMaxRateHz)) {
      Fail(node, path,
           "must be between " + FormatNumber(1.0 / kMaxDurationS) + " and " +
               FormatNumber(kMaxRateHz) + " Hz");
    }
    return v;
  }

  /// Optional number with a lower bound (inclusive unless strict).
  double Bounded(const YAML::Node& map,
                 const std::string& path,
                 const char* key,
                 double fallback,
                 double lower,
                 bool strict) const {
    const double v = Double(map, path, key, fallback);
    if (strict ? !(v > lower) : !(v >= lower)) {
      Fail(map[key] ? map[key] : map, Join(path, key),
           std::string("must be ") + (strict ? "> " : ">= ") + FormatNumber(lower));
    }
    return v;
  }

  double Positive(const YAML::Node& map, const std::string& path, const char* key) const {
    const double v = Double(map, path, key);
    if (!(v > 0.0)) Fail(map[key], Join(path, key), "must be > 0");
    return v;
  }

  double Positive(const YAML::Node& map,
                  const std::string& path,
                  const char* key,
                  double fallback) const {
    return Bounded(map, path, key, fallback, 0.0, true);
  }

  double NonNegative(const YAML::Node& map,
                     const std::string& path,
                     const char* key,
                     double fallback) const {
    return Bounded(map, path, key, fallback, 0.0, false);
  }

  template <int N>
  Eigen::Matrix<double, N, 1> Vector(const YAML::Node& node, const std::string& path) const {
    if (!node.IsSequence() || node.size() != static_cast<std::size_t>(N)) {
      Fail(node, path, "expected a list of " + std::to_string(N) + " numbers");
    }
    Eigen::Matrix<double, N, 1> v;
    for (int i = 0; i < N; ++i) v[i] = Double(node[i], Index(path, static_cast<std::size_t>(i)));
    return v;
  }

  template <int N>
  Eigen::Matrix<double, N, 1> Vector(const YAML::Node& map,
                                     const std::string& path,
                                     const char* key,
                                     const Eigen::Matrix<double, N, 1>& fallback) const {
    return map[key] ? Vector<N>(map[key], Join(path, key)) : fallback;
  }

  bool Bool(const YAML::Node& map, const std::string& path, const char* key, bool fallback) const {
    const YAML::Node node = map[key];
    if (!node) return fallback;
    bool value = false;
    if (!node.IsScalar() || !YAML::convert<bool>::decode(node, value)) {
      Fail(node, Join(path, key), "expected true or false");
    }
    return value;
  }

  std::string String(const YAML::Node& map,
                     const std::string& path,
                     const char* key,
                     const std::string& fallback) const {
    const YAML::Node node = map[key];
    if (!node) return fallback;
    if (!node.IsScalar()) Fail(node, Join(path, key), "expected a string");
    return node.Scalar();
  }

  std::uint64_t UInt64(const YAML::Node& map,
                       const std::string& path,
                       const char* key,
                       std::uint64_t fallback) const {
    const YAML::Node node = map[key];
    if (!node) return fallback;
    const std::string text = node.IsScalar() ? node.Scalar() : std::string();
    if (text.empty() || text.find_first_not_of("0123456789") != std::string::npos) {
      Fail(node, Join(path, key), "expected a non-negative integer");
    }
    try {
      return std::stoull(text);
    } catch (const std::exception&) {
      Fail(node, Join(path, key), "integer out of range");
    }
  }

 private:
  std::string file_;
};

ImuGrade ParseGrade(const Reader& r, const YAML::Node& node, const std::string& path) {
  const std::string name = node.Scalar();
  if (name == "consumer") return ImuGrade::kConsumer;
  if (name == "tactical") return ImuGrade::kTactical;
  if (name == "navigation") return ImuGrade::kNavigation;
  r.Fail(node, path, "unknown IMU grade '" + name + "' (expected consumer, tactical, navigation)");
}

ImuModel ParseImu(const Reader& r, const YAML::Node& node, const std::string& path) {
  if (node.IsMap() && node["gravity_m_s2"]) {
    r.Fail(node["gravity_m_s2"], Join(path, "gravity_m_s2"),
           "moved: gravity is the Earth's; write `earth: {model: flat, gravity_m_s2: ...}` at the "
           "top level, or leave it out for the WGS84 Earth");
  }
  r.CheckKeys(node, path,
              {"grade", "rate_hz", "T_b_i", "gyro_noise_density_rad_s_sqrt_hz",
               "accel_noise_density_m_s2_sqrt_hz", "gyro_bias_random_walk_rad_s2_sqrt_hz",
               "accel_bias_random_walk_m_s3_sqrt_hz", "gyro_bias_initial_sigma_rad_s",
               "accel_bias_initial_sigma_m_s2", "scale_factor_ppm", "misalignment_mrad",
               "bias_instability"});
  ImuModel imu;
  imu.grade = r.String(node, path, "grade", "tactical");
  imu.errors = ImuGradePreset(
      ParseGrade(r, node["grade"] ? node["grade"] : YAML::Node("tactical"), Join(path, "grade")));
  imu.rate_hz = r.Positive(node, path, "rate_hz", 200.0);
  ImuNoise& n = imu.errors.noise;
  n.gyro_noise_density_rad_s_sqrt_hz = r.NonNegative(node, path, "gyro_noise_density_rad_s_sqrt_hz",
                                                     n.gyro_noise_density_rad_s_sqrt_hz);
  n.accel_noise_density_m_s2_sqrt_hz = r.NonNegative(node, path, "accel_noise_density_m_s2_sqrt_hz",
                                                     n.accel_noise_density_m_s2_sqrt_hz);
  n.gyro_bias_random_walk_rad_s2_sqrt_hz = r.NonNegative(
      node, path, "gyro_bias_random_walk_rad_s2_sqrt_hz", n.gyro_bias_random_walk_rad_s2_sqrt_hz);
  n.accel_bias_random_walk_m_s3_sqrt_hz = r.NonNegative(
      node, path, "accel_bias_random_walk_m_s3_sqrt_hz", n.accel_bias_random_walk_m_s3_sqrt_hz);
  imu.errors.gyro_bias_initial_sigma_rad_s = r.NonNegative(
      node, path, "gyro_bias_initial_sigma_rad_s", imu.errors.gyro_bias_initial_sigma_rad_s);
  imu.errors.accel_bias_initial_sigma_m_s2 = r.NonNegative(
      node, path, "accel_bias_initial_sigma_m_s2", imu.errors.accel_bias_initial_sigma_m_s2);
  ImuErrorModel& e = imu.errors;
  if (const YAML::Node sf = node["scale_factor_ppm"]) {
    const std::string sp = Join(path, "scale_factor_ppm");
    r.CheckKeys(sf, sp, {"gyro", "accel"});
    e.gyro_scale_factor_ppm = r.NonNegative(sf, sp, "gyro", e.gyro_scale_factor_ppm);
    e.accel_scale_factor_ppm = r.NonNegative(sf, sp, "accel", e.accel_scale_factor_ppm);
  }
  if (const YAML::Node ma = node["misalignment_mrad"]) {
    const std::string mp = Join(path, "misalignment_mrad");
    r.CheckKeys(ma, mp, {"gyro", "accel"});
    e.gyro_misalignment_mrad = r.NonNegative(ma, mp, "gyro", e.gyro_misalignment_mrad);
    e.accel_misalignment_mrad = r.NonNegative(ma, mp, "accel", e.accel_misalignment_mrad);
  }
  if (const YAML::Node bi = node["bias_instability"]) {
    const std::string bp = Join(path, "bias_instability");
    r.CheckKeys(bi, bp, {"gyro_rad_s", "accel_m_s2", "tau_s"});
    e.gyro_bias_instability_rad_s =
        r.NonNegative(bi, bp, "gyro_rad_s", e.gyro_bias_instability_rad_s);
    e.accel_bias_instability_m_s2 =
        r.NonNegative(bi, bp, "accel_m_s2", e.accel_bias_instability_m_s2);
    e.bias_instability_tau_s = r.NonNegative(bi, bp, "tau_s", e.bias_instability_tau_s);
    if (!(e.bias_instability_tau_s > 0.0) &&
        (e.gyro_bias_instability_rad_s > 0.0 || e.accel_bias_instability_m_s2 > 0.0)) {
      r.Fail(bi["tau_s"] ? bi["tau_s"] : bi, Join(bp, "tau_s"),
             "a bias instability needs a correlation time > 0 (set gyro_rad_s and accel_m_s2 "
             "to 0 for none)");
    }
  }
  if (const YAML::Node t = node["T_b_i"]) {
    const std::string tp = Join(path, "T_b_i");
    r.CheckKeys(t, tp, {"q_xyzw", "p_m"});
    const Eigen::Vector4d q = r.Vector<4>(t, tp, "q_xyzw", Eigen::Vector4d(0, 0, 0, 1));
    if (std::abs(q.norm() - 1.0) > 1e-6) {
      r.Fail(t["q_xyzw"], Join(tp, "q_xyzw"), "quaternion is not unit length");
    }
    imu.q_b_i = Eigen::Quaterniond(q[3], q[0], q[1], q[2]).normalized();
    imu.p_b_i = r.Vector<3>(t, tp, "p_m", Eigen::Vector3d::Zero());
  }
  return imu;
}

GnssModel ParseGnss(const Reader& r, const YAML::Node& node, const std::string& path) {
  r.CheckKeys(node, path,
              {"rate_hz", "lever_arm_b_m", "noise_sigma_horizontal_m", "noise_sigma_vertical_m",
               "reported_sigma_horizontal_m", "reported_sigma_vertical_m", "drift", "slow_drift",
               "multipath", "timing", "jumps", "outages", "dual_antenna"});
  GnssModel g;
  g.rate_hz = r.Positive(node, path, "rate_hz", g.rate_hz);
  g.p_b_g = r.Vector<3>(node, path, "lever_arm_b_m", g.p_b_g);
  g.noise_sigma_horizontal_m =
      r.NonNegative(node, path, "noise_sigma_horizontal_m", g.noise_sigma_horizontal_m);
  g.noise_sigma_vertical_m =
      r.NonNegative(node, path, "noise_sigma_vertical_m", g.noise_sigma_vertical_m);
  g.reported_sigma_horizontal_m =
      r.Positive(node, path, "reported_sigma_horizontal_m", g.reported_sigma_horizontal_m);
  g.reported_sigma_vertical_m =
      r.Positive(node, path, "reported_sigma_vertical_m", g.reported_sigma_vertical_m);
  if (const YAML::Node d = node["drift"]) {
    const std::string dp = Join(path, "drift");
    r.CheckKeys(d, dp, {"sigma_horizontal_m", "sigma_vertical_m", "tau_s"});
    g.drift_sigma_horizontal_m = r.NonNegative(d, dp, "sigma_horizontal_m", 0.0);
    g.drift_sigma_vertical_m = r.NonNegative(d, dp, "sigma_vertical_m", 0.0);
    g.drift_tau_s = r.Positive(d, dp, "tau_s", g.drift_tau_s);
  }
  if (const YAML::Node d = node["slow_drift"]) {
    const std::string dp = Join(path, "slow_drift");
    r.CheckKeys(d, dp, {"sigma_horizontal_m", "sigma_vertical_m", "tau_s"});
    g.slow_drift_sigma_horizontal_m = r.NonNegative(d, dp, "sigma_horizontal_m", 0.0);
    g.slow_drift_sigma_vertical_m = r.NonNegative(d, dp, "sigma_vertical_m", 0.0);
    g.slow_drift_tau_s = r.Positive(d, dp, "tau_s", g.slow_drift_tau_s);
  }
  if (const YAML::Node m = node["multipath"]) {
    const std::string mp = Join(path, "multipath");
    r.CheckKeys(
        m, mp,
        {"rate_per_hour", "mean_duration_s", "sigma_horizontal_m", "sigma_vertical_m", "tau_s"});
    g.multipath_rate_per_hour = r.NonNegative(m, mp, "rate_per_hour", 0.0);
    g.multipath_mean_duration_s = r.Positive(m, mp, "mean_duration_s", g.multipath_mean_duration_s);
    g.multipath_sigma_horizontal_m =
        r.NonNegative(m, mp, "sigma_horizontal_m", g.multipath_sigma_horizontal_m);
    g.multipath_sigma_vertical_m =
        r.NonNegative(m, mp, "sigma_vertical_m", g.multipath_sigma_vertical_m);
    g.multipath_tau_s = r.Positive(m, mp, "tau_s", g.multipath_tau_s);
  }
  if (const YAML::Node t = node["timing"]) {
    const std::string tp = Join(path, "timing");
    r.CheckKeys(t, tp, {"offset_s", "latency_s", "stamp_jitter_s"});
    g.time_offset_s = r.NonNegative(t, tp, "offset_s", 0.0);
    g.latency_s = r.NonNegative(t, tp, "latency_s", 0.0);
    g.stamp_jitter_s = r.NonNegative(t, tp, "stamp_jitter_s", 0.0);
    // Stamps must stay in order: jitter is cut at 3 sigma, so 6 sigma must fit in a period.
    if (6.0 * g.stamp_jitter_s >= 1.0 / g.rate_hz) {
      r.Fail(t["stamp_jitter_s"], Join(tp, "stamp_jitter_s"),
             "must be below a sixth of the fix period (stamps would swap)");
    }
  }
  if (const YAML::Node jumps = node["jumps"]) {
    const std::string jp = Join(path, "jumps");
    r.ExpectSequence(jumps, jp);
    for (std::size_t i = 0; i < jumps.size(); ++i) {
      const std::string ip = Index(jp, i);
      r.CheckKeys(jumps[i], ip, {"start_s", "duration_s", "offset_enu_m"});
      GnssJump j;
      j.start_s = r.Double(jumps[i], ip, "start_s");
      j.duration_s = r.Positive(jumps[i], ip, "duration_s");
      j.offset_enu_m =
          r.Vector<3>(r.Required(jumps[i], ip, "offset_enu_m"), Join(ip, "offset_enu_m"));
      g.jumps.push_back(j);
    }
  }
  if (const YAML::Node outages = node["outages"]) {
    const std::string op = Join(path, "outages");
    r.ExpectSequence(outages, op);
    for (std::size_t i = 0; i < outages.size(); ++i) {
      const std::string ip = Index(op, i);
      r.CheckKeys(outages[i], ip, {"start_s", "duration_s"});
      GnssOutage o;
      o.start_s = r.Double(outages[i], ip, "start_s");
      o.duration_s = r.Positive(outages[i], ip, "duration_s");
      g.outages.push_back(o);
    }
  }
  if (const YAML::Node d = node["dual_antenna"]) {
    const std::string dp = Join(path, "dual_antenna");
    r.CheckKeys(d, dp, {"enabled", "sigma_deg", "baseline_b"});
    g.dual_antenna_enabled = r.Bool(d, dp, "enabled", true);
    g.heading_sigma_deg = r.NonNegative(d, dp, "sigma_deg", g.heading_sigma_deg);
    g.baseline_b = r.Vector<3>(d, dp, "baseline_b", g.baseline_b);
    if (g.baseline_b.head<2>().norm() < 1e-6) {
      r.Fail(d["baseline_b"], Join(dp, "baseline_b"), "baseline must have a horizontal part");
    }
  }
  return g;
}

PoseFixModel ParsePoseFixes(const Reader& r, const YAML::Node& node, const std::string& path) {
  r.CheckKeys(node, path,
              {"enabled", "rate_hz", "time_offset_s", "start_s", "end_s", "kind",
               "sigma_horizontal_m", "sigma_vertical_m", "sigma_heading_deg", "outliers", "T_b_s"});
  PoseFixModel p;
  p.enabled = r.Bool(node, path, "enabled", true);
  p.rate_hz = r.Positive(node, path, "rate_hz", p.rate_hz);
  p.time_offset_s = r.NonNegative(node, path, "time_offset_s", p.time_offset_s);
  p.start_s = r.NonNegative(node, path, "start_s", p.start_s);
  p.end_s = r.Positive(node, path, "end_s", p.end_s);
  p.kind = r.String(node, path, "kind", p.kind);
  if (p.kind != "en" && p.kind != "enu" && p.kind != "enh" && p.kind != "enuh") {
    r.Fail(node["kind"], Join(path, "kind"), "expected en, enu, enh or enuh");
  }
  p.sigma_horizontal_m = r.Positive(node, path, "sigma_horizontal_m", p.sigma_horizontal_m);
  p.sigma_vertical_m = r.Positive(node, path, "sigma_vertical_m", p.sigma_vertical_m);
  p.sigma_heading_deg = r.Positive(node, path, "sigma_heading_deg", p.sigma_heading_deg);
  if (const YAML::Node o = node["outliers"]) {
    const std::string op = Join(path, "outliers");
    r.CheckKeys(o, op, {"probability", "min_m", "heading_min_deg"});
    p.outlier_probability = r.NonNegative(o, op, "probability", 0.0);
    if (p.outlier_probability > 1.0) r.Fail(o["probability"], Join(op, "probability"), "above 1");
    p.outlier_min_m = r.Positive(o, op, "min_m", p.outlier_min_m);
    p.outlier_heading_min_deg = r.Positive(o, op, "heading_min_deg", p.outlier_heading_min_deg);
  }
  if (const YAML::Node t = node["T_b_s"]) {
    const std::string tp = Join(path, "T_b_s");
    r.CheckKeys(t, tp, {"q_xyzw", "p_m"});
    const Eigen::Vector4d q = r.Vector<4>(t, tp, "q_xyzw", Eigen::Vector4d(0, 0, 0, 1));
    if (std::abs(q.norm() - 1.0) > 1e-3) r.Fail(t["q_xyzw"], Join(tp, "q_xyzw"), "not unit");
    p.mount.q_b_s = Eigen::Quaterniond(q[3], q[0], q[1], q[2]).normalized();
    p.mount.p_b_s = r.Vector<3>(t, tp, "p_m", p.mount.p_b_s);
  }
  return p;
}

CameraModelSim ParseCamera(const Reader& r, const YAML::Node& node, const std::string& path) {
  r.CheckKeys(node, path,
              {"enabled", "rate_hz", "time_offset_s", "start_s", "end_s", "width_px", "height_px",
               "horizontal_fov_deg", "distortion", "images", "ring", "p_b_c_m", "pitch_down_deg"});
  CameraModelSim c;
  c.enabled = r.Bool(node, path, "enabled", true);
  c.rate_hz = r.Positive(node, path, "rate_hz", c.rate_hz);
  c.time_offset_s = r.NonNegative(node, path, "time_offset_s", c.time_offset_s);
  c.start_s = r.NonNegative(node, path, "start_s", c.start_s);
  c.end_s = r.Positive(node, path, "end_s", c.end_s);
  const double w = r.Positive(node, path, "width_px", c.width_px);
  const double h = r.Positive(node, path, "height_px", c.height_px);
  if (w != std::floor(w) || h != std::floor(h) || w > 20000 || h > 20000) {
    r.Fail(node["width_px"] ? node["width_px"] : node, Join(path, "width_px"),
           "image sizes must be whole numbers up to 20000");
  }
  c.width_px = static_cast<int>(w);
  c.height_px = static_cast<int>(h);
  c.horizontal_fov_deg = r.Positive(node, path, "horizontal_fov_deg", c.horizontal_fov_deg);
  if (c.horizontal_fov_deg >= 170.0) {
    r.Fail(node["horizontal_fov_deg"], Join(path, "horizontal_fov_deg"), "must be below 170");
  }
  if (const YAML::Node d = node["distortion"]) {
    if (!d.IsSequence() || (d.size() != 0 && d.size() != 4 && d.size() != 5)) {
      r.Fail(d, Join(path, "distortion"), "expected 0, 4 or 5 coefficients (k1 k2 p1 p2 [k3])");
    }
    c.distortion.clear();
    for (size_t i = 0; i < d.size(); ++i) {
      c.distortion.push_back(
          r.Double(d[i], Join(path, "distortion") + "[" + std::to_string(i) + "]"));
    }
  }
  c.images = r.String(node, path, "images", c.images);
  if (c.images != "mask" && c.images != "grey") {
    r.Fail(node["images"], Join(path, "images"), "expected mask or grey");
  }
  c.ring = r.Bool(node, path, "ring", c.ring);
  c.p_b_c = r.Vector<3>(node, path, "p_b_c_m", c.p_b_c);
  c.pitch_down_deg = r.Double(node, path, "pitch_down_deg", c.pitch_down_deg);
  return c;
}

// A whole number in [lower, upper] (default `fallback`).
int WholeNumber(const Reader& r,
                const YAML::Node& map,
                const std::string& path,
                const char* key,
                int fallback,
                int lower,
                int upper) {
  const double v = r.Double(map, path, key, fallback);
  if (v != std::floor(v) || v < lower || v > upper) {
    r.Fail(
        map[key], Join(path, key),
        "expected a whole number from " + std::to_string(lower) + " to " + std::to_string(upper));
  }
  return static_cast<int>(v);
}

AerialImageSim ParseAerialImage(const Reader& r, const YAML::Node& node, const std::string& path) {
  r.CheckKeys(node, path,
              {"enabled", "resolution_m", "margin_m", "camera_height_m", "sun_azimuth_deg",
               "sun_elevation_deg", "image_offset_east_m", "image_offset_north_m", "noise_grey"});
  AerialImageSim a;
  a.enabled = r.Bool(node, path, "enabled", true);
  a.resolution_m = r.Positive(node, path, "resolution_m", a.resolution_m);
  if (a.resolution_m < 0.02) {
    r.Fail(node["resolution_m"], Join(path, "resolution_m"), "must be >= 0.02 (m per pixel)");
  }
  a.margin_m = r.NonNegative(node, path, "margin_m", a.margin_m);
  a.camera_height_m = r.Positive(node, path, "camera_height_m", a.camera_height_m);
  if (a.camera_height_m < 100.0) {
    r.Fail(node["camera_height_m"], Join(path, "camera_height_m"),
           "must be >= 100 m (above the tallest object, and a photograph from the air)");
  }
  a.sun_azimuth_deg = r.Double(node, path, "sun_azimuth_deg", a.sun_azimuth_deg);
  a.sun_elevation_deg = r.Positive(node, path, "sun_elevation_deg", a.sun_elevation_deg);
  if (a.sun_elevation_deg > 90.0) {
    r.Fail(node["sun_elevation_deg"], Join(path, "sun_elevation_deg"), "must be <= 90");
  }
  a.image_offset_east_m = r.Double(node, path, "image_offset_east_m", a.image_offset_east_m);
  a.image_offset_north_m = r.Double(node, path, "image_offset_north_m", a.image_offset_north_m);
  a.noise_grey = r.NonNegative(node, path, "noise_grey", a.noise_grey);
  return a;
}

HarbourSpec ParseHarbour(const Reader& r, const YAML::Node& node, const std::string& path) {
  r.CheckKeys(
      node, path,
      {"enabled", "centre_east_m", "centre_north_m", "rotation_deg", "water_level_up_m",
       "basin_size_m", "quay_height_m", "entrance_width_m", "piers", "channel_width_m",
       "channel_length_m", "boats_moored", "boats_image_only", "boats_lidar_only", "aerial_image"});
  HarbourSpec h;
  h.enabled = r.Bool(node, path, "enabled", true);
  h.centre_east_m = r.Double(node, path, "centre_east_m", h.centre_east_m);
  h.centre_north_m = r.Double(node, path, "centre_north_m", h.centre_north_m);
  h.rotation_deg = r.Double(node, path, "rotation_deg", h.rotation_deg);
  h.water_level_up_m = r.Double(node, path, "water_level_up_m", h.water_level_up_m);
  h.basin_size_m = r.Positive(node, path, "basin_size_m", h.basin_size_m);
  if (h.basin_size_m < 150.0 || h.basin_size_m > 1000.0) {
    r.Fail(node["basin_size_m"], Join(path, "basin_size_m"), "must be from 150 to 1000 m");
  }
  h.quay_height_m = r.Positive(node, path, "quay_height_m", h.quay_height_m);
  if (h.quay_height_m > 10.0) {
    r.Fail(node["quay_height_m"], Join(path, "quay_height_m"), "must be <= 10 m");
  }
  h.entrance_width_m = r.Positive(node, path, "entrance_width_m", h.entrance_width_m);
  if (h.entrance_width_m < 20.0 || h.entrance_width_m > 0.3 * h.basin_size_m) {
    r.Fail(node["entrance_width_m"], Join(path, "entrance_width_m"),
           "must be from 20 m to 0.3 basin_size_m");
  }
  h.piers = WholeNumber(r, node, path, "piers", h.piers, 0, 3);
  h.channel_width_m = r.Positive(node, path, "channel_width_m", h.channel_width_m);
  if (h.channel_width_m < 20.0 || h.channel_width_m > 0.2 * h.basin_size_m) {
    r.Fail(node["channel_width_m"], Join(path, "channel_width_m"),
           "must be from 20 m to 0.2 basin_size_m");
  }
  h.channel_length_m = r.Positive(node, path, "channel_length_m", h.channel_length_m);
  if (h.channel_length_m < 80.0) {
    r.Fail(node["channel_length_m"], Join(path, "channel_length_m"),
           "must be >= 80 m (it runs through the 60 m of land behind the north quay)");
  }
  h.boats_moored = WholeNumber(r, node, path, "boats_moored", h.boats_moored, 0, 200);
  h.boats_image_only = WholeNumber(r, node, path, "boats_image_only", h.boats_image_only, 0, 200);
  h.boats_lidar_only = WholeNumber(r, node, path, "boats_lidar_only", h.boats_lidar_only, 0, 200);
  if (const YAML::Node a = node["aerial_image"]) {
    h.aerial_image = ParseAerialImage(r, a, Join(path, "aerial_image"));
  }
  return h;
}

LidarModelSim ParseLidar(const Reader& r, const YAML::Node& node, const std::string& path) {
  r.CheckKeys(node, path,
              {"enabled", "write_rate_hz", "time_offset_s", "start_s", "end_s", "rotation_rate_hz",
               "elevations_deg", "beams", "min_elevation_deg", "max_elevation_deg",
               "azimuth_step_deg", "min_range_m", "max_range_m", "range_noise_sigma_m",
               "dropout_at_max_range", "dropout_range_exponent", "T_b_l", "hull"});
  LidarModelSim l;
  l.enabled = r.Bool(node, path, "enabled", true);
  l.rotation_rate_hz = r.Positive(node, path, "rotation_rate_hz", l.rotation_rate_hz);
  l.write_rate_hz = r.Positive(node, path, "write_rate_hz", l.write_rate_hz);
  if (l.write_rate_hz > l.rotation_rate_hz) {
    r.Fail(node["write_rate_hz"], Join(path, "write_rate_hz"),
           "must be <= rotation_rate_hz (a scan is one whole sweep)");
  }
  l.time_offset_s = r.NonNegative(node, path, "time_offset_s", l.time_offset_s);
  l.start_s = r.NonNegative(node, path, "start_s", l.start_s);
  l.end_s = r.Positive(node, path, "end_s", l.end_s);
  if (const YAML::Node e = node["elevations_deg"]) {
    const std::string ep = Join(path, "elevations_deg");
    if (!e.IsSequence() || e.size() == 0 || e.size() > 256) {
      r.Fail(e, ep, "expected a list of 1 to 256 elevations");
    }
    for (std::size_t i = 0; i < e.size(); ++i) {
      const double v = r.Double(e[i], Index(ep, i));
      if (std::abs(v) >= 90.0) r.Fail(e[i], Index(ep, i), "must be within +-90 deg");
      l.elevations_deg.push_back(v);
    }
    if (node["beams"] || node["min_elevation_deg"] || node["max_elevation_deg"]) {
      r.Fail(e, ep, "give either elevations_deg or beams with min/max_elevation_deg, not both");
    }
  }
  l.beams = WholeNumber(r, node, path, "beams", l.beams, 1, 256);
  l.min_elevation_deg = r.Double(node, path, "min_elevation_deg", l.min_elevation_deg);
  l.max_elevation_deg = r.Double(node, path, "max_elevation_deg", l.max_elevation_deg);
  if (std::abs(l.min_elevation_deg) >= 90.0 || std::abs(l.max_elevation_deg) >= 90.0 ||
      (l.beams > 1 && !(l.max_elevation_deg > l.min_elevation_deg))) {
    r.Fail(node["max_elevation_deg"] ? node["max_elevation_deg"] : node,
           Join(path, "max_elevation_deg"),
           "elevations must be within +-90 deg, the maximum above the minimum");
  }
  l.azimuth_step_deg = r.Positive(node, path, "azimuth_step_deg", l.azimuth_step_deg);
  if (l.azimuth_step_deg < 0.01 || l.azimuth_step_deg > 90.0) {
    r.Fail(node["azimuth_step_deg"], Join(path, "azimuth_step_deg"), "must be 0.01 to 90 deg");
  }
  l.min_range_m = r.NonNegative(node, path, "min_range_m", l.min_range_m);
  l.max_range_m = r.Positive(node, path, "max_range_m", l.max_range_m);
  if (!(l.max_range_m > l.min_range_m)) {
    r.Fail(node["max_range_m"], Join(path, "max_range_m"), "must be above min_range_m");
  }
  l.range_noise_sigma_m = r.NonNegative(node, path, "range_noise_sigma_m", l.range_noise_sigma_m);
  l.dropout_at_max_range =
      r.NonNegative(node, path, "dropout_at_max_range", l.dropout_at_max_range);
  if (l.dropout_at_max_range > 1.0) {
    r.Fail(node["dropout_at_max_range"], Join(path, "dropout_at_max_range"),
           "a probability: must be <= 1");
  }
  l.dropout_range_exponent =
      r.NonNegative(node, path, "dropout_range_exponent", l.dropout_range_exponent);
  if (const YAML::Node t = node["T_b_l"]) {
    const std::string tp = Join(path, "T_b_l");
    r.CheckKeys(t, tp, {"q_xyzw", "p_m"});
    const Eigen::Vector4d q = r.Vector<4>(t, tp, "q_xyzw", Eigen::Vector4d(0, 0, 0, 1));
    if (std::abs(q.norm() - 1.0) > 1e-6) {
      r.Fail(t["q_xyzw"], Join(tp, "q_xyzw"), "quaternion is not unit length");
    }
    l.T_b_l.q_b_s = Eigen::Quaterniond(q[3], q[0], q[1], q[2]).normalized();
    l.T_b_l.p_b_s = r.Vector<3>(t, tp, "p_m", l.T_b_l.p_b_s);
  }
  if (const YAML::Node h = node["hull"]) {
    const std::string hp = Join(path, "hull");
    r.CheckKeys(h, hp, {"centre_b_m", "size_m", "reflectivity"});
    l.hull_centre_b_m = r.Vector<3>(h, hp, "centre_b_m", l.hull_centre_b_m);
    l.hull_size_m = r.Vector<3>(h, hp, "size_m", l.hull_size_m);
    if (!(l.hull_size_m.minCoeff() >= 0.0)) {
      r.Fail(h["size_m"], Join(hp, "size_m"), "sizes must be >= 0 (all 0: no hull)");
    }
    l.hull_reflectivity = r.NonNegative(h, hp, "reflectivity", l.hull_reflectivity);
    if (l.hull_reflectivity > 1.0) {
      r.Fail(h["reflectivity"], Join(hp, "reflectivity"), "must be <= 1");
    }
  }
  return l;
}

Leg ParseLeg(const Reader& r, const YAML::Node& node, const std::string& path) {
  r.ExpectMap(node, path);
  const YAML::Node type_node = r.Required(node, path, "type");
  const std::string type = type_node.IsScalar() ? type_node.Scalar() : std::string();
  Leg leg;
  if (type == "straight") {
    r.CheckKeys(node, path, {"type", "duration_s"});
    leg.type = Leg::Type::kStraight;
    leg.duration_s = r.Positive(node, path, "duration_s");
  } else if (type == "turn") {
    r.CheckKeys(node, path, {"type", "angle_deg", "rate_deg_s", "ramp_s"});
    leg.type = Leg::Type::kTurn;
    leg.angle_deg = r.Double(node, path, "angle_deg");
    leg.rate_deg_s = r.Positive(node, path, "rate_deg_s");
    if (node["ramp_s"]) leg.ramp_s = r.Positive(node, path, "ramp_s");
  } else if (type == "speed_change") {
    r.CheckKeys(node, path, {"type", "to_m_s", "accel_m_s2"});
    leg.type = Leg::Type::kSpeedChange;
    leg.to_m_s = r.Double(node, path, "to_m_s");
    if (leg.to_m_s < 0.0) r.Fail(node["to_m_s"], Join(path, "to_m_s"), "must be >= 0");
    leg.accel_m_s2 = r.Positive(node, path, "accel_m_s2");
  } else {
    r.Fail(type_node, Join(path, "type"),
           "unknown leg type '" + type + "' (expected straight, turn, speed_change)");
  }
  return leg;
}

TrajectorySpec ParseTrajectory(const Reader& r, const YAML::Node& node, const std::string& path) {
  r.CheckKeys(node, path, {"start", "current_enu_m_s", "turn_ramp_s", "heel_deg_per_m_s2", "legs"});
  TrajectorySpec t;
  if (const YAML::Node s = node["start"]) {
    const std::string sp = Join(path, "start");
    r.CheckKeys(s, sp, {"east_m", "north_m", "up_m", "heading_deg", "speed_m_s"});
    t.start_enu_m = Eigen::Vector3d(r.Double(s, sp, "east_m", 0.0), r.Double(s, sp, "north_m", 0.0),
                                    r.Double(s, sp, "up_m", 0.0));
    t.start_heading_deg = r.Double(s, sp, "heading_deg", 0.0);
    t.start_speed_m_s = r.NonNegative(s, sp, "speed_m_s", t.start_speed_m_s);
  }
  t.current_enu_m_s = r.Vector<2>(node, path, "current_enu_m_s", t.current_enu_m_s);
  t.turn_ramp_s = r.Positive(node, path, "turn_ramp_s", t.turn_ramp_s);
  t.heel_deg_per_m_s2 = r.Double(node, path, "heel_deg_per_m_s2", t.heel_deg_per_m_s2);
  if (const YAML::Node legs = node["legs"]) {
    const std::string lp = Join(path, "legs");
    r.ExpectSequence(legs, lp);
    for (std::size_t i = 0; i < legs.size(); ++i) {
      t.legs.push_back(ParseLeg(r, legs[i], Index(lp, i)));
    }
  }
  return t;
}

std::vector<WaveComponent> ParseWaves(const Reader& r,
                                      const YAML::Node& node,
                                      const std::string& path,
                                      const char* amplitude_key) {
  std::vector<WaveComponent> out;
  if (!node) return out;
  r.ExpectSequence(node, path);
  for (std::size_t i = 0; i < node.size(); ++i) {
    const std::string ip = Index(path, i);
    r.CheckKeys(node[i], ip, {amplitude_key, "period_s"});
    WaveComponent c;
    c.amplitude = r.Double(node[i], ip, amplitude_key);
    if (c.amplitude < 0.0) r.Fail(node[i][amplitude_key], Join(ip, amplitude_key), "must be >= 0");
    c.period_s = r.Positive(node[i], ip, "period_s");
    out.push_back(c);
  }
  return out;
}

ScenarioConfig ParseRoot(const Reader& r, const YAML::Node& root) {
  if (!root.IsMap()) r.Fail(root, "", "a scenario must be a YAML mapping");
  r.CheckKeys(
      root, "",
      {"name", "duration_s", "seed", "origin", "earth", "imu", "gnss", "pose_fixes", "camera",
       "dem", "harbour", "lidar", "water_surface", "groundtruth_rate_hz", "trajectory", "waves"});
  ScenarioConfig c;
  c.name = r.String(root, "", "name", "");
  c.duration_s = r.Positive(root, "", "duration_s");
  c.seed = r.UInt64(root, "", "seed", c.seed);
  c.groundtruth_rate_hz = r.Positive(root, "", "groundtruth_rate_hz", c.groundtruth_rate_hz);
  {
    const YAML::Node o = r.Required(root, "", "origin");
    r.CheckKeys(o, "origin", {"lat_deg", "lon_deg", "height_m"});
    c.origin.lat_deg = r.Double(o, "origin", "lat_deg");
    c.origin.lon_deg = r.Double(o, "origin", "lon_deg");
    c.origin.height_m = r.Double(o, "origin", "height_m");
    if (std::abs(c.origin.lat_deg) > 89.0) {
      r.Fail(o["lat_deg"], "origin.lat_deg", "must be within +-89 deg");
    }
    if (std::abs(c.origin.lon_deg) > 180.0) {
      r.Fail(o["lon_deg"], "origin.lon_deg", "must be within +-180 deg");
    }
  }
  if (const YAML::Node e = root["earth"]) {
    r.CheckKeys(e, "earth", {"model", "gravity_m_s2"});
    const std::string model = r.String(e, "earth", "model", "wgs84");
    if (!ParseEarthKind(model, &c.earth.kind)) {
      r.Fail(e["model"], "earth.model", "expected wgs84 or flat");
    }
    if (e["gravity_m_s2"] && c.earth.kind != EarthKind::kFlat) {
      r.Fail(e["gravity_m_s2"], "earth.gravity_m_s2", "only for model flat");
    }
    c.earth.gravity_m_s2 = r.Positive(e, "earth", "gravity_m_s2", c.earth.gravity_m_s2);
  }
  c.imu = root["imu"] ? ParseImu(r, root["imu"], "imu") : ImuModel();
  c.gnss = root["gnss"] ? ParseGnss(r, root["gnss"], "gnss") : GnssModel();
  if (root["pose_fixes"]) c.pose_fixes = ParsePoseFixes(r, root["pose_fixes"], "pose_fixes");
  if (root["camera"]) c.camera = ParseCamera(r, root["camera"], "camera");
  if (const YAML::Node d = root["dem"]) {
    r.CheckKeys(d, "dem", {"file", "vertical_datum", "error", "relief"});
    DemSim dem;
    dem.path = r.String(d, "dem", "file", "");
    if (dem.path.empty()) r.Fail(d, "dem.file", "missing");
    dem.vertical_datum = r.String(d, "dem", "vertical_datum", dem.vertical_datum);
    if (dem.vertical_datum != "egm96" && dem.vertical_datum != "ellipsoidal") {
      r.Fail(d["vertical_datum"], "dem.vertical_datum", "expected egm96 or ellipsoidal");
    }
    if (const YAML::Node e = d["error"]) {
      r.CheckKeys(e, "dem.error", {"sigma_m", "length_m"});
      dem.error.sigma_m = r.NonNegative(e, "dem.error", "sigma_m", dem.error.sigma_m);
      dem.error.length_m = r.Positive(e, "dem.error", "length_m", dem.error.length_m);
    }
    dem.relief.gain = r.NonNegative(d, "dem", "relief", dem.relief.gain);
    if (dem.relief.gain > 10.0) r.Fail(d["relief"], "dem.relief", "must be <= 10");
    c.dem = dem;
  }
  if (c.camera.enabled && !c.dem) r.Fail(root["camera"], "camera", "a camera needs a dem");
  if (root["harbour"]) c.harbour = ParseHarbour(r, root["harbour"], "harbour");
  if (root["lidar"]) c.lidar = ParseLidar(r, root["lidar"], "lidar");
  if (c.lidar.enabled && !c.harbour.enabled) {
    r.Fail(root["lidar"], "lidar", "a lidar needs a harbour (the world it scans): add harbour:");
  }
  if (const YAML::Node w = root["water_surface"]) {
    r.CheckKeys(w, "water_surface", {"enabled", "sigma_m", "rate_hz"});
    c.water_surface_enabled = r.Bool(w, "water_surface", "enabled", true);
    c.water_surface_sigma_m = r.Positive(w, "water_surface", "sigma_m", c.water_surface_sigma_m);
    c.water_surface_rate_hz = r.Positive(w, "water_surface", "rate_hz", c.water_surface_rate_hz);
  }
  // The simulator holds every sample of a stream in memory at once.
  for (const auto& [key, rate] : {std::pair<const char*, double>{"imu.rate_hz", c.imu.rate_hz},
                                  {"groundtruth_rate_hz", c.groundtruth_rate_hz},
                                  {"gnss.rate_hz", c.gnss.rate_hz}}) {
    if (c.duration_s * rate > kMaxSamples) {
      r.Fail(root["duration_s"], "duration_s",
             "with " + std::string(key) + " " + FormatNumber(rate) + " that is " +
                 FormatNumber(c.duration_s * rate) + " samples, more than the simulator holds (" +
                 FormatNumber(kMaxSamples) + ")");
    }
  }
  c.trajectory =
      root["trajectory"] ? ParseTrajectory(r, root["trajectory"], "trajectory") : TrajectorySpec();
  if (const YAML::Node w = root["waves"]) {
    r.CheckKeys(w, "waves", {"roll", "pitch", "heave"});
    c.waves.roll_deg = ParseWaves(r, w["roll"], "waves.roll", "amplitude_deg");
    c.waves.pitch_deg = ParseWaves(r, w["pitch"], "waves.pitch", "amplitude_deg");
    c.waves.heave_m = ParseWaves(r, w["heave"], "waves.heave", "amplitude_m");
  }
  return c;
}

bool IsPathLike(const std::string& s) {
  auto ends_with = [&s](const std::string& suffix) {
    return s.size() >= suffix.size() &&
           s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
  };
  return s.find('/') != std::string::npos || ends_with(".yaml") || ends_with(".yml");
}

std::vector<std::string> SearchDirs() {
  std::vector<std::string> dirs;
  if (const char* env = std::getenv("SKERRY_SCENARIO_DIR"); env != nullptr && *env != '\0') {
    dirs.emplace_back(env);
  }
  for (const char* d : {SKERRY_SCENARIO_INSTALL_DIR, SKERRY_SCENARIO_SOURCE_DIR}) {
    if (*d != '\0') dirs.emplace_back(d);
  }
  return dirs;
}

}  // namespace

ImuErrorModel ImuGradePreset(ImuGrade grade) {
  ImuErrorModel m;
  ImuNoise& n = m.noise;
  switch (grade) {
    case ImuGrade::kConsumer:
      // MEMS of the ADIS16448 / BMI088 class; densities as in the EuRoC imu0_sensor.yaml.
      n.gyro_noise_density_rad_s_sqrt_hz = 1.6968e-4;  // 0.58 deg/sqrt(h)
      n.accel_noise_density_m_s2_sqrt_hz = 2.0e-3;     // ~200 ug/sqrt(Hz)
      n.gyro_bias_random_walk_rad_s2_sqrt_hz = 1.9393e-5;
      n.accel_bias_random_walk_m_s3_sqrt_hz = 3.0e-3;
      m.gyro_bias_initial_sigma_rad_s = 1.7e-3;  // 0.1 deg/s after a start-up calibration
      m.accel_bias_initial_sigma_m_s2 = 5.0 * kMilliG;
      // ADIS16448 datasheet: in-run bias stability 14.5 deg/h and 0.25 mg; scale factors and
      // misalignment as left by a factory calibration (0.1 %, 0.5 mrad).
      m.gyro_scale_factor_ppm = 1000.0;
      m.accel_scale_factor_ppm = 1000.0;
      m.gyro_misalignment_mrad = 0.5;
      m.accel_misalignment_mrad = 0.5;
      m.gyro_bias_instability_rad_s = 14.5 * kDegPerHourToRadPerS;
      m.accel_bias_instability_m_s2 = 0.25 * kMilliG;
      m.bias_instability_tau_s = 100.0;
      break;
    case ImuGrade::kTactical:
      // Fibre-optic tactical IMU (KVH 1750/1775 class, the kind fitted to survey and patrol
      // vessels): ARW 0.012 deg/sqrt(h), gyro bias instability 0.05 deg/h,
      // VRW 0.05 m/s/sqrt(h), accelerometer bias instability 0.05 mg.
      n.gyro_noise_density_rad_s_sqrt_hz = 0.012 * kDegPerSqrtHourToRadPerSqrtS;
      n.accel_noise_density_m_s2_sqrt_hz = 0.05 * kMetrePerSecondPerSqrtHour;
      // Random walks that wander by the bias instability in about 10 minutes:
      // 0.05 deg/h / sqrt(600 s) and 0.05 mg / sqrt(600 s).
      n.gyro_bias_random_walk_rad_s2_sqrt_hz = 0.05 * kDegPerHourToRadPerS / std::sqrt(600.0);
      n.accel_bias_random_walk_m_s3_sqrt_hz = 0.05 * kMilliG / std::sqrt(600.0);
      m.gyro_bias_initial_sigma_rad_s = 0.25 * kDegPerHourToRadPerS;
      m.accel_bias_initial_sigma_m_s2 = 0.2 * kMilliG;
      // Closed-loop FOG scale factor 50 ppm, servo accelerometers 300 ppm, 0.1 mrad residual
      // misalignment; the instabilities above as Gauss-Markov with a 5-minute correlation time.
      m.gyro_scale_factor_ppm = 50.0;
      m.accel_scale_factor_ppm = 300.0;
      m.gyro_misalignment_mrad = 0.1;
      m.accel_misalignment_mrad = 0.1;
      m.gyro_bias_instability_rad_s = 0.05 * kDegPerHourToRadPerS;
      m.accel_bias_instability_m_s2 = 0.05 * kMilliG;
      m.bias_instability_tau_s = 300.0;
      break;
    case ImuGrade::kNavigation:
      // Ring-laser INS class: ARW 0.002 deg/sqrt(h), bias 0.003 deg/h, 25 ug.
      n.gyro_noise_density_rad_s_sqrt_hz = 0.002 * kDegPerSqrtHourToRadPerSqrtS;
      n.accel_noise_density_m_s2_sqrt_hz = 0.006 * kMetrePerSecondPerSqrtHour;
      // Wander by the bias instability in about an hour.
      n.gyro_bias_random_walk_rad_s2_sqrt_hz = 0.003 * kDegPerHourToRadPerS / std::sqrt(3600.0);
      n.accel_bias_random_walk_m_s3_sqrt_hz = 0.01 * kMilliG / std::sqrt(3600.0);
      m.gyro_bias_initial_sigma_rad_s = 0.005 * kDegPerHourToRadPerS;
      m.accel_bias_initial_sigma_m_s2 = 0.025 * kMilliG;
      // Ring-laser gyros 5 ppm, accelerometers 50 ppm, 0.02 mrad; hour-long correlation.
      m.gyro_scale_factor_ppm = 5.0;
      m.accel_scale_factor_ppm = 50.0;
      m.gyro_misalignment_mrad = 0.02;
      m.accel_misalignment_mrad = 0.02;
      m.gyro_bias_instability_rad_s = 0.003 * kDegPerHourToRadPerS;
      m.accel_bias_instability_m_s2 = 0.01 * kMilliG;
      m.bias_instability_tau_s = 3600.0;
      break;
  }
  return m;
}

ScenarioConfig MatchedToEstimator(const ScenarioConfig& config, const DriftModel& drift) {
  ScenarioConfig c = config;
  ImuErrorModel& e = c.imu.errors;
  e.gyro_scale_factor_ppm = e.accel_scale_factor_ppm = 0.0;
  e.gyro_misalignment_mrad = e.accel_misalignment_mrad = 0.0;
  e.gyro_bias_instability_rad_s = e.accel_bias_instability_m_s2 = 0.0;
  e.bias_instability_tau_s = 0.0;
  GnssModel& g = c.gnss;
  g.slow_drift_sigma_horizontal_m = g.slow_drift_sigma_vertical_m = 0.0;
  g.multipath_rate_per_hour = 0.0;
  g.latency_s = g.stamp_jitter_s = 0.0;
  g.reported_sigma_horizontal_m = std::max(g.noise_sigma_horizontal_m, 1e-3);
  g.reported_sigma_vertical_m = std::max(g.noise_sigma_vertical_m, 1e-3);
  g.drift_sigma_horizontal_m = drift.sigma_horizontal_m;
  g.drift_sigma_vertical_m = drift.sigma_vertical_m;
  g.drift_tau_s = drift.tau_s;
  if (!c.name.empty()) c.name += "-matched";
  return c;
}

ScenarioConfig ParseScenario(const std::string& yaml_text, const std::string& file) {
  const Reader reader(file);
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::ParserException& e) {
    throw InputError(file, e.mark.is_null() ? 0 : e.mark.line + 1, "", "YAML syntax: " + e.msg);
  }
  try {
    ScenarioConfig c = ParseRoot(reader, root);
    c.source_file = file;
    // A DEM named relative to the scenario file.
    if (c.dem && !std::filesystem::path(c.dem->path).is_absolute() && !file.empty()) {
      c.dem->path = std::filesystem::weakly_canonical(
                        std::filesystem::absolute(file).parent_path() / c.dem->path)
                        .string();
    }
    return c;
  } catch (const InputError&) {
    throw;
  } catch (const YAML::Exception& e) {  // anything yaml-cpp raises that we did not foresee
    throw InputError(file, e.mark.is_null() ? 0 : e.mark.line + 1, "", e.msg);
  }
}

ScenarioConfig LoadScenario(const std::string& name_or_path) {
  namespace fs = std::filesystem;
  std::string path;
  if (IsPathLike(name_or_path)) {
    path = name_or_path;
  } else {
    std::string searched;
    for (const std::string& dir : SearchDirs()) {
      const fs::path candidate = fs::path(dir) / (name_or_path + ".yaml");
      std::error_code ec;
      if (fs::is_regular_file(candidate, ec)) {
        path = candidate.string();
        break;
      }
      searched += (searched.empty() ? "" : ", ") + dir;
    }
    if (path.empty()) {
      throw InputError(name_or_path, 0, "scenario",
                       "no built-in scenario of this name (searched: " + searched + ")");
    }
  }
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, "", "cannot open scenario file");
  std::stringstream text;
  text << in.rdbuf();
  return ParseScenario(text.str(), path);
}

std::vector<std::string> ListBuiltinScenarios() {
  namespace fs = std::filesystem;
  std::vector<std::string> names;
  for (const std::string& dir : SearchDirs()) {
    std::error_code ec;
    for (fs::directory_iterator it(dir, ec), end; !ec && it != end; it.increment(ec)) {
      if (it->path().extension() == ".yaml") names.push_back(it->path().stem().string());
    }
  }
  std::sort(names.begin(), names.end());
  names.erase(std::unique(names.begin(), names.end()), names.end());
  return names;
}

}  // namespace skerry::sim
