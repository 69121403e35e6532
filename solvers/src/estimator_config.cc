#include "skerry/solvers/estimator_config.h"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "skerry/core/format_number.h"
#include "skerry/core/input_error.h"
#include "skerry/solvers/keyframe_policy.h"
#include "skerry/solvers/nav_graph.h"

#ifndef SKERRY_PRESET_SOURCE_DIR
#define SKERRY_PRESET_SOURCE_DIR ""
#endif
#ifndef SKERRY_PRESET_INSTALL_DIR
#define SKERRY_PRESET_INSTALL_DIR ""
#endif

namespace skerry {
namespace {

// Reads a YAML mapping, remembering which keys were used so unknown keys can be reported.
class MapReader {
 public:
  MapReader(const YAML::Node& node, std::string file, std::string path)
      : node_(node), file_(std::move(file)), path_(std::move(path)) {
    if (!node_.IsMap()) {
      throw InputError(file_, node_.Mark().line + 1, path_.empty() ? "(top level)" : path_,
                       "expected a mapping");
    }
  }

  template <typename T>
  void Get(const std::string& key, T* value) {
    used_.insert(key);
    const YAML::Node child = node_[key];
    if (!child) return;
    try {
      *value = child.as<T>();
    } catch (const YAML::Exception&) {
      throw InputError(file_, child.Mark().line + 1, Path(key), "wrong type");
    }
  }

  void GetPositive(const std::string& key, double* value, bool allow_zero = false) {
    Get(key, value);
    if (!(allow_zero ? *value >= 0.0 : *value > 0.0) || !std::isfinite(*value)) {
      throw InputError(file_, Line(key), Path(key), allow_zero ? "must be >= 0" : "must be > 0");
    }
  }

  // A duration in seconds: as GetPositive, and at most kMaxDurationS. Durations become int64
  // nanoseconds (SecondsToNs), which hold only 292 years: 1e300 s came out as a negative time,
  // so that init.attitude_window_s averaged no sample and the run aborted on a NaN attitude.
  void GetDuration(const std::string& key, double* value, bool allow_zero = false) {
    GetPositive(key, value, allow_zero);
    if (*value > kMaxDurationS) {
      throw InputError(file_, Line(key), Path(key),
                       "must be at most " + FormatNumber(kMaxDurationS) + " s");
    }
  }

  // The keyframe rate, whose period must lie between KeyframePolicy::kMinPeriodS and
  // kMaxDurationS: 1e-12 Hz made a period past the int64 nanoseconds, and the window a keyframe
  // at every IMU sample that never solved (a 5 km RMSE reported as a success).
  void GetKeyframeRate(const std::string& key, double* value) {
    GetPositive(key, value);
    if (*value < 1.0 / kMaxDurationS || *value > 1.0 / KeyframePolicy::kMinPeriodS) {
      throw InputError(file_, Line(key), Path(key),
                       "must be between " + FormatNumber(1.0 / kMaxDurationS) + " and " +
                           FormatNumber(1.0 / KeyframePolicy::kMinPeriodS) + " Hz");
    }
  }

  void GetAtLeast(const std::string& key, int* value, int min) {
    Get(key, value);
    if (*value < min) {
      throw InputError(file_, Line(key), Path(key), "must be >= " + std::to_string(min));
    }
  }

  void GetLoss(const std::string& type_key, const std::string& scale_key, RobustLoss* loss) {
    std::string name = ToString(loss->type);
    Get(type_key, &name);
    try {
      loss->type = ParseLossType(name);
    } catch (const std::invalid_argument& e) {
      throw InputError(file_, Line(type_key), Path(type_key), e.what());
    }
    GetPositive(scale_key, &loss->scale);
  }

  MapReader Child(const std::string& key) {
    used_.insert(key);
    return MapReader(node_[key], file_, Path(key));
  }
  bool Has(const std::string& key) const { return static_cast<bool>(node_[key]); }
  const YAML::Node& node() const { return node_; }
  /// True if `key` holds exactly the word `word`.
  bool IsString(const std::string& key, const std::string& word) const {
    const YAML::Node child = node_[key];
    return child && child.IsScalar() && child.Scalar() == word;
  }

  int Line(const std::string& key) const {
    const YAML::Node child = node_[key];
    return (child ? child.Mark().line : node_.Mark().line) + 1;
  }
  /// A key of this mapping as a name (not a YAML "? " complex key).
  std::string KeyOf(const YAML::Node& key) const {
    if (!key.IsScalar()) {
      throw InputError(file_, key.Mark().line + 1, path_.empty() ? "(document)" : path_,
                       "a key must be a plain name");
    }
    return key.Scalar();
  }
  std::string Path(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

  void CheckNoUnknownKeys() const {
    for (const auto& kv : node_) {
      const std::string key = KeyOf(kv.first);
      if (!used_.count(key)) {
        throw InputError(file_, kv.first.Mark().line + 1, Path(key), "unknown key");
      }
    }
  }

 private:
  YAML::Node node_;
  std::string file_;
  std::string path_;
  std::set<std::string> used_;
};

void ReadCeres(MapReader r, CeresConfig* c, const std::string& file) {
  r.Get("trust_region", &c->trust_region);
  r.Get("dogleg_type", &c->dogleg_type);
  r.Get("linear_solver", &c->linear_solver);
  r.GetAtLeast("max_iterations", &c->max_iterations, 1);
  r.GetPositive("initial_trust_region_radius", &c->initial_trust_region_radius);
  r.GetDuration("max_time_s", &c->max_time_s, true);
  r.GetAtLeast("num_threads", &c->num_threads, 1);
  r.GetPositive("function_tolerance", &c->function_tolerance);
  r.GetPositive("gradient_tolerance", &c->gradient_tolerance);
  r.GetPositive("parameter_tolerance", &c->parameter_tolerance);
  r.Get("chain_gains", &c->chain_gains);
  r.CheckNoUnknownKeys();
  // Validate each name on its own so the error points at its line and key.
  const std::pair<const char*, CeresConfig> probes[] = {{"trust_region", CeresConfig{}},
                                                        {"dogleg_type", CeresConfig{}},
                                                        {"linear_solver", CeresConfig{}},
                                                        {"chain_gains", CeresConfig{}}};
  for (auto [key, probe] : probes) {
    const std::string k = key;
    if (k == "trust_region") probe.trust_region = c->trust_region;
    if (k == "dogleg_type") probe.dogleg_type = c->dogleg_type;
    if (k == "linear_solver") probe.linear_solver = c->linear_solver;
    if (k == "chain_gains") probe.chain_gains = c->chain_gains;
    try {
      MakeSolverOptions(probe);
    } catch (const std::invalid_argument& e) {
      throw InputError(file, r.Line(k), r.Path(k), e.what());
    }
  }
}

// The configuration in `root`, every key checked; `path` names the source in the errors.
EstimatorConfig ParseEstimatorConfig(const YAML::Node& root,
                                     const std::string& path,
                                     std::string name) {
  EstimatorConfig c;
  c.name = std::move(name);
  MapReader r(root, path, "");
  r.Get("name", &c.name);
  r.GetKeyframeRate("keyframe_rate_hz", &c.keyframe_rate_hz);
  r.GetAtLeast("window_keyframes", &c.window_keyframes, 2);
  r.GetDuration("window_s", &c.window_s, true);
  r.Get("first_estimate_jacobians", &c.first_estimate_jacobians);
  r.Get("estimate_gyro_calibration", &c.estimate_gyro_calibration);
  r.Get("compute_covariance", &c.compute_covariance);
  if (r.Has("gnss")) {
    MapReader g = r.Child("gnss");
    g.GetLoss("loss", "loss_scale", &c.gnss_loss);
    g.GetLoss("heading_loss", "heading_loss_scale", &c.heading_loss);
    g.GetPositive("gate_probability", &c.gnss_gate_probability, true);
    if (c.gnss_gate_probability >= 1.0) {
      throw InputError(path, g.Line("gate_probability"), g.Path("gate_probability"),
                       "must be in [0, 1) (0 switches the gate off)");
    }
    g.GetDuration("gate_max_reject_s", &c.gnss_gate_max_reject_s, true);
    g.GetDuration("gate_streak_max_gap_s", &c.gnss_gate_streak_max_gap_s);
    g.GetPositive("sigma_scale", &c.gnss_sigma_scale);
    g.Get("use_heading", &c.use_gnss_heading);
    g.Get("jump_test", &c.gnss_jump_test);
    g.Get("jump_as_drift_step", &c.gnss_jump_as_drift_step);
    g.GetDuration("jump_step_after_s", &c.gnss_jump_step_after_s, true);
    g.GetPositive("drift_sigma_horizontal_m", &c.gnss_drift.sigma_horizontal_m, true);
    g.GetPositive("drift_sigma_vertical_m", &c.gnss_drift.sigma_vertical_m, true);
    g.GetDuration("drift_tau_s", &c.gnss_drift.tau_s);
    if (c.gnss_jump_as_drift_step && (!c.gnss_jump_test || !c.gnss_drift.enabled())) {
      throw InputError(path, g.Line("jump_as_drift_step"), g.Path("jump_as_drift_step"),
                       "needs the jump test (jump_test: true) and the drift model "
                       "(drift_sigma_horizontal_m or drift_sigma_vertical_m above 0)");
    }
    g.CheckNoUnknownKeys();
  }
  if (r.Has("sensors")) {
    MapReader all = r.Child("sensors");
    for (const auto& kv : YAML::Node(all.node())) {
      const std::string name = all.KeyOf(kv.first);
      MapReader o = all.Child(name);
      SensorOptions options;
      o.GetLoss("loss", "loss_scale", &options.loss);
      o.GetPositive("gate_probability", &options.gate_probability, true);
      if (options.gate_probability >= 1.0) {
        throw InputError(path, o.Line("gate_probability"), o.Path("gate_probability"),
                         "must be in [0, 1) (0 switches the gate off)");
      }
      o.Get("calibrate", &options.calibrate);
      o.GetPositive("extrinsic_prior_sigma_deg", &options.extrinsic_prior_sigma_deg);
      o.GetPositive("extrinsic_prior_sigma_m", &options.extrinsic_prior_sigma_m);
      o.CheckNoUnknownKeys();
      c.sensors[name] = options;
    }
  }
  if (r.Has("skyline")) {
    MapReader k = r.Child("skyline");
    k.GetAtLeast("column_stride_px", &c.skyline.column_stride_px, 1);
    k.GetPositive("sigma_px", &c.skyline.sigma_px);
    k.GetPositive("correlation_px", &c.skyline.correlation_px, true);
    k.GetPositive("huber_sigmas", &c.skyline.huber_sigmas, true);
    k.GetDuration("frame_correlation_s", &c.skyline.frame_correlation_s, true);
    k.GetPositive("frame_correlation_m", &c.skyline.frame_correlation_m, true);
    k.GetPositive("dem_sigma_m", &c.skyline.dem_sigma_m, true);
    k.GetPositive("min_confidence", &c.skyline.min_confidence, true);
    k.GetAtLeast("min_samples", &c.skyline.min_samples, 1);
    k.Get("source", &c.skyline.source);
    if (c.skyline.source != "auto" && c.skyline.source != "mask" && c.skyline.source != "image") {
      throw InputError(path, k.Line("source"), k.Path("source"), "expected auto, mask or image");
    }
    // Negative over cold water (rays bent away from the ground); at 1 and above a ray bends as
    // fast as the Earth and the horizon has no distance.
    k.Get("refraction_k", &c.skyline.refraction_k);
    if (!(c.skyline.refraction_k > -1.0 && c.skyline.refraction_k < 1.0)) {
      throw InputError(path, k.Line("refraction_k"), k.Path("refraction_k"), "must be in (-1, 1)");
    }
    k.GetPositive("refraction_k_sigma", &c.skyline.refraction_k_sigma, true);
    k.Get("crest_offset_m", &c.skyline.crest_offset_m);
    if (!(std::abs(c.skyline.crest_offset_m) <= 1000.0)) {
      throw InputError(path, k.Line("crest_offset_m"), k.Path("crest_offset_m"),
                       "must be finite and within +-1000 m");
    }
    k.GetPositive("crest_offset_sigma_m", &c.skyline.crest_offset_sigma_m, true);
    k.GetPositive("max_range_m", &c.skyline.max_range_m);
    k.GetPositive("dem_spacing_m", &c.skyline.dem_spacing_m, true);
    k.GetAtLeast("dem_oversampling", &c.skyline.dem_oversampling, 1);
    k.GetPositive("dem_sharpening", &c.skyline.dem_sharpening, true);
    k.GetPositive("dem_footprint_cells", &c.skyline.dem_footprint_cells);
    if (c.skyline.dem_footprint_cells > 10.0) {
      throw InputError(path, k.Line("dem_footprint_cells"), k.Path("dem_footprint_cells"),
                       "must be <= 10 (a footprint of cells, not metres)");
    }
    k.GetPositive("dem_sharpening_sigma", &c.skyline.dem_sharpening_sigma, true);
    // The camera's sensor parameter is one number: one of these estimated at most.
    const std::vector<std::pair<const char*, double>> estimated = {
        {"refraction_k_sigma", c.skyline.refraction_k_sigma},
        {"crest_offset_sigma_m", c.skyline.crest_offset_sigma_m},
        {"dem_sharpening_sigma", c.skyline.dem_sharpening_sigma}};
    const char* first = nullptr;
    for (const auto& [key, sigma] : estimated) {
      if (!(sigma > 0)) continue;
      if (first != nullptr) {
        throw InputError(path, k.Line(key), k.Path(key),
                         std::string("a camera estimates one parameter: ") + first + " and " + key +
                             " are both > 0");
      }
      first = key;
    }
    k.GetAtLeast("reacquire_after_rejections", &c.skyline.reacquire_after_rejections, 0);
    k.GetPositive("relocate_min_radius_m", &c.skyline.relocate_min_radius_m);
    k.GetPositive("start_radius_m", &c.skyline.start_radius_m);
    k.GetPositive("relocate_above_heading_sigma_deg", &c.skyline.relocate_above_heading_sigma_deg,
                  true);
    k.GetAtLeast("threads", &c.skyline.threads, 1);
    k.CheckNoUnknownKeys();
  }
  if (r.Has("lidar_aerial")) {
    MapReader k = r.Child("lidar_aerial");
    LidarAerialConfig& l = c.lidar_aerial;
    k.GetPositive("resolution_m", &l.resolution_m);
    k.GetPositive("max_distance_m", &l.max_distance_m);
    k.GetPositive("map_blur_m", &l.map_blur_m, true);
    k.GetPositive("canny_high_quantile", &l.canny_high_quantile);
    k.GetPositive("canny_low_quantile", &l.canny_low_quantile);
    if (!(l.canny_low_quantile < l.canny_high_quantile && l.canny_high_quantile < 1.0)) {
      throw InputError(path, k.Line("canny_high_quantile"), k.Path("canny_high_quantile"),
                       "expected canny_low_quantile < canny_high_quantile < 1");
    }
    k.GetPositive("sigma_m", &l.sigma_m);
    for (const char* key : {"loss", "batch_loss"}) {
      std::string* loss = std::string(key) == "loss" ? &l.loss : &l.batch_loss;
      k.Get(key, loss);
      if (*loss != "geman_mcclure" && *loss != "huber") {
        throw InputError(path, k.Line(key), k.Path(key), "expected huber or geman_mcclure");
      }
    }
    k.GetPositive("loss_sigmas", &l.loss_sigmas, true);
    k.GetPositive("window_trim_sigmas", &l.window_trim_sigmas, true);
    k.GetPositive("information_scale_m", &l.information_scale_m, true);
    k.GetPositive("effective_points", &l.effective_points);
    k.GetDuration("scan_correlation_s", &l.scan_correlation_s, true);
    k.Get("min_height_m", &l.min_height_m);
    if (!std::isfinite(l.min_height_m)) {
      throw InputError(path, k.Line("min_height_m"), k.Path("min_height_m"), "must be finite");
    }
    k.GetPositive("max_range_m", &l.max_range_m);
    for (const char* key : {"hull_min_b_m", "hull_max_b_m"}) {
      std::vector<double>* v =
          std::string(key) == "hull_min_b_m" ? &l.hull_min_b_m : &l.hull_max_b_m;
      k.Get(key, v);
      if (v->size() != 3 ||
          !std::all_of(v->begin(), v->end(), [](double x) { return std::isfinite(x); })) {
        throw InputError(path, k.Line(key), k.Path(key), "expected three finite numbers (x, y, z)");
      }
    }
    for (int i = 0; i < 3; ++i) {
      if (l.hull_min_b_m[i] > l.hull_max_b_m[i]) {
        throw InputError(path, k.Line("hull_max_b_m"), k.Path("hull_max_b_m"),
                         "must not be below hull_min_b_m");
      }
    }
    k.GetPositive("cell_m", &l.cell_m);
    k.GetPositive("front_sector_deg", &l.front_sector_deg, true);
    k.GetPositive("wall_gap_per_m", &l.wall_gap_per_m, true);
    k.GetPositive("max_edge_height_m", &l.max_edge_height_m, true);
    k.GetAtLeast("max_points", &l.max_points, 1);
    k.GetAtLeast("min_points", &l.min_points, 1);
    k.GetPositive("map_margin_m", &l.map_margin_m, true);
    k.GetPositive("map_tile_above_mcells", &l.map_tile_above_mcells, true);
    k.GetPositive("map_tile_m", &l.map_tile_m);
    k.Get("model_relief", &l.model_relief);
    k.GetPositive("start_radius_m", &l.start_radius_m);
    k.GetPositive("relocate_above_position_sigma_m", &l.relocate_above_position_sigma_m, true);
    k.GetPositive("relocate_above_heading_sigma_deg", &l.relocate_above_heading_sigma_deg, true);
    k.GetAtLeast("reacquire_after_rejections", &l.reacquire_after_rejections, 0);
    k.CheckNoUnknownKeys();
  }
  if (r.Has("solver")) ReadCeres(r.Child("solver"), &c.ceres, path);
  if (r.Has("batch_solver")) ReadCeres(r.Child("batch_solver"), &c.batch_ceres, path);
  if (r.Has("init")) {
    MapReader i = r.Child("init");
    std::string static_auto_text;
    i.Get("mode", &c.init.mode);
    if (c.init.mode != "auto" && c.init.mode != "cog" && c.init.mode != "heading" &&
        c.init.mode != "given" && c.init.mode != "align" && c.init.mode != "skyline" &&
        c.init.mode != "lidar") {
      throw InputError(path, i.Line("mode"), i.Path("mode"),
                       "expected auto, cog, heading, given, align, skyline or lidar");
    }
    i.GetPositive("min_cog_distance_m", &c.init.min_cog_distance_m);
    i.GetDuration("max_cog_time_s", &c.init.max_cog_time_s);
    i.GetDuration("attitude_window_s", &c.init.attitude_window_s);
    i.GetPositive("roll_pitch_sigma_deg", &c.init.roll_pitch_sigma_deg);
    i.GetPositive("yaw_sigma_deg", &c.init.yaw_sigma_deg);
    i.GetPositive("velocity_sigma_m_s", &c.init.velocity_sigma_m_s);
    i.GetPositive("position_sigma_scale", &c.init.position_sigma_scale);
    if (i.IsString("static_s", "auto")) {
      i.Get("static_s", &static_auto_text);
      c.init.static_s = InitConfig::kStaticAuto;
    } else if (i.Has("static_s")) {
      i.GetDuration("static_s", &c.init.static_s, true);
    }
    i.GetAtLeast("align_hypotheses", &c.init.align_hypotheses, 1);
    i.GetDuration("align_min_s", &c.init.align_min_s, true);
    i.GetDuration("align_max_s", &c.init.align_max_s);
    if (c.init.align_max_s < c.init.align_min_s) {
      const std::string key = i.Has("align_max_s") ? "align_max_s" : "align_min_s";
      throw InputError(path, i.Line(key), i.Path(key),
                       "align_max_s must not be below align_min_s (" +
                           std::to_string(c.init.align_min_s) + " s)");
    }
    i.GetPositive("align_decide_mass", &c.init.align_decide_mass);
    if (c.init.align_decide_mass > 1.0) {
      throw InputError(path, i.Line("align_decide_mass"), i.Path("align_decide_mass"),
                       "a probability: at most 1");
    }
    i.CheckNoUnknownKeys();
  }
  if (r.Has("watchdog")) {
    MapReader w = r.Child("watchdog");
    w.Get("enabled", &c.watchdog.enabled);
    w.GetDuration("window_s", &c.watchdog.window_s);
    w.GetAtLeast("min_fixes", &c.watchdog.min_fixes, 1);
    w.GetPositive("rejected_share", &c.watchdog.rejected_share);
    if (c.watchdog.rejected_share > 1.0) {
      throw InputError(path, w.Line("rejected_share"), w.Path("rejected_share"),
                       "a share: at most 1");
    }
    w.GetAtLeast("reacquisitions", &c.watchdog.reacquisitions, 1);
    w.GetAtLeast("max_restarts", &c.watchdog.max_restarts, 0);
    w.CheckNoUnknownKeys();
  }
  r.CheckNoUnknownKeys();
  return c;
}

}  // namespace

namespace {

struct Override {
  std::string key;  ///< dotted path
  std::vector<std::string> parts;
};

// One `--set KEY=VALUE` written into the configuration's YAML tree (sections made as needed).
Override ApplyOverride(const std::string& text, YAML::Node* root) {
  const std::size_t eq = text.find('=');
  Override o;
  o.key = text.substr(0, eq);
  if (eq == std::string::npos || o.key.empty()) {
    throw InputError(kCommandLine, 0, "--set", "'" + text + "': expected KEY=VALUE");
  }
  const std::string field = "--set " + o.key;
  for (std::size_t begin = 0;;) {
    const std::size_t dot = o.key.find('.', begin);
    o.parts.push_back(o.key.substr(begin, dot - begin));
    if (o.parts.back().empty()) throw InputError(kCommandLine, 0, field, "an empty key name");
    if (dot == std::string::npos) break;
    begin = dot + 1;
  }
  YAML::Node value;
  try {
    value = YAML::Load(text.substr(eq + 1));
  } catch (const YAML::Exception& e) {
    throw InputError(kCommandLine, 0, field, "not a YAML value: " + e.msg);
  }
  if (!value.IsDefined() || value.IsNull()) {
    throw InputError(kCommandLine, 0, field, "no value after '='");
  }
  if (!root->IsDefined() || root->IsNull()) *root = YAML::Node(YAML::NodeType::Map);
  YAML::Node node = *root;
  // A file that is not a mapping at the top is the reader's error (MapReader), not --set's.
  if (!node.IsMap()) return o;
  for (std::size_t i = 0; i + 1 < o.parts.size(); ++i) {
    YAML::Node child = node[o.parts[i]];
    if (!child.IsDefined() || child.IsNull()) {
      node[o.parts[i]] = YAML::Node(YAML::NodeType::Map);
      child.reset(node[o.parts[i]]);
    }
    node.reset(child);  // rebinds; `node = child` would overwrite the section with its child
    if (!node.IsMap()) {
      throw InputError(kCommandLine, 0, field,
                       "'" + o.parts[i] + "' holds a value, not a section of keys");
    }
  }
  node[o.parts.back()] = value;
  return o;
}

}  // namespace

EstimatorConfig LoadEstimatorConfig(const std::string& path,
                                    const std::vector<std::string>& overrides) {
  YAML::Node root;
  try {
    root = YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw InputError(path, 0, "(file)", "cannot open");
  } catch (const YAML::ParserException& e) {
    throw InputError(path, e.mark.line + 1, "(syntax)", e.msg);
  }
  std::vector<Override> applied;
  for (const std::string& text : overrides) applied.push_back(ApplyOverride(text, &root));
  try {
    return ParseEstimatorConfig(root, path, std::filesystem::path(path).stem().string());
  } catch (const InputError& e) {
    // An error at a key the command line set (or inside a section it set) is the command
    // line's: the file has no line for it. The last override of a key is the one in the tree.
    for (auto o = applied.rbegin(); o != applied.rend(); ++o) {
      const std::string& f = e.field();
      if (f == o->key || f.rfind(o->key + ".", 0) == 0) {
        throw InputError(kCommandLine, 0, "--set " + f, e.message());
      }
    }
    throw;
  }
}

// The configuration a program built, checked by the reader of the files: written as the YAML
// it stands for and read back, so that a program gets every check a file gets, from the same
// code (a second list of the checks would drift from the first).
void ValidateEstimatorConfig(const EstimatorConfig& config) {
  try {
    ParseEstimatorConfig(YAML::Load(ToYaml(config)), "EstimatorConfig", config.name);
  } catch (const InputError& e) {
    throw std::invalid_argument("EstimatorConfig " + e.field() + ": " + e.message());
  } catch (const YAML::Exception& e) {
    throw std::invalid_argument(std::string("EstimatorConfig: ") + e.what());
  }
}

EstimatorConfig LoadPreset(const std::string& name_or_path,
                           const std::vector<std::string>& overrides) {
  namespace fs = std::filesystem;
  if (fs::is_regular_file(name_or_path)) return LoadEstimatorConfig(name_or_path, overrides);
  std::vector<std::string> dirs;
  if (const char* env = std::getenv("SKERRY_PRESET_DIR")) dirs.emplace_back(env);
  dirs.emplace_back(SKERRY_PRESET_INSTALL_DIR);
  dirs.emplace_back(SKERRY_PRESET_SOURCE_DIR);
  for (const std::string& d : dirs) {
    if (d.empty()) continue;
    const fs::path p = fs::path(d) / (name_or_path + ".yaml");
    if (fs::is_regular_file(p)) return LoadEstimatorConfig(p.string(), overrides);
  }
  throw InputError(name_or_path, 0, "(preset)",
                   "no such file and no preset of that name (looked in $SKERRY_PRESET_DIR, " +
                       std::string(SKERRY_PRESET_INSTALL_DIR) + ", " + SKERRY_PRESET_SOURCE_DIR +
                       ")");
}

std::string ToYaml(const EstimatorConfig& c) {
  YAML::Emitter e;
  auto ceres = [&e](const char* key, const CeresConfig& s) {
    e << YAML::Key << key << YAML::Value << YAML::BeginMap;
    e << YAML::Key << "trust_region" << YAML::Value << s.trust_region;
    e << YAML::Key << "dogleg_type" << YAML::Value << s.dogleg_type;
    e << YAML::Key << "linear_solver" << YAML::Value << s.linear_solver;
    e << YAML::Key << "max_iterations" << YAML::Value << s.max_iterations;
    e << YAML::Key << "initial_trust_region_radius" << YAML::Value << s.initial_trust_region_radius;
    e << YAML::Key << "max_time_s" << YAML::Value << s.max_time_s;
    e << YAML::Key << "num_threads" << YAML::Value << s.num_threads;
    e << YAML::Key << "function_tolerance" << YAML::Value << s.function_tolerance;
    e << YAML::Key << "gradient_tolerance" << YAML::Value << s.gradient_tolerance;
    e << YAML::Key << "parameter_tolerance" << YAML::Value << s.parameter_tolerance;
    e << YAML::Key << "chain_gains" << YAML::Value << s.chain_gains;
    e << YAML::EndMap;
  };
  e << YAML::BeginMap;
  e << YAML::Key << "name" << YAML::Value << c.name;
  e << YAML::Key << "keyframe_rate_hz" << YAML::Value << c.keyframe_rate_hz;
  e << YAML::Key << "window_keyframes" << YAML::Value << c.window_keyframes;
  e << YAML::Key << "window_s" << YAML::Value << c.window_s;
  e << YAML::Key << "first_estimate_jacobians" << YAML::Value << c.first_estimate_jacobians;
  e << YAML::Key << "estimate_gyro_calibration" << YAML::Value << c.estimate_gyro_calibration;
  e << YAML::Key << "compute_covariance" << YAML::Value << c.compute_covariance;
  e << YAML::Key << "gnss" << YAML::Value << YAML::BeginMap;
  e << YAML::Key << "loss" << YAML::Value << ToString(c.gnss_loss.type);
  e << YAML::Key << "loss_scale" << YAML::Value << c.gnss_loss.scale;
  e << YAML::Key << "heading_loss" << YAML::Value << ToString(c.heading_loss.type);
  e << YAML::Key << "heading_loss_scale" << YAML::Value << c.heading_loss.scale;
  e << YAML::Key << "gate_probability" << YAML::Value << c.gnss_gate_probability;
  e << YAML::Key << "gate_max_reject_s" << YAML::Value << c.gnss_gate_max_reject_s;
  e << YAML::Key << "gate_streak_max_gap_s" << YAML::Value << c.gnss_gate_streak_max_gap_s;
  e << YAML::Key << "sigma_scale" << YAML::Value << c.gnss_sigma_scale;
  e << YAML::Key << "use_heading" << YAML::Value << c.use_gnss_heading;
  e << YAML::Key << "jump_test" << YAML::Value << c.gnss_jump_test;
  e << YAML::Key << "jump_as_drift_step" << YAML::Value << c.gnss_jump_as_drift_step;
  e << YAML::Key << "jump_step_after_s" << YAML::Value << c.gnss_jump_step_after_s;
  e << YAML::Key << "drift_sigma_horizontal_m" << YAML::Value << c.gnss_drift.sigma_horizontal_m;
  e << YAML::Key << "drift_sigma_vertical_m" << YAML::Value << c.gnss_drift.sigma_vertical_m;
  e << YAML::Key << "drift_tau_s" << YAML::Value << c.gnss_drift.tau_s;
  e << YAML::EndMap;
  ceres("solver", c.ceres);
  ceres("batch_solver", c.batch_ceres);
  e << YAML::Key << "init" << YAML::Value << YAML::BeginMap;
  e << YAML::Key << "mode" << YAML::Value << c.init.mode;
  e << YAML::Key << "min_cog_distance_m" << YAML::Value << c.init.min_cog_distance_m;
  e << YAML::Key << "max_cog_time_s" << YAML::Value << c.init.max_cog_time_s;
  e << YAML::Key << "attitude_window_s" << YAML::Value << c.init.attitude_window_s;
  e << YAML::Key << "roll_pitch_sigma_deg" << YAML::Value << c.init.roll_pitch_sigma_deg;
  e << YAML::Key << "yaw_sigma_deg" << YAML::Value << c.init.yaw_sigma_deg;
  e << YAML::Key << "velocity_sigma_m_s" << YAML::Value << c.init.velocity_sigma_m_s;
  e << YAML::Key << "position_sigma_scale" << YAML::Value << c.init.position_sigma_scale;
  if (c.init.static_s == InitConfig::kStaticAuto) {
    e << YAML::Key << "static_s" << YAML::Value << "auto";
  } else {
    e << YAML::Key << "static_s" << YAML::Value << c.init.static_s;
  }
  e << YAML::Key << "align_hypotheses" << YAML::Value << c.init.align_hypotheses;
  e << YAML::Key << "align_min_s" << YAML::Value << c.init.align_min_s;
  e << YAML::Key << "align_max_s" << YAML::Value << c.init.align_max_s;
  e << YAML::Key << "align_decide_mass" << YAML::Value << c.init.align_decide_mass;
  e << YAML::EndMap;
  e << YAML::Key << "watchdog" << YAML::Value << YAML::BeginMap;
  e << YAML::Key << "enabled" << YAML::Value << c.watchdog.enabled;
  e << YAML::Key << "window_s" << YAML::Value << c.watchdog.window_s;
  e << YAML::Key << "min_fixes" << YAML::Value << c.watchdog.min_fixes;
  e << YAML::Key << "rejected_share" << YAML::Value << c.watchdog.rejected_share;
  e << YAML::Key << "reacquisitions" << YAML::Value << c.watchdog.reacquisitions;
  e << YAML::Key << "max_restarts" << YAML::Value << c.watchdog.max_restarts;
  e << YAML::EndMap;
  e << YAML::Key << "skyline" << YAML::Value << YAML::BeginMap;
  e << YAML::Key << "column_stride_px" << YAML::Value << c.skyline.column_stride_px;
  e << YAML::Key << "sigma_px" << YAML::Value << c.skyline.sigma_px;
  e << YAML::Key << "correlation_px" << YAML::Value << c.skyline.correlation_px;
  e << YAML::Key << "huber_sigmas" << YAML::Value << c.skyline.huber_sigmas;
  e << YAML::Key << "frame_correlation_s" << YAML::Value << c.skyline.frame_correlation_s;
  e << YAML::Key << "frame_correlation_m" << YAML::Value << c.skyline.frame_correlation_m;
  e << YAML::Key << "dem_sigma_m" << YAML::Value << c.skyline.dem_sigma_m;
  e << YAML::Key << "min_confidence" << YAML::Value << c.skyline.min_confidence;
  e << YAML::Key << "min_samples" << YAML::Value << c.skyline.min_samples;
  e << YAML::Key << "source" << YAML::Value << c.skyline.source;
  e << YAML::Key << "refraction_k" << YAML::Value << c.skyline.refraction_k;
  e << YAML::Key << "refraction_k_sigma" << YAML::Value << c.skyline.refraction_k_sigma;
  e << YAML::Key << "crest_offset_m" << YAML::Value << c.skyline.crest_offset_m;
  e << YAML::Key << "crest_offset_sigma_m" << YAML::Value << c.skyline.crest_offset_sigma_m;
  e << YAML::Key << "max_range_m" << YAML::Value << c.skyline.max_range_m;
  e << YAML::Key << "dem_spacing_m" << YAML::Value << c.skyline.dem_spacing_m;
  e << YAML::Key << "dem_oversampling" << YAML::Value << c.skyline.dem_oversampling;
  e << YAML::Key << "dem_sharpening" << YAML::Value << c.skyline.dem_sharpening;
  e << YAML::Key << "dem_footprint_cells" << YAML::Value << c.skyline.dem_footprint_cells;
  e << YAML::Key << "dem_sharpening_sigma" << YAML::Value << c.skyline.dem_sharpening_sigma;
  e << YAML::Key << "reacquire_after_rejections" << YAML::Value
    << c.skyline.reacquire_after_rejections;
  e << YAML::Key << "relocate_min_radius_m" << YAML::Value << c.skyline.relocate_min_radius_m;
  e << YAML::Key << "start_radius_m" << YAML::Value << c.skyline.start_radius_m;
  e << YAML::Key << "relocate_above_heading_sigma_deg" << YAML::Value
    << c.skyline.relocate_above_heading_sigma_deg;
  e << YAML::Key << "threads" << YAML::Value << c.skyline.threads;
  e << YAML::EndMap;
  {
    const LidarAerialConfig& l = c.lidar_aerial;
    e << YAML::Key << "lidar_aerial" << YAML::Value << YAML::BeginMap;
    e << YAML::Key << "resolution_m" << YAML::Value << l.resolution_m;
    e << YAML::Key << "max_distance_m" << YAML::Value << l.max_distance_m;
    e << YAML::Key << "map_blur_m" << YAML::Value << l.map_blur_m;
    e << YAML::Key << "canny_high_quantile" << YAML::Value << l.canny_high_quantile;
    e << YAML::Key << "canny_low_quantile" << YAML::Value << l.canny_low_quantile;
    e << YAML::Key << "sigma_m" << YAML::Value << l.sigma_m;
    e << YAML::Key << "loss" << YAML::Value << l.loss;
    e << YAML::Key << "batch_loss" << YAML::Value << l.batch_loss;
    e << YAML::Key << "loss_sigmas" << YAML::Value << l.loss_sigmas;
    e << YAML::Key << "window_trim_sigmas" << YAML::Value << l.window_trim_sigmas;
    e << YAML::Key << "information_scale_m" << YAML::Value << l.information_scale_m;
    e << YAML::Key << "effective_points" << YAML::Value << l.effective_points;
    e << YAML::Key << "scan_correlation_s" << YAML::Value << l.scan_correlation_s;
    e << YAML::Key << "min_height_m" << YAML::Value << l.min_height_m;
    e << YAML::Key << "max_range_m" << YAML::Value << l.max_range_m;
    e << YAML::Key << "hull_min_b_m" << YAML::Value << YAML::Flow << l.hull_min_b_m;
    e << YAML::Key << "hull_max_b_m" << YAML::Value << YAML::Flow << l.hull_max_b_m;
    e << YAML::Key << "cell_m" << YAML::Value << l.cell_m;
    e << YAML::Key << "front_sector_deg" << YAML::Value << l.front_sector_deg;
    e << YAML::Key << "wall_gap_per_m" << YAML::Value << l.wall_gap_per_m;
    e << YAML::Key << "max_edge_height_m" << YAML::Value << l.max_edge_height_m;
    e << YAML::Key << "max_points" << YAML::Value << l.max_points;
    e << YAML::Key << "min_points" << YAML::Value << l.min_points;
    e << YAML::Key << "map_margin_m" << YAML::Value << l.map_margin_m;
    e << YAML::Key << "map_tile_above_mcells" << YAML::Value << l.map_tile_above_mcells;
    e << YAML::Key << "map_tile_m" << YAML::Value << l.map_tile_m;
    e << YAML::Key << "model_relief" << YAML::Value << l.model_relief;
    e << YAML::Key << "start_radius_m" << YAML::Value << l.start_radius_m;
    e << YAML::Key << "relocate_above_position_sigma_m" << YAML::Value
      << l.relocate_above_position_sigma_m;
    e << YAML::Key << "reacquire_after_rejections" << YAML::Value << l.reacquire_after_rejections;
    e << YAML::Key << "relocate_above_heading_sigma_deg" << YAML::Value
      << l.relocate_above_heading_sigma_deg;
    e << YAML::EndMap;
  }
  if (!c.sensors.empty()) {
    e << YAML::Key << "sensors" << YAML::Value << YAML::BeginMap;
    for (const auto& [name, o] : c.sensors) {
      e << YAML::Key << name << YAML::Value << YAML::BeginMap;
      e << YAML::Key << "loss" << YAML::Value << ToString(o.loss.type);
      e << YAML::Key << "loss_scale" << YAML::Value << o.loss.scale;
      e << YAML::Key << "gate_probability" << YAML::Value << o.gate_probability;
      e << YAML::Key << "calibrate" << YAML::Value << o.calibrate;
      e << YAML::Key << "extrinsic_prior_sigma_deg" << YAML::Value << o.extrinsic_prior_sigma_deg;
      e << YAML::Key << "extrinsic_prior_sigma_m" << YAML::Value << o.extrinsic_prior_sigma_m;
      e << YAML::EndMap;
    }
    e << YAML::EndMap;
  }
  e << YAML::EndMap;
  return e.c_str();
}

}  // namespace skerry
