#include "skerry/io/dataset.h"

#include <yaml-cpp/yaml.h>

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "skerry/core/format_number.h"
#include "skerry/core/input_error.h"
#include "skerry/io/atomic_file.h"
#include "skerry/io/csv_reader.h"
#include "skerry/io/state_row_io.h"
#include "yaml_util.h"

namespace skerry {
namespace {

namespace fs = std::filesystem;
using yaml_util::Reader;

constexpr char kDatasetYaml[] = "dataset.yaml";
constexpr char kTruthStatesCsv[] = "truth_states.csv";
constexpr char kEventsCsv[] = "events.csv";
constexpr char kPoseFixOutliersCsv[] = "pose_fix_outliers.csv";
constexpr char kHeadingCsv[] = "heading.csv";
constexpr char kCourseCsv[] = "course.csv";
constexpr char kAttitudeCsv[] = "attitude.csv";
constexpr char kRateOfTurnCsv[] = "rate_of_turn.csv";

std::string InDir(const std::string& directory, const std::string& file) {
  return (fs::path(directory) / file).string();
}

// A geodetic point {lat_deg, lon_deg, height_m} at `path` (origin, a map's viewpoint).
GeoOrigin ParseGeoPoint(const Reader& yaml, const YAML::Node& node, const std::string& path) {
  yaml.RequireMap(node, path);
  yaml.RejectUnknownKeys(node, path, {"lat_deg", "lon_deg", "height_m"});
  GeoOrigin origin;
  const YAML::Node lat = yaml.Require(node, path, "lat_deg");
  origin.lat_deg = yaml.Double(lat, path + ".lat_deg");
  if (std::fabs(origin.lat_deg) > 90.0) yaml.Fail(lat, path + ".lat_deg", "outside [-90, 90]");
  const YAML::Node lon = yaml.Require(node, path, "lon_deg");
  origin.lon_deg = yaml.Double(lon, path + ".lon_deg");
  if (std::fabs(origin.lon_deg) > 180.0) yaml.Fail(lon, path + ".lon_deg", "outside [-180, 180]");
  origin.height_m = yaml.Double(yaml.Require(node, path, "height_m"), path + ".height_m");
  return origin;
}

GeoOrigin ParseOrigin(const Reader& yaml, const YAML::Node& root) {
  return ParseGeoPoint(yaml, yaml.Require(root, "", "origin"), "origin");
}

// A sensor's T_b_s: {q_xyzw: [x, y, z, w], p_m: [x, y, z]}.
SensorMount ParseMount(const Reader& yaml, const YAML::Node& node, const std::string& path) {
  yaml.RequireMap(node, path);
  yaml.RejectUnknownKeys(node, path, {"q_xyzw", "p_m"});
  const YAML::Node q_node = yaml.Require(node, path, "q_xyzw");
  const std::vector<double> q = yaml.Doubles(q_node, path + ".q_xyzw", 4);
  const Eigen::Quaterniond q_b_s(q[3], q[0], q[1], q[2]);
  if (!IsUnitQuaternion(q_b_s)) yaml.Fail(q_node, path + ".q_xyzw", "quaternion is not unit");
  SensorMount mount;
  mount.q_b_s = q_b_s.normalized();
  mount.p_b_s = yaml.Vector3(yaml.Require(node, path, "p_m"), path + ".p_m");
  return mount;
}

// A file or folder named in dataset.yaml must exist (relative to the dataset folder).
std::string ExistingPath(const Reader& yaml,
                         const YAML::Node& node,
                         const std::string& path,
                         const std::string& directory,
                         bool folder) {
  const std::string name = yaml.String(node, path);
  const fs::path full = fs::path(name).is_absolute() ? fs::path(name) : fs::path(directory) / name;
  std::error_code ec;
  const bool ok = folder ? fs::is_directory(full, ec) : fs::is_regular_file(full, ec);
  if (!ok)
    yaml.Fail(node, path,
              std::string("no such ") + (folder ? "folder: " : "file: ") + full.string());
  return full.string();
}

CameraConfig ParseCamera(const Reader& yaml,
                         const YAML::Node& node,
                         const std::string& name,
                         const std::string& directory) {
  const std::string path = "sensors." + name;
  yaml.RequireMap(node, path);
  yaml.RejectUnknownKeys(
      node, path,
      {"images", "file", "width_px", "height_px", "fx", "fy", "cx", "cy", "distortion", "T_b_c"});
  CameraConfig c;
  c.name = name;
  c.image_dir =
      ExistingPath(yaml, yaml.Require(node, path, "images"), path + ".images", directory, true);
  c.file = ExistingPath(yaml, yaml.Require(node, path, "file"), path + ".file", directory, false);
  auto positive = [&](const std::string& key) {
    return yaml.PositiveDouble(yaml.Require(node, path, key), path + "." + key);
  };
  auto pixels = [&](const std::string& key) {
    const YAML::Node n = yaml.Require(node, path, key);
    const double v = yaml.PositiveDouble(n, path + "." + key);
    if (v != std::floor(v) || v > 1e6)
      yaml.Fail(n, path + "." + key, "expected a whole number of pixels");
    return static_cast<int>(v);
  };
  c.width_px = pixels("width_px");
  c.height_px = pixels("height_px");
  c.fx = positive("fx");
  c.fy = positive("fy");
  c.cx = yaml.Double(yaml.Require(node, path, "cx"), path + ".cx");
  c.cy = yaml.Double(yaml.Require(node, path, "cy"), path + ".cy");
  if (node["distortion"]) {
    const YAML::Node d = node["distortion"];
    if (!d.IsSequence() || (d.size() != 4 && d.size() != 5 && d.size() != 8)) {
      yaml.Fail(d, path + ".distortion",
                "expected 4, 5 or 8 OpenCV coefficients (k1, k2, p1, p2[, k3[, k4, k5, k6]])");
    }
    c.distortion = yaml.Doubles(d, path + ".distortion", static_cast<int>(d.size()));
  }
  c.T_b_c = ParseMount(yaml, yaml.Require(node, path, "T_b_c"), path + ".T_b_c");
  return c;
}

LidarConfig ParseLidar(const Reader& yaml,
                       const YAML::Node& node,
                       const std::string& name,
                       const std::string& directory) {
  const std::string path = "sensors." + name;
  yaml.RequireMap(node, path);
  yaml.RejectUnknownKeys(node, path, {"scans", "file", "T_b_l"});
  LidarConfig l;
  l.name = name;
  l.scan_dir =
      ExistingPath(yaml, yaml.Require(node, path, "scans"), path + ".scans", directory, true);
  l.file = ExistingPath(yaml, yaml.Require(node, path, "file"), path + ".file", directory, false);
  l.T_b_l = ParseMount(yaml, yaml.Require(node, path, "T_b_l"), path + ".T_b_l");
  return l;
}

// camera.csv / lidar.csv: t, file (in `folder`), time strictly increasing, every file present.
std::vector<SensorFrame> ReadFramesCsv(const std::string& path, const std::string& folder) {
  CsvReader reader(path, {"t", "file"});
  std::vector<SensorFrame> frames;
  while (reader.Next()) {
    SensorFrame f;
    f.t_ns = reader.GetIncreasingTimeNs(0);
    f.file = reader.GetString(1);
    if (f.file.empty()) reader.Fail(1, "empty file name");
    std::error_code ec;
    if (!fs::is_regular_file(fs::path(folder) / f.file, ec)) {
      reader.Fail(1, "no such file in " + folder + ": " + f.file);
    }
    frames.push_back(f);
  }
  return frames;
}

std::optional<MapConfig> ParseMap(const Reader& yaml,
                                  const YAML::Node& maps,
                                  const std::string& key,
                                  const std::string& directory) {
  const YAML::Node node = maps[key];
  if (!node) return std::nullopt;
  const std::string path = "maps." + key;
  yaml.RequireMap(node, path);
  const bool dem = key == "dem";
  if (dem) {
    yaml.RejectUnknownKeys(node, path, {"file", "crs", "vertical_datum"});
  } else {
    yaml.RejectUnknownKeys(node, path, {"file", "crs", "viewpoint", "clip_fraction"});
  }
  MapConfig m;
  m.path = ExistingPath(yaml, yaml.Require(node, path, "file"), path + ".file", directory, false);
  if (node["crs"]) m.crs = yaml.String(node["crs"], path + ".crs");
  if (!dem && node["viewpoint"]) {
    m.viewpoint = ParseGeoPoint(yaml, node["viewpoint"], path + ".viewpoint");
  }
  if (!dem && node["clip_fraction"]) {
    const double clip = yaml.Double(node["clip_fraction"], path + ".clip_fraction");
    if (!(clip >= 0.0 && clip < 0.5)) {
      yaml.Fail(node["clip_fraction"], path + ".clip_fraction",
                "must be in [0, 0.5): the share of cells clipped at each end of the stretch");
    }
    m.clip_fraction = clip;
  }
  if (dem) {
    const YAML::Node datum = yaml.Require(node, path, "vertical_datum");
    m.vertical_datum = yaml.String(datum, path + ".vertical_datum");
    if (m.vertical_datum != "egm96" && m.vertical_datum != "ellipsoidal") {
      yaml.Fail(datum, path + ".vertical_datum",
                "expected egm96 (orthometric heights, as SRTM) or ellipsoidal");
    }
  }
  return m;
}

// The rate dataset.yaml declares for the IMU against the rate its samples come at (the median
// interval, which gaps and jitter leave alone). The declared rate sets the rest detector's
// thresholds (rest_detection.cc) and the twin's noise, so a dataset written with the wrong one
// (200 Hz declared, 100 Hz recorded) ran with thresholds 1.4x off and said nothing. Refused
// beyond 25 % either way, naming the key and both rates.
void CheckImuRate(const Reader& yaml,
                  const YAML::Node& rate_node,
                  double declared_hz,
                  const std::vector<ImuSample>& samples,
                  const std::string& imu_path) {
  if (samples.size() < 3) return;
  std::vector<TimeNs> dt;
  dt.reserve(samples.size() - 1);
  for (size_t k = 1; k < samples.size(); ++k) dt.push_back(samples[k].t_ns - samples[k - 1].t_ns);
  std::nth_element(dt.begin(), dt.begin() + dt.size() / 2, dt.end());
  const double median_s = NsToSeconds(dt[dt.size() / 2]);
  if (!(median_s > 0.0)) return;  // the reader refuses times that do not increase
  const double recorded_hz = 1.0 / median_s;
  const double ratio = declared_hz / recorded_hz;
  if (ratio < 0.8 || ratio > 1.25) {
    yaml.Fail(rate_node, "sensors.imu.rate_hz",
              "declares " + FormatNumber(declared_hz) + " Hz, but the samples of " + imu_path +
                  " come at " + FormatNumber(recorded_hz) + " Hz (median interval " +
                  FormatNumber(median_s) + " s)");
  }
}

// Parses sensors.imu; returns the data file name.
std::string ParseImu(const Reader& yaml, const YAML::Node& node, ImuConfig* imu) {
  const std::string path = "sensors.imu";
  yaml.RequireMap(node, path);
  yaml.RejectUnknownKeys(
      node, path,
      {"file", "rate_hz", "T_b_i", "gyro_noise_density_rad_s_sqrt_hz",
       "accel_noise_density_m_s2_sqrt_hz", "gyro_bias_random_walk_rad_s2_sqrt_hz",
       "accel_bias_random_walk_m_s3_sqrt_hz", "gyro_bias_prior_sigma_rad_s",
       "accel_bias_prior_sigma_m_s2", "gyro_scale_factor_sigma_ppm", "gyro_misalignment_sigma_mrad",
       "gravity_m_s2"});
  if (node["gravity_m_s2"]) {
    // Before the Earth model, gravity was one constant magnitude here; silently ignoring it
    // would change what an old dataset means.
    yaml.Fail(
        node["gravity_m_s2"], path + ".gravity_m_s2",
        "moved: gravity is the Earth's, not the IMU's; leave it out for WGS84 normal "
        "gravity or write `earth: {model: flat, gravity_m_s2: ...}` (docs/dataset-format.md)");
  }
  auto positive = [&](const std::string& key) {
    return yaml.PositiveDouble(yaml.Require(node, path, key), path + "." + key);
  };
  const std::string file = yaml.String(yaml.Require(node, path, "file"), path + ".file");
  imu->rate_hz = positive("rate_hz");

  const SensorMount mount = ParseMount(yaml, yaml.Require(node, path, "T_b_i"), path + ".T_b_i");
  imu->q_b_i = mount.q_b_s;
  imu->p_b_i = mount.p_b_s;

  imu->noise.gyro_noise_density_rad_s_sqrt_hz = positive("gyro_noise_density_rad_s_sqrt_hz");
  imu->noise.accel_noise_density_m_s2_sqrt_hz = positive("accel_noise_density_m_s2_sqrt_hz");
  imu->noise.gyro_bias_random_walk_rad_s2_sqrt_hz =
      positive("gyro_bias_random_walk_rad_s2_sqrt_hz");
  imu->noise.accel_bias_random_walk_m_s3_sqrt_hz = positive("accel_bias_random_walk_m_s3_sqrt_hz");
  if (node["gyro_bias_prior_sigma_rad_s"]) {
    imu->gyro_bias_prior_sigma_rad_s = positive("gyro_bias_prior_sigma_rad_s");
  }
  if (node["accel_bias_prior_sigma_m_s2"]) {
    imu->accel_bias_prior_sigma_m_s2 = positive("accel_bias_prior_sigma_m_s2");
  }
  // The datasheet's residual gyro scale factor and misalignment: optional, >= 0.
  for (const auto& [key, value] :
       {std::pair<const char*, double*>{"gyro_scale_factor_sigma_ppm",
                                        &imu->gyro_scale_factor_sigma_ppm},
        {"gyro_misalignment_sigma_mrad", &imu->gyro_misalignment_sigma_mrad}}) {
    if (node[key]) *value = yaml.NonNegativeDouble(node[key], path + "." + key);
  }
  return file;
}

// Parses the optional `earth` section (default: the WGS84 Earth).
EarthConfig ParseEarth(const Reader& yaml, const YAML::Node& root) {
  EarthConfig earth;
  const YAML::Node node = root["earth"];
  if (!node) return earth;
  yaml.RequireMap(node, "earth");
  yaml.RejectUnknownKeys(node, "earth", {"model", "gravity_m_s2"});
  const YAML::Node model = yaml.Require(node, "earth", "model");
  if (!ParseEarthKind(yaml.String(model, "earth.model"), &earth.kind)) {
    yaml.Fail(model, "earth.model", "expected wgs84 or flat");
  }
  if (node["gravity_m_s2"]) {
    if (earth.kind != EarthKind::kFlat) {
      yaml.Fail(node["gravity_m_s2"], "earth.gravity_m_s2",
                "only for model flat (wgs84 uses normal gravity at every position)");
    }
    earth.gravity_m_s2 = yaml.PositiveDouble(node["gravity_m_s2"], "earth.gravity_m_s2");
  }
  return earth;
}

// Parses sensors.gnss; returns the data file name.
std::string ParseGnss(const Reader& yaml, const YAML::Node& node, GnssConfig* gnss) {
  const std::string path = "sensors.gnss";
  yaml.RequireMap(node, path);
  yaml.RejectUnknownKeys(node, path, {"file", "lever_arm_b_m", "baseline_b"});
  const std::string file = yaml.String(yaml.Require(node, path, "file"), path + ".file");
  gnss->p_b_g = yaml.Vector3(yaml.Require(node, path, "lever_arm_b_m"), path + ".lever_arm_b_m");
  if (node["baseline_b"]) {
    const YAML::Node b = node["baseline_b"];
    gnss->baseline_b = yaml.Vector3(b, path + ".baseline_b");
    if (!(gnss->baseline_b.norm() > 0.0)) yaml.Fail(b, path + ".baseline_b", "must be non-zero");
  }
  return file;
}

// Parses sensors.pose_fixes; returns the data file name.
std::string ParsePoseFixes(const Reader& yaml, const YAML::Node& node, SensorMount* mount) {
  const std::string path = "sensors.pose_fixes";
  yaml.RequireMap(node, path);
  yaml.RejectUnknownKeys(node, path, {"file", "T_b_s"});
  const std::string file = yaml.String(yaml.Require(node, path, "file"), path + ".file");
  *mount = ParseMount(yaml, yaml.Require(node, path, "T_b_s"), path + ".T_b_s");
  return file;
}

// Parses sensors.water_surface.
WaterSurfaceConfig ParseWaterSurface(const Reader& yaml, const YAML::Node& node) {
  const std::string path = "sensors.water_surface";
  yaml.RequireMap(node, path);
  yaml.RejectUnknownKeys(node, path, {"height_m", "sigma_m", "rate_hz"});
  WaterSurfaceConfig w;
  w.height_m = yaml.Double(yaml.Require(node, path, "height_m"), path + ".height_m");
  w.sigma_m = yaml.PositiveDouble(yaml.Require(node, path, "sigma_m"), path + ".sigma_m");
  if (node["rate_hz"]) w.rate_hz = yaml.PositiveDouble(node["rate_hz"], path + ".rate_hz");
  return w;
}

// ",value" at the end of a row.
void AppendCsvDouble(double value, std::string* line) {
  *line += ',';
  AppendDouble(value, line);
}

bool StartsWith(const std::string& s, const std::string& prefix) {
  return s.compare(0, prefix.size(), prefix) == 0;
}

std::vector<ImuSample> ReadImuCsv(const std::string& path) {
  CsvReader reader = OpenImuCsv(path);
  std::vector<ImuSample> samples;
  samples.reserve(reader.RowsAtMost());
  while (reader.Next()) samples.push_back(ReadImuRow(&reader));
  if (samples.empty()) ThrowNoImuSamples(path);
  return samples;
}

std::vector<GnssFix> ReadGnssCsv(const std::string& path, const LocalFrame& frame) {
  CsvReader reader = OpenGnssCsv(path);
  std::vector<GnssFix> fixes;
  fixes.reserve(reader.RowsAtMost());
  while (reader.Next()) fixes.push_back(ReadGnssRow(frame, &reader));
  return fixes;
}

std::vector<NavState> ReadTruthStatesCsv(const std::string& path) {
  CsvReader reader(path, NavStateColumns());
  std::vector<NavState> states;
  states.reserve(reader.RowsAtMost());
  while (reader.Next()) states.push_back(ReadNavStateRow(&reader));
  return states;
}

// The marine files (docs/dataset-format.md), each loaded when present.
void ReadMarineCsvs(const std::string& directory, MarineRecords* marine) {
  const std::string heading_path = InDir(directory, kHeadingCsv);
  if (fs::exists(heading_path)) {
    CsvReader reader(heading_path, {"t", "heading_deg"});
    while (reader.Next()) {
      HeadingRecord h;
      h.t_ns = reader.GetIncreasingTimeNs(0);
      h.heading_deg = reader.GetDouble(1);
      if (!(h.heading_deg >= 0.0 && h.heading_deg < 360.0)) reader.Fail(1, "outside [0, 360)");
      marine->headings.push_back(h);
    }
  }
  const std::string course_path = InDir(directory, kCourseCsv);
  if (fs::exists(course_path)) {
    CsvReader reader(course_path, {"t", "cog_deg", "sog_m_s"});
    while (reader.Next()) {
      CourseRecord c;
      c.t_ns = reader.GetIncreasingTimeNs(0);
      c.cog_deg = reader.GetDouble(1);
      if (!(c.cog_deg >= 0.0 && c.cog_deg < 360.0)) reader.Fail(1, "outside [0, 360)");
      c.sog_m_s = reader.GetDouble(2);
      if (!(c.sog_m_s >= 0.0)) reader.Fail(2, "speed must not be negative");
      marine->courses.push_back(c);
    }
  }
  const std::string attitude_path = InDir(directory, kAttitudeCsv);
  if (fs::exists(attitude_path)) {
    CsvReader reader(attitude_path, {"t", "roll_deg", "pitch_deg", "yaw_deg"});
    while (reader.Next()) {
      AttitudeRecord a;
      a.t_ns = reader.GetIncreasingTimeNs(0);
      a.roll_deg = reader.GetDouble(1);
      a.pitch_deg = reader.GetDouble(2);
      a.yaw_deg = reader.GetOptionalDouble(3);
      marine->attitudes.push_back(a);
    }
  }
  const std::string rot_path = InDir(directory, kRateOfTurnCsv);
  if (fs::exists(rot_path)) {
    CsvReader reader(rot_path, {"t", "rate_deg_s"});
    while (reader.Next()) {
      RateOfTurnRecord r;
      r.t_ns = reader.GetIncreasingTimeNs(0);
      r.rate_deg_s = reader.GetDouble(1);
      marine->rates_of_turn.push_back(r);
    }
  }
}

// Writes one marine file: its header, then `row(record)` a line.
template <typename Record, typename Row>
void WriteMarineCsv(const std::string& path,
                    const char* header,
                    const std::vector<Record>& records,
                    Row row) {
  AtomicFile out_file(path);
  std::ofstream& out = out_file.stream();
  out << header << '\n';
  for (const Record& r : records) out << FormatSeconds(r.t_ns) << ',' << row(r) << '\n';
  out_file.Commit();
}

void EmitVector(YAML::Emitter* out, std::initializer_list<double> values) {
  *out << YAML::Flow << YAML::BeginSeq;
  for (double v : values) *out << v;
  *out << YAML::EndSeq;
}

// A sensor's T_b_s as ParseMount reads it.
void EmitMount(YAML::Emitter* y, const char* key, const SensorMount& m) {
  *y << YAML::Key << key << YAML::Value << YAML::BeginMap;
  *y << YAML::Key << "q_xyzw" << YAML::Value;
  EmitVector(y, {m.q_b_s.x(), m.q_b_s.y(), m.q_b_s.z(), m.q_b_s.w()});
  *y << YAML::Key << "p_m" << YAML::Value;
  EmitVector(y, {m.p_b_s.x(), m.p_b_s.y(), m.p_b_s.z()});
  *y << YAML::EndMap;
}

}  // namespace

CsvReader OpenImuCsv(const std::string& path) {
  return CsvReader(path, {"t", "wx", "wy", "wz", "ax", "ay", "az"});
}

ImuSample ReadImuRow(CsvReader* reader) {
  ImuSample s;
  s.t_ns = reader->GetIncreasingTimeNs(0);
  for (int i = 0; i < 3; ++i) {
    s.gyro_rad_s[i] = reader->GetDouble(1 + i);
    s.accel_m_s2[i] = reader->GetDouble(4 + i);
  }
  return s;
}

void RequireImu(const Dataset& data, const std::string& command) {
  if (data.has_imu) return;
  throw InputError(InDir(data.directory, kDatasetYaml), 0, "sensors.imu",
                   "dataset '" + data.name + "' has no IMU (no sensors.imu, no imu.csv): `" +
                       command +
                       "` integrates an IMU; a dataset imported from a marine log holds GNSS "
                       "fixes and heading records only (docs/marine_logs.md)");
}

void ThrowNoImuSamples(const std::string& path) {
  // Said here: an estimator given nothing would only report that it never initialised.
  throw InputError(path, 0, "t", "no IMU samples: the file has a header and no data");
}

CsvReader OpenGnssCsv(const std::string& path) {
  return CsvReader(path, {"t", "lat", "lon", "height", "sigma_e", "sigma_n", "sigma_u"},
                   CsvOptions(), {"heading_deg", "sigma_heading_deg"});
}

GnssFix ReadGnssRow(const LocalFrame& frame, CsvReader* reader) {
  GnssFix fix;
  fix.t_ns = reader->GetIncreasingTimeNs(0);
  fix.lat_deg = reader->GetDouble(1);
  if (std::fabs(fix.lat_deg) > 90.0) reader->Fail(1, "latitude outside [-90, 90]");
  fix.lon_deg = reader->GetDouble(2);
  if (std::fabs(fix.lon_deg) > 180.0) reader->Fail(2, "longitude outside [-180, 180]");
  fix.height_m = reader->GetDouble(3);
  for (int i = 0; i < 3; ++i) {
    fix.sigma_enu_m[i] = reader->GetDouble(4 + i);
    if (!(fix.sigma_enu_m[i] > 0.0)) reader->Fail(4 + i, "sigma must be positive");
  }
  if (reader->has_optional_columns()) {
    const std::optional<double> heading = reader->GetOptionalDouble(7);
    const std::optional<double> sigma = reader->GetOptionalDouble(8);
    if (heading.has_value() != sigma.has_value()) {
      reader->Fail(heading ? 8 : 7,
                   "heading_deg and sigma_heading_deg must both be given or "
                   "both be empty");
    }
    if (heading) {
      if (!(*sigma > 0.0)) reader->Fail(8, "sigma must be positive");
      fix.has_heading = true;
      fix.heading_deg = *heading;
      fix.sigma_heading_deg = *sigma;
    }
  }
  fix.p_w = frame.ToEnu(fix.lat_deg, fix.lon_deg, fix.height_m);
  return fix;
}

std::vector<PoseFix> ReadPoseFixesCsv(const std::string& path) {
  const std::vector<std::string> cov = {"cov_ee", "cov_en", "cov_eu", "cov_eh", "cov_nn",
                                        "cov_nu", "cov_nh", "cov_uu", "cov_uh", "cov_hh"};
  std::vector<std::string> columns = {"t", "kind", "east", "north", "up", "heading_deg"};
  columns.insert(columns.end(), cov.begin(), cov.end());
  CsvReader reader(path, columns);
  std::vector<PoseFix> fixes;
  constexpr double kDeg = M_PI / 180.0;
  while (reader.Next()) {
    PoseFix f;
    f.t_ns = reader.GetIncreasingTimeNs(0);
    const std::string kind = reader.GetString(1);
    if (kind == "en") {
    } else if (kind == "enu") {
      f.has_up = true;
    } else if (kind == "enh") {
      f.has_heading = true;
    } else if (kind == "enuh") {
      f.has_up = f.has_heading = true;
    } else {
      reader.Fail(1, "unknown kind \"" + kind + "\" (known: en, enu, enh, enuh)");
    }
    for (int i = 0; i < 3; ++i) f.p_w[i] = reader.GetDouble(2 + i);
    f.heading_deg = reader.GetDouble(5);
    // Upper triangle over (e, n, u, heading), the heading in degrees in the file, radians inside.
    int col = 6;
    for (int i = 0; i < 4; ++i) {
      for (int j = i; j < 4; ++j, ++col) {
        const double scale = (i == 3 ? kDeg : 1.0) * (j == 3 ? kDeg : 1.0);
        f.covariance(i, j) = f.covariance(j, i) = reader.GetDouble(col) * scale;
      }
    }
    const std::vector<int> c = f.MeasuredComponents();
    Eigen::MatrixXd C(c.size(), c.size());
    for (size_t i = 0; i < c.size(); ++i) {
      for (size_t j = 0; j < c.size(); ++j) C(i, j) = f.covariance(c[i], c[j]);
    }
    const Eigen::LLT<Eigen::MatrixXd> llt(C);
    if (llt.info() != Eigen::Success) {
      reader.Fail(
          6, "the covariance of the measured components (" + kind + ") is not positive definite");
    }
    fixes.push_back(f);
  }
  return fixes;
}

std::vector<GnssEvent> ReadEventsCsv(const std::string& path) {
  CsvReader reader(path, {"t_start", "t_end", "type", "de", "dn", "du"});
  std::vector<GnssEvent> events;
  while (reader.Next()) {
    GnssEvent event;
    event.t_start_ns = reader.GetIncreasingTimeNs(0);
    event.t_end_ns = reader.GetTimeNs(1);
    if (event.t_end_ns <= event.t_start_ns) reader.Fail(1, "t_end must be after t_start");
    event.type = reader.GetString(2);
    if (event.type != "outage" && event.type != "jump") {
      reader.Fail(2, "unknown event type \"" + event.type + "\" (known: outage, jump)");
    }
    for (int i = 0; i < 3; ++i) event.offset_enu_m[i] = reader.GetDouble(3 + i);
    events.push_back(event);
  }
  return events;
}

Dataset LoadDataset(const std::string& directory, DatasetParts parts) {
  const std::string yaml_path = InDir(directory, kDatasetYaml);
  const Reader yaml(yaml_path);
  const YAML::Node root = yaml_util::Parse(yaml_util::ReadFileText(yaml_path), yaml_path);
  yaml.RequireMap(root, "");
  yaml.RejectUnknownKeys(root, "", {"name", "origin", "earth", "sensors", "groundtruth", "maps"});

  Dataset dataset;
  dataset.directory = directory;
  dataset.name = yaml.String(yaml.Require(root, "", "name"), "name");
  dataset.origin = ParseOrigin(yaml, root);
  dataset.earth = ParseEarth(yaml, root);

  const YAML::Node sensors = yaml.Require(root, "", "sensors");
  yaml.RequireMap(sensors, "sensors");
  for (const auto& kv : sensors) {
    const std::string kind = yaml.Key(kv.first, "sensors");
    if (kind == "imu" || kind == "gnss" || kind == "pose_fixes" || kind == "water_surface") {
      continue;
    }
    if (StartsWith(kind, "camera")) {
      dataset.cameras.push_back(ParseCamera(yaml, kv.second, kind, directory));
    } else if (StartsWith(kind, "lidar")) {
      dataset.lidars.push_back(ParseLidar(yaml, kv.second, kind, directory));
    } else {
      yaml.Fail(kv.first, "sensors." + kind,
                "unknown sensor kind (known: imu, gnss, pose_fixes, water_surface, camera*, "
                "lidar*)");
    }
  }
  // No `imu`: a dataset without IMU (a marine log's): it loads, and the estimators refuse it.
  std::string imu_file;
  dataset.has_imu = static_cast<bool>(sensors["imu"]);
  if (dataset.has_imu) imu_file = ParseImu(yaml, sensors["imu"], &dataset.imu);
  std::string gnss_file;
  if (sensors["gnss"]) {
    dataset.has_gnss = true;
    gnss_file = ParseGnss(yaml, sensors["gnss"], &dataset.gnss);
  }
  std::string pose_fix_file;
  if (sensors["pose_fixes"]) {
    dataset.has_pose_fixes = true;
    pose_fix_file = ParsePoseFixes(yaml, sensors["pose_fixes"], &dataset.pose_fix_mount);
  }
  if (sensors["water_surface"]) {
    dataset.water_surface = ParseWaterSurface(yaml, sensors["water_surface"]);
  }
  if (root["maps"]) {
    const YAML::Node maps = root["maps"];
    yaml.RequireMap(maps, "maps");
    yaml.RejectUnknownKeys(maps, "maps", {"dem", "orthophoto"});
    dataset.dem = ParseMap(yaml, maps, "dem", directory);
    dataset.orthophoto = ParseMap(yaml, maps, "orthophoto", directory);
  }
  std::string groundtruth_file;
  if (root["groundtruth"]) {
    groundtruth_file = yaml.String(root["groundtruth"], "groundtruth");
  }

  dataset.gnss_path = gnss_file.empty() ? std::string() : InDir(directory, gnss_file);
  dataset.imu_path = imu_file.empty() ? std::string() : InDir(directory, imu_file);
  const bool streams = parts != DatasetParts::kWithoutStreams;
  if (streams && dataset.has_imu) {
    dataset.imu_samples = ReadImuCsv(dataset.imu_path);
    CheckImuRate(yaml, sensors["imu"]["rate_hz"], dataset.imu.rate_hz, dataset.imu_samples,
                 dataset.imu_path);
  }
  if (dataset.has_gnss && streams) {
    dataset.gnss_fixes = ReadGnssCsv(dataset.gnss_path, LocalFrame(dataset.origin));
  }
  if (dataset.has_pose_fixes) {
    dataset.pose_fix_path = InDir(directory, pose_fix_file);
    dataset.pose_fixes = ReadPoseFixesCsv(dataset.pose_fix_path);
  }
  for (const CameraConfig& c : dataset.cameras) {
    dataset.camera_frames.push_back(ReadFramesCsv(c.file, c.image_dir));
  }
  for (const LidarConfig& l : dataset.lidars) {
    dataset.lidar_scans.push_back(ReadFramesCsv(l.file, l.scan_dir));
  }
  if (!groundtruth_file.empty()) {
    dataset.groundtruth_path = InDir(directory, groundtruth_file);
    dataset.groundtruth = ReadTum(dataset.groundtruth_path);
  }
  const std::string truth_path = InDir(directory, kTruthStatesCsv);
  if (parts == DatasetParts::kAll && fs::exists(truth_path)) {
    dataset.truth_states = ReadTruthStatesCsv(truth_path);
  }
  const std::string events_path = InDir(directory, kEventsCsv);
  if (fs::exists(events_path)) dataset.events = ReadEventsCsv(events_path);
  const std::string outliers_path = InDir(directory, kPoseFixOutliersCsv);
  if (fs::exists(outliers_path)) {
    CsvReader reader(outliers_path, {"t"});
    while (reader.Next()) dataset.pose_fix_outliers.push_back(reader.GetIncreasingTimeNs(0));
  }
  if (streams) ReadMarineCsvs(directory, &dataset.marine);
  return dataset;
}

Dataset DatasetUntil(const Dataset& data, TimeNs t_end_ns) {
  Dataset out = data;
  // Every stream is in time order: keep the prefix up to t_end_ns.
  auto cut = [t_end_ns](auto* v, auto time_of) {
    auto it =
        std::find_if(v->begin(), v->end(), [&](const auto& x) { return time_of(x) > t_end_ns; });
    v->erase(it, v->end());
  };
  cut(&out.imu_samples, [](const ImuSample& s) { return s.t_ns; });
  cut(&out.gnss_fixes, [](const GnssFix& f) { return f.t_ns; });
  cut(&out.pose_fixes, [](const PoseFix& f) { return f.t_ns; });
  cut(&out.pose_fix_outliers, [](TimeNs t) { return t; });
  for (auto& frames : out.camera_frames) cut(&frames, [](const SensorFrame& f) { return f.t_ns; });
  for (auto& scans : out.lidar_scans) cut(&scans, [](const SensorFrame& f) { return f.t_ns; });
  cut(&out.groundtruth, [](const StampedPose& p) { return p.t_ns; });
  cut(&out.truth_states, [](const NavState& s) { return s.t_ns; });
  cut(&out.marine.headings, [](const HeadingRecord& r) { return r.t_ns; });
  cut(&out.marine.courses, [](const CourseRecord& r) { return r.t_ns; });
  cut(&out.marine.attitudes, [](const AttitudeRecord& r) { return r.t_ns; });
  cut(&out.marine.rates_of_turn, [](const RateOfTurnRecord& r) { return r.t_ns; });
  out.events.clear();
  for (GnssEvent e : data.events) {
    if (e.t_start_ns > t_end_ns) continue;
    e.t_end_ns = std::min(e.t_end_ns, t_end_ns);
    out.events.push_back(e);
  }
  return out;
}

void WriteDataset(const Dataset& dataset, const std::string& directory) {
  std::error_code ec;
  fs::create_directories(directory, ec);
  if (ec) throw InputError(directory, 0, "", "cannot create directory: " + ec.message());

  const ImuConfig& imu = dataset.imu;
  YAML::Emitter y;
  y.SetDoublePrecision(17);
  y << YAML::BeginMap;
  y << YAML::Key << "name" << YAML::Value << dataset.name;
  y << YAML::Key << "origin" << YAML::Value << YAML::BeginMap;
  y << YAML::Key << "lat_deg" << YAML::Value << dataset.origin.lat_deg;
  y << YAML::Key << "lon_deg" << YAML::Value << dataset.origin.lon_deg;
  y << YAML::Key << "height_m" << YAML::Value << dataset.origin.height_m;
  y << YAML::EndMap;
  y << YAML::Key << "earth" << YAML::Value << YAML::BeginMap;
  y << YAML::Key << "model" << YAML::Value << EarthKindName(dataset.earth.kind);
  if (dataset.earth.kind == EarthKind::kFlat) {
    y << YAML::Key << "gravity_m_s2" << YAML::Value << dataset.earth.gravity_m_s2;
  }
  y << YAML::EndMap;
  y << YAML::Key << "sensors" << YAML::Value << YAML::BeginMap;
  if (dataset.has_imu) {
    y << YAML::Key << "imu" << YAML::Value << YAML::BeginMap;
    y << YAML::Key << "file" << YAML::Value << "imu.csv";
    y << YAML::Key << "rate_hz" << YAML::Value << imu.rate_hz;
    EmitMount(&y, "T_b_i", {imu.q_b_i, imu.p_b_i});
    y << YAML::Key << "gyro_noise_density_rad_s_sqrt_hz" << YAML::Value
      << imu.noise.gyro_noise_density_rad_s_sqrt_hz;
    y << YAML::Key << "accel_noise_density_m_s2_sqrt_hz" << YAML::Value
      << imu.noise.accel_noise_density_m_s2_sqrt_hz;
    y << YAML::Key << "gyro_bias_random_walk_rad_s2_sqrt_hz" << YAML::Value
      << imu.noise.gyro_bias_random_walk_rad_s2_sqrt_hz;
    y << YAML::Key << "accel_bias_random_walk_m_s3_sqrt_hz" << YAML::Value
      << imu.noise.accel_bias_random_walk_m_s3_sqrt_hz;
    y << YAML::Key << "gyro_bias_prior_sigma_rad_s" << YAML::Value
      << imu.gyro_bias_prior_sigma_rad_s;
    y << YAML::Key << "accel_bias_prior_sigma_m_s2" << YAML::Value
      << imu.accel_bias_prior_sigma_m_s2;
    if (imu.gyro_scale_factor_sigma_ppm > 0.0) {
      y << YAML::Key << "gyro_scale_factor_sigma_ppm" << YAML::Value
        << imu.gyro_scale_factor_sigma_ppm;
    }
    if (imu.gyro_misalignment_sigma_mrad > 0.0) {
      y << YAML::Key << "gyro_misalignment_sigma_mrad" << YAML::Value
        << imu.gyro_misalignment_sigma_mrad;
    }
    y << YAML::EndMap;
  }
  if (dataset.has_gnss) {
    const GnssConfig& gnss = dataset.gnss;
    y << YAML::Key << "gnss" << YAML::Value << YAML::BeginMap;
    y << YAML::Key << "file" << YAML::Value << "gnss.csv";
    y << YAML::Key << "lever_arm_b_m" << YAML::Value;
    EmitVector(&y, {gnss.p_b_g.x(), gnss.p_b_g.y(), gnss.p_b_g.z()});
    y << YAML::Key << "baseline_b" << YAML::Value;
    EmitVector(&y, {gnss.baseline_b.x(), gnss.baseline_b.y(), gnss.baseline_b.z()});
    y << YAML::EndMap;
  }
  if (dataset.has_pose_fixes) {
    y << YAML::Key << "pose_fixes" << YAML::Value << YAML::BeginMap;
    y << YAML::Key << "file" << YAML::Value << "pose_fixes.csv";
    EmitMount(&y, "T_b_s", dataset.pose_fix_mount);
    y << YAML::EndMap;
  }
  if (dataset.water_surface) {
    const WaterSurfaceConfig& w = *dataset.water_surface;
    y << YAML::Key << "water_surface" << YAML::Value << YAML::BeginMap;
    y << YAML::Key << "height_m" << YAML::Value << w.height_m;
    y << YAML::Key << "sigma_m" << YAML::Value << w.sigma_m;
    y << YAML::Key << "rate_hz" << YAML::Value << w.rate_hz;
    y << YAML::EndMap;
  }
  // Cameras and LiDARs: their frame lists are written here, their image and scan folders and the
  // maps are referred to where they are, not copied: relative to the dataset folder when they lie
  // inside it (the folder can then be moved as a whole), else by absolute path.
  const fs::path root = fs::weakly_canonical(fs::absolute(directory));
  auto named = [&root](const std::string& p) {
    const fs::path full = fs::weakly_canonical(fs::absolute(p));
    const fs::path inside = full.lexically_relative(root);
    const bool within = !inside.empty() && *inside.begin() != "..";
    return within ? inside.string() : full.string();
  };
  for (const CameraConfig& c : dataset.cameras) {
    y << YAML::Key << c.name << YAML::Value << YAML::BeginMap;
    y << YAML::Key << "images" << YAML::Value << named(c.image_dir);
    y << YAML::Key << "file" << YAML::Value << c.name + ".csv";
    y << YAML::Key << "width_px" << YAML::Value << c.width_px;
    y << YAML::Key << "height_px" << YAML::Value << c.height_px;
    y << YAML::Key << "fx" << YAML::Value << c.fx << YAML::Key << "fy" << YAML::Value << c.fy;
    y << YAML::Key << "cx" << YAML::Value << c.cx << YAML::Key << "cy" << YAML::Value << c.cy;
    if (!c.distortion.empty()) {
      y << YAML::Key << "distortion" << YAML::Value << YAML::Flow << c.distortion;
    }
    EmitMount(&y, "T_b_c", c.T_b_c);
    y << YAML::EndMap;
  }
  for (const LidarConfig& l : dataset.lidars) {
    y << YAML::Key << l.name << YAML::Value << YAML::BeginMap;
    y << YAML::Key << "scans" << YAML::Value << named(l.scan_dir);
    y << YAML::Key << "file" << YAML::Value << l.name + ".csv";
    EmitMount(&y, "T_b_l", l.T_b_l);
    y << YAML::EndMap;
  }
  y << YAML::EndMap;
  if (dataset.dem || dataset.orthophoto) {
    y << YAML::Key << "maps" << YAML::Value << YAML::BeginMap;
    for (const auto& [key, map] :
         {std::make_pair("dem", dataset.dem), std::make_pair("orthophoto", dataset.orthophoto)}) {
      if (!map) continue;
      y << YAML::Key << key << YAML::Value << YAML::BeginMap;
      y << YAML::Key << "file" << YAML::Value << named(map->path);
      if (!map->crs.empty()) y << YAML::Key << "crs" << YAML::Value << map->crs;
      if (!map->vertical_datum.empty()) {
        y << YAML::Key << "vertical_datum" << YAML::Value << map->vertical_datum;
      }
      if (map->viewpoint) {
        y << YAML::Key << "viewpoint" << YAML::Value << YAML::BeginMap;
        y << YAML::Key << "lat_deg" << YAML::Value << map->viewpoint->lat_deg;
        y << YAML::Key << "lon_deg" << YAML::Value << map->viewpoint->lon_deg;
        y << YAML::Key << "height_m" << YAML::Value << map->viewpoint->height_m;
        y << YAML::EndMap;
      }
      if (map->clip_fraction) {
        y << YAML::Key << "clip_fraction" << YAML::Value << *map->clip_fraction;
      }
      y << YAML::EndMap;
    }
    y << YAML::EndMap;
  }
  if (!dataset.groundtruth.empty()) {
    y << YAML::Key << "groundtruth" << YAML::Value << "groundtruth.tum";
  }
  y << YAML::EndMap;
  if (dataset.has_imu) {
    const std::string path = InDir(directory, "imu.csv");
    AtomicFile out_file(path);
    std::ofstream& out = out_file.stream();
    out << "t,wx,wy,wz,ax,ay,az\n";
    std::string line;
    for (const ImuSample& s : dataset.imu_samples) {
      line.clear();
      AppendSeconds(s.t_ns, &line);
      for (int i = 0; i < 3; ++i) AppendCsvDouble(s.gyro_rad_s[i], &line);
      for (int i = 0; i < 3; ++i) AppendCsvDouble(s.accel_m_s2[i], &line);
      line += '\n';
      out << line;
    }
    out_file.Commit();
  }
  if (dataset.has_gnss) {
    const std::string path = InDir(directory, "gnss.csv");
    AtomicFile out_file(path);
    std::ofstream& out = out_file.stream();
    bool any_heading = false;
    for (const GnssFix& f : dataset.gnss_fixes) any_heading = any_heading || f.has_heading;
    out << "t,lat,lon,height,sigma_e,sigma_n,sigma_u"
        << (any_heading ? ",heading_deg,sigma_heading_deg" : "") << '\n';
    for (const GnssFix& f : dataset.gnss_fixes) {
      out << FormatSeconds(f.t_ns) << ',' << FormatDouble(f.lat_deg) << ','
          << FormatDouble(f.lon_deg) << ',' << FormatDouble(f.height_m);
      for (int i = 0; i < 3; ++i) out << ',' << FormatDouble(f.sigma_enu_m[i]);
      if (any_heading) {
        if (f.has_heading) {
          out << ',' << FormatDouble(f.heading_deg) << ',' << FormatDouble(f.sigma_heading_deg);
        } else {
          out << ",,";
        }
      }
      out << '\n';
    }
    out_file.Commit();
  }
  auto write_frames = [&](const std::string& name, const std::vector<SensorFrame>& frames) {
    const std::string path = InDir(directory, name + ".csv");
    AtomicFile out_file(path);
    std::ofstream& out = out_file.stream();
    out << "t,file\n";
    for (const SensorFrame& f : frames) out << FormatSeconds(f.t_ns) << ',' << f.file << '\n';
    out_file.Commit();
  };
  for (size_t k = 0; k < dataset.cameras.size(); ++k) {
    write_frames(dataset.cameras[k].name, dataset.camera_frames.at(k));
  }
  for (size_t k = 0; k < dataset.lidars.size(); ++k) {
    write_frames(dataset.lidars[k].name, dataset.lidar_scans.at(k));
  }
  if (dataset.has_pose_fixes) {
    const std::string path = InDir(directory, "pose_fixes.csv");
    AtomicFile out_file(path);
    std::ofstream& out = out_file.stream();
    out << "t,kind,east,north,up,heading_deg,cov_ee,cov_en,cov_eu,cov_eh,cov_nn,cov_nu,cov_nh,"
           "cov_uu,cov_uh,cov_hh\n";
    constexpr double kDeg = 180.0 / M_PI;
    for (const PoseFix& f : dataset.pose_fixes) {
      out << FormatSeconds(f.t_ns) << ','
          << (f.has_up ? (f.has_heading ? "enuh" : "enu") : (f.has_heading ? "enh" : "en"));
      for (int i = 0; i < 3; ++i) out << ',' << FormatDouble(f.p_w[i]);
      out << ',' << FormatDouble(f.heading_deg);
      for (int i = 0; i < 4; ++i) {
        for (int j = i; j < 4; ++j) {
          const double scale = (i == 3 ? kDeg : 1.0) * (j == 3 ? kDeg : 1.0);
          out << ',' << FormatDouble(f.covariance(i, j) * scale);
        }
      }
      out << '\n';
    }
    out_file.Commit();
  }
  const MarineRecords& marine = dataset.marine;
  if (!marine.headings.empty()) {
    WriteMarineCsv(InDir(directory, kHeadingCsv), "t,heading_deg", marine.headings,
                   [](const HeadingRecord& r) { return FormatDouble(r.heading_deg); });
  }
  if (!marine.courses.empty()) {
    WriteMarineCsv(InDir(directory, kCourseCsv), "t,cog_deg,sog_m_s", marine.courses,
                   [](const CourseRecord& r) {
                     return FormatDouble(r.cog_deg) + ',' + FormatDouble(r.sog_m_s);
                   });
  }
  if (!marine.attitudes.empty()) {
    WriteMarineCsv(InDir(directory, kAttitudeCsv), "t,roll_deg,pitch_deg,yaw_deg", marine.attitudes,
                   [](const AttitudeRecord& r) {
                     return FormatDouble(r.roll_deg) + ',' + FormatDouble(r.pitch_deg) + ',' +
                            (r.yaw_deg ? FormatDouble(*r.yaw_deg) : std::string());
                   });
  }
  if (!marine.rates_of_turn.empty()) {
    WriteMarineCsv(InDir(directory, kRateOfTurnCsv), "t,rate_deg_s", marine.rates_of_turn,
                   [](const RateOfTurnRecord& r) { return FormatDouble(r.rate_deg_s); });
  }
  if (!dataset.groundtruth.empty()) {
    WriteTum(InDir(directory, "groundtruth.tum"), dataset.groundtruth);
  }
  if (!dataset.truth_states.empty()) {
    const std::string path = InDir(directory, kTruthStatesCsv);
    AtomicFile out_file(path);
    std::ofstream& out = out_file.stream();
    const std::vector<std::string> columns = NavStateColumns();
    for (std::size_t i = 0; i < columns.size(); ++i) out << (i > 0 ? "," : "") << columns[i];
    out << '\n';
    std::string line;
    for (const NavState& s : dataset.truth_states) {
      line.clear();
      AppendNavStateRow(s, &line);
      line += '\n';
      out << line;
    }
    out_file.Commit();
  }
  if (!dataset.pose_fix_outliers.empty()) {
    const std::string path = InDir(directory, kPoseFixOutliersCsv);
    AtomicFile out_file(path);
    std::ofstream& out = out_file.stream();
    out << "t\n";
    for (TimeNs t : dataset.pose_fix_outliers) out << FormatSeconds(t) << '\n';
    out_file.Commit();
  }
  if (!dataset.events.empty()) {
    const std::string path = InDir(directory, kEventsCsv);
    AtomicFile out_file(path);
    std::ofstream& out = out_file.stream();
    out << "t_start,t_end,type,de,dn,du\n";
    for (const GnssEvent& e : dataset.events) {
      out << FormatSeconds(e.t_start_ns) << ',' << FormatSeconds(e.t_end_ns) << ',' << e.type;
      for (int i = 0; i < 3; ++i) out << ',' << FormatDouble(e.offset_enu_m[i]);
      out << '\n';
    }
    out_file.Commit();
  }
  // dataset.yaml last: it is what makes the folder a dataset, so a writer killed before this
  // line leaves a folder that does not load rather than one with files missing.
  WriteFileAtomically(InDir(directory, kDatasetYaml), std::string(y.c_str()) + '\n');
}

}  // namespace skerry
