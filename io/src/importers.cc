#include "skerry/io/importers.h"

#include <spdlog/spdlog.h>
#include <yaml-cpp/yaml.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>
#include <stdexcept>

#include "skerry/core/earth_model.h"
#include "skerry/core/input_error.h"
#include "skerry/io/csv_reader.h"
#include "skerry/io/state_row_io.h"
#include "skerry/io/trajectory_formats.h"
#include "yaml_util.h"

namespace skerry {
namespace {

namespace fs = std::filesystem;

std::string InDir(const std::string& directory, const std::string& file) {
  return (fs::path(directory) / file).string();
}

// ---------------------------------------------------------------------------------------------
// EuRoC

// imu0_sensor.yaml (OpenCV FileStorage flavour): T_BS, rate and noise densities.
void ReadEurocImuYaml(const std::string& path, ImuConfig* imu) {
  std::string text = yaml_util::ReadFileText(path);
  // OpenCV writes a `%YAML:1.0` directive that yaml-cpp rejects. Blank it (keeping the newline)
  // so that line numbers in errors still match the file.
  if (text.rfind("%YAML", 0) == 0) {
    const std::size_t eol = text.find('\n');
    text.erase(0, eol == std::string::npos ? text.size() : eol);
  }
  const YAML::Node root = yaml_util::Parse(text, path);
  const yaml_util::Reader yaml(path);
  yaml.RequireMap(root, "");

  const YAML::Node t_bs = yaml.Require(root, "", "T_BS");
  const YAML::Node rows = yaml.Require(t_bs, "T_BS", "rows");
  const YAML::Node cols = yaml.Require(t_bs, "T_BS", "cols");
  if (yaml.Double(rows, "T_BS.rows") != 4.0) yaml.Fail(rows, "T_BS.rows", "expected 4");
  if (yaml.Double(cols, "T_BS.cols") != 4.0) yaml.Fail(cols, "T_BS.cols", "expected 4");
  const YAML::Node data = yaml.Require(t_bs, "T_BS", "data");
  const std::vector<double> v = yaml.Doubles(data, "T_BS.data", 16);
  Eigen::Matrix4d T_b_s;  // row-major in the file
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) T_b_s(r, c) = v[4 * r + c];
  }
  const Eigen::Matrix3d R_b_s = T_b_s.topLeftCorner<3, 3>();
  if ((R_b_s.transpose() * R_b_s - Eigen::Matrix3d::Identity()).norm() > 1e-6 ||
      R_b_s.determinant() < 0.0 || (T_b_s.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() > 0.0) {
    yaml.Fail(data, "T_BS.data", "not a rigid transform");
  }
  imu->q_b_i = Eigen::Quaterniond(R_b_s).normalized();
  imu->p_b_i = T_b_s.topRightCorner<3, 1>();

  auto positive = [&](const std::string& key) {
    return yaml.PositiveDouble(yaml.Require(root, "", key), key);
  };
  imu->rate_hz = positive("rate_hz");
  imu->noise.gyro_noise_density_rad_s_sqrt_hz = positive("gyroscope_noise_density");
  imu->noise.gyro_bias_random_walk_rad_s2_sqrt_hz = positive("gyroscope_random_walk");
  imu->noise.accel_noise_density_m_s2_sqrt_hz = positive("accelerometer_noise_density");
  imu->noise.accel_bias_random_walk_m_s3_sqrt_hz = positive("accelerometer_random_walk");
}

std::vector<ImuSample> ReadEurocImu(const std::string& path) {
  CsvReader reader(
      path, {"timestamp [ns]", "w_RS_S_x [rad s^-1]", "w_RS_S_y [rad s^-1]", "w_RS_S_z [rad s^-1]",
             "a_RS_S_x [m s^-2]", "a_RS_S_y [m s^-2]", "a_RS_S_z [m s^-2]"});
  std::vector<ImuSample> samples;
  while (reader.Next()) {
    ImuSample s;
    s.t_ns = reader.GetInt64(0);
    reader.CheckIncreasing(0, s.t_ns);
    for (int i = 0; i < 3; ++i) {
      s.gyro_rad_s[i] = reader.GetDouble(1 + i);
      s.accel_m_s2[i] = reader.GetDouble(4 + i);
    }
    samples.push_back(s);
  }
  if (samples.empty()) {
    throw InputError(path, 0, "timestamp [ns]", "no IMU samples: the file has a header only");
  }
  return samples;
}

// Ground truth: time, p, q (w, x, y, z), v, bg, ba, the body in the Vicon world, its velocity
// there, and the IMU biases (IMU frame). ASL's own header or the short one of open_vins/Kimera.
std::vector<NavState> ReadEurocGroundTruth(const std::string& path, bool asl_header) {
  const std::vector<std::string> columns =
      asl_header ? EurocAslStateColumns()
                 : std::vector<std::string>{"time(ns)", "px",  "py",  "pz",  "qw", "qx",
                                            "qy",       "qz",  "vx",  "vy",  "vz", "bwx",
                                            "bwy",      "bwz", "bax", "bay", "baz"};
  CsvReader reader(path, columns);
  std::vector<NavState> states;
  while (reader.Next()) {
    NavState s;
    s.t_ns = reader.GetInt64(0);
    reader.CheckIncreasing(0, s.t_ns);
    for (int i = 0; i < 3; ++i) {
      s.p_w_b[i] = reader.GetDouble(1 + i);
      s.v_w[i] = reader.GetDouble(8 + i);
      s.bg[i] = reader.GetDouble(11 + i);
      s.ba[i] = reader.GetDouble(14 + i);
    }
    s.q_w_b = ReadUnitQuaternionWxyz(reader, 4);
    states.push_back(s);
  }
  return states;
}

// The files of one EuRoC sequence, in either layout.
struct EurocFiles {
  std::string name;
  std::string imu;
  std::string imu_yaml;
  std::string groundtruth;  ///< empty when the sequence has none
  bool asl_header = true;
};

EurocFiles FindEurocFiles(const std::string& dir) {
  const fs::path d = fs::absolute(dir).lexically_normal();
  const fs::path stem = d.filename().empty() ? d.parent_path() : d;
  EurocFiles f;
  fs::path mav0;
  if (fs::is_directory(d / "mav0")) {
    mav0 = d / "mav0";
    f.name = "euroc_" + stem.filename().string();
  } else if (fs::is_regular_file(d / "imu0" / "data.csv")) {
    mav0 = d;
    f.name = "euroc_" + stem.parent_path().filename().string();
  }
  if (!mav0.empty()) {
    f.imu = (mav0 / "imu0" / "data.csv").string();
    f.imu_yaml = (mav0 / "imu0" / "sensor.yaml").string();
    const fs::path gt = mav0 / "state_groundtruth_estimate0" / "data.csv";
    if (fs::is_regular_file(gt)) f.groundtruth = gt.string();
    if (!fs::is_regular_file(f.imu)) throw InputError(f.imu, 0, "file", "missing");
    if (!fs::is_regular_file(f.imu_yaml)) throw InputError(f.imu_yaml, 0, "file", "missing");
    return f;
  }
  // The flattened copy: imu0_data.csv, imu0_sensor.yaml and one other CSV, the ground truth.
  if (!fs::is_regular_file(d / "imu0_data.csv")) {
    throw InputError(dir, 0, "",
                     "not a EuRoC sequence: expected mav0/imu0/data.csv (the ASL format) or "
                     "imu0_data.csv beside imu0_sensor.yaml");
  }
  f.imu = (d / "imu0_data.csv").string();
  f.imu_yaml = (d / "imu0_sensor.yaml").string();
  if (!fs::is_regular_file(f.imu_yaml)) throw InputError(f.imu_yaml, 0, "file", "missing");
  f.asl_header = false;
  std::vector<fs::path> csvs;
  for (const auto& entry : fs::directory_iterator(d)) {
    if (entry.path().extension() == ".csv" && entry.path().filename() != "imu0_data.csv") {
      csvs.push_back(entry.path());
    }
  }
  std::sort(csvs.begin(), csvs.end());
  if (csvs.size() > 1) {
    std::string names;
    for (const fs::path& p : csvs) names += (names.empty() ? "" : ", ") + p.filename().string();
    throw InputError(dir, 0, "",
                     "more than one ground-truth CSV beside imu0_data.csv (" + names + ")");
  }
  if (!csvs.empty()) {
    f.groundtruth = csvs.front().string();
    f.name = "euroc_" + csvs.front().stem().string();
  } else {
    f.name = "euroc_" + stem.filename().string();
  }
  return f;
}

// ---------------------------------------------------------------------------------------------
// Husky (robot_localization test1.bag)

// The row without its first field (bag_time, the recorder's arrival time): two rows with equal
// remainders are the same message recorded twice.
std::string WithoutBagTime(const std::string& line) {
  const std::size_t comma = line.find(',');
  return comma == std::string::npos ? std::string() : line.substr(comma + 1);
}

// Reads the `stamp` column (header time) and applies the duplicate policy: a row whose stamp
// equals the previous one and whose content (all but bag_time) is identical is a duplicate
// message and is dropped with a warning (returns false); any other non-increasing stamp throws
// InputError. We never sort: reordering would hide a broken clock.
bool ReadHuskyStamp(CsvReader* reader, std::string* last_content, TimeNs* last_t, TimeNs* t) {
  *t = reader->GetTimeNs(1);
  std::string content = WithoutBagTime(reader->raw_line());
  if (!last_content->empty() && *t == *last_t && content == *last_content) {
    spdlog::warn("{}:{}: dropping duplicate of the previous message (stamp {})", reader->file(),
                 reader->line(), FormatSeconds(*t));
    return false;
  }
  reader->CheckIncreasing(1, *t);
  *last_content = std::move(content);
  *last_t = *t;
  return true;
}

void CheckFrame(const CsvReader& reader, int col, std::string* frame) {
  const std::string& f = reader.GetString(col);
  if (frame->empty()) {
    *frame = f;
  } else if (f != *frame) {
    reader.Fail(col, "frame changed from \"" + *frame + "\" to \"" + f + "\"");
  }
}

}  // namespace

Dataset ImportEuroc(const std::string& dir) {
  const EurocFiles files = FindEurocFiles(dir);
  Dataset dataset;
  dataset.name = files.name;
  dataset.directory = dir;
  dataset.origin = kEurocOrigin;
  dataset.earth.kind = EarthKind::kFlat;
  dataset.earth.gravity_m_s2 =
      EarthModel(kEurocOrigin).Gravity(Eigen::Vector3d::Zero()).norm();  // 9.8068 m/s^2
  // Body = EuRoC's body frame; T_BS in imu0/sensor.yaml places the IMU (S) in it.
  ReadEurocImuYaml(files.imu_yaml, &dataset.imu);
  dataset.imu_samples = ReadEurocImu(files.imu);
  if (!files.groundtruth.empty()) {
    dataset.truth_states = ReadEurocGroundTruth(files.groundtruth, files.asl_header);
  } else {
    spdlog::warn("{}: no ground truth (state_groundtruth_estimate0) in this sequence", dir);
  }
  for (const NavState& s : dataset.truth_states) {
    StampedPose pose;
    pose.t_ns = s.t_ns;
    pose.p_w_b = s.p_w_b;
    pose.q_w_b = s.q_w_b;
    dataset.groundtruth.push_back(pose);
  }
  dataset.has_gnss = false;
  return dataset;
}

void AddFixesFromGroundTruth(
    double rate_hz, double sigma_m, std::uint64_t seed, Dataset* data, double duration_s) {
  if (!(rate_hz > 0.0 && rate_hz <= 1e6) || !(sigma_m > 0.0 && std::isfinite(sigma_m))) {
    throw std::invalid_argument("AddFixesFromGroundTruth: rate " + std::to_string(rate_hz) +
                                " Hz and sigma " + std::to_string(sigma_m) +
                                " m: expected a rate in (0, 1e6] and a sigma > 0");
  }
  const std::vector<StampedPose>& truth = data->groundtruth;
  data->gnss_fixes.clear();
  data->has_gnss = true;
  data->gnss.p_b_g = Eigen::Vector3d::Zero();
  if (truth.empty()) return;
  // Box-Muller on the top 53 bits of std::mt19937_64 (std::normal_distribution is
  // implementation-defined).
  std::mt19937_64 engine(seed);
  bool has_spare = false;
  double spare = 0.0;
  auto normal = [&]() {
    if (has_spare) {
      has_spare = false;
      return spare;
    }
    const double u1 = (static_cast<double>(engine() >> 11) + 1.0) * 0x1.0p-53;
    const double u2 = static_cast<double>(engine() >> 11) * 0x1.0p-53;
    const double r = std::sqrt(-2.0 * std::log(u1));
    spare = r * std::sin(2.0 * M_PI * u2);
    has_spare = true;
    return r * std::cos(2.0 * M_PI * u2);
  };
  const LocalFrame frame(data->origin);
  const TimeNs period_ns = SecondsToNs(1.0 / rate_hz);
  const TimeNs t_end =
      duration_s > 0.0 ? truth.front().t_ns + SecondsToNs(duration_s) : truth.back().t_ns;
  for (TimeNs t = truth.front().t_ns; t <= t_end; t += period_ns) {
    StampedPose pose;
    if (!InterpolatePose(truth, t, &pose)) break;
    GnssFix fix;
    fix.t_ns = t;
    const double e = normal(), n = normal(), u = normal();
    fix.p_w = pose.p_w_b + sigma_m * Eigen::Vector3d(e, n, u);
    const Eigen::Vector3d llh = frame.ToGeodetic(fix.p_w);
    fix.lat_deg = llh.x();
    fix.lon_deg = llh.y();
    fix.height_m = llh.z();
    fix.sigma_enu_m = Eigen::Vector3d::Constant(sigma_m);
    data->gnss_fixes.push_back(fix);
  }
}

Dataset ImportHusky(const std::string& husky_dir) {
  Dataset dataset;
  dataset.name = "husky_test1";
  dataset.directory = husky_dir;

  // IMU: a Microstrain 3DM-GX2 on frame imu_link. Extrinsic from robot_localization's
  // test/test_ekf_localization_node_bag1.test, which plays this bag with
  //   static_transform_publisher 0 -0.3 0.52 -1.570796327 0 1.570796327 base_link imu_link
  // (x y z yaw pitch roll): R_b_i = Rz(-pi/2) Ry(0) Rx(pi/2), so imu y = body up, which the data
  // confirms (mean ay = +9.79 m/s^2 at rest). base_link is FLU.
  ImuConfig& imu = dataset.imu;
  imu.rate_hz = 30.0;
  imu.q_b_i = Eigen::Quaterniond(Eigen::AngleAxisd(-M_PI / 2.0, Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(M_PI / 2.0, Eigen::Vector3d::UnitX()));
  imu.p_b_i = Eigen::Vector3d(0.0, -0.3, 0.52);
  // No noise figures come with the bag (the launch file calls this IMU "slightly broken").
  // Assumed, deliberately loose: gyro white noise from the ~0.027 rad/s sample spread at 30 Hz,
  // accelerometer from the ~0.5 m/s^2 spread (vibration on a skid-steer robot).
  imu.noise.gyro_noise_density_rad_s_sqrt_hz = 5e-3;
  imu.noise.accel_noise_density_m_s2_sqrt_hz = 0.1;
  imu.noise.gyro_bias_random_walk_rad_s2_sqrt_hz = 1e-4;
  imu.noise.accel_bias_random_walk_m_s3_sqrt_hz = 1e-3;
  imu.gyro_bias_prior_sigma_rad_s = 0.01;
  imu.accel_bias_prior_sigma_m_s2 = 0.2;

  {
    // imu_data.csv: we use `stamp` (the message header time); qx..qw (the IMU's own attitude
    // output) is not a raw measurement and is ignored.
    CsvReader reader(
        InDir(husky_dir, "imu_data.csv"),
        {"bag_time", "stamp", "frame", "qx", "qy", "qz", "qw", "wx", "wy", "wz", "ax", "ay", "az"});
    std::string frame, last_content;
    TimeNs last_t = 0;
    while (reader.Next()) {
      CheckFrame(reader, 2, &frame);
      ImuSample s;
      if (!ReadHuskyStamp(&reader, &last_content, &last_t, &s.t_ns)) continue;
      for (int i = 0; i < 3; ++i) {
        s.gyro_rad_s[i] = reader.GetDouble(7 + i);
        s.accel_m_s2[i] = reader.GetDouble(10 + i);
      }
      dataset.imu_samples.push_back(s);
    }
  }

  // GNSS: sensor_msgs/NavSatFix. Rows with status < 0 (STATUS_NO_FIX) are skipped before their
  // numbers are read (they may be NaN). position_covariance is ENU; its diagonal gives the
  // sigmas; COVARIANCE_TYPE_UNKNOWN (0) is refused rather than guessed. NavSatFix defines
  // `altitude` as above the WGS84 ellipsoid and we take it so; should the receiver have written
  // height above MSL instead (7 m here, where the geoid is ~28 m below the ellipsoid), the error
  // is a constant vertical offset that the origin (the first fix) absorbs. Beware: the altitude
  // of this receiver wanders from +7 m to -28 m during the run while claiming sigma_u = 1.8 m;
  // we pass the receiver's figures through unchanged. The antenna lever arm is not given for
  // this run: zero.
  dataset.has_gnss = true;
  {
    CsvReader reader(InDir(husky_dir, "fix.csv"),
                     {"bag_time", "stamp", "frame", "status", "service", "lat", "lon", "alt",
                      "cov_xx", "cov_yy", "cov_zz", "cov_type"});
    std::string frame, last_content;
    TimeNs last_t = 0;
    bool have_origin = false;
    std::vector<GnssFix> fixes;
    while (reader.Next()) {
      CheckFrame(reader, 2, &frame);
      if (reader.GetInt64(3) < 0) continue;
      GnssFix fix;
      if (!ReadHuskyStamp(&reader, &last_content, &last_t, &fix.t_ns)) continue;
      fix.lat_deg = reader.GetDouble(5);
      fix.lon_deg = reader.GetDouble(6);
      fix.height_m = reader.GetDouble(7);
      if (std::fabs(fix.lat_deg) > 90.0) reader.Fail(5, "latitude outside [-90, 90]");
      if (std::fabs(fix.lon_deg) > 180.0) reader.Fail(6, "longitude outside [-180, 180]");
      if (reader.GetInt64(11) == 0) reader.Fail(11, "covariance type unknown");
      for (int i = 0; i < 3; ++i) {
        const double var = reader.GetDouble(8 + i);
        if (!(var > 0.0)) reader.Fail(8 + i, "variance must be positive");
        fix.sigma_enu_m[i] = std::sqrt(var);
      }
      if (!have_origin) {
        dataset.origin = GeoOrigin{fix.lat_deg, fix.lon_deg, fix.height_m};
        have_origin = true;
      }
      fixes.push_back(fix);
    }
    if (!have_origin) throw InputError(reader.file(), 0, "status", "no valid fix");
    const LocalFrame frame_w(dataset.origin);
    for (GnssFix& fix : fixes) fix.p_w = frame_w.ToEnu(fix.lat_deg, fix.lon_deg, fix.height_m);
    dataset.gnss_fixes = std::move(fixes);
  }
  return dataset;
}

}  // namespace skerry
