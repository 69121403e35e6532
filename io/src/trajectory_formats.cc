#include "skerry/io/trajectory_formats.h"

#include <spdlog/spdlog.h>

#include <Eigen/SVD>
#include <array>
#include <cctype>
#include <filesystem>
#include <fstream>

#include "skerry/core/input_error.h"
#include "skerry/io/atomic_file.h"
#include "skerry/io/csv_reader.h"
#include "skerry/io/state_row_io.h"

namespace skerry {
namespace {

namespace fs = std::filesystem;

// ---------------------------------------------------------------------------------------------
// KITTI

const std::vector<std::string>& KittiColumns() {
  static const std::vector<std::string> kColumns = {"r11", "r12", "r13", "tx",  "r21", "r22",
                                                    "r23", "ty",  "r31", "r32", "r33", "tz"};
  return kColumns;
}

// The times sidecar: one time in seconds per line, strictly increasing, one per pose.
void ReadKittiTimes(const std::string& kitti_path, std::vector<StampedPose>* poses) {
  const std::string path = KittiTimesPath(kitti_path);
  CsvOptions options;
  options.delimiter = ' ';
  options.header = false;
  options.skip_comments = true;
  CsvReader reader(path, {"t"}, options);
  std::size_t n = 0;
  while (reader.Next()) {
    if (n == poses->size()) {
      reader.Fail(
          0, "more times than the " + std::to_string(poses->size()) + " poses of " + kitti_path);
    }
    (*poses)[n++].t_ns = reader.GetIncreasingTimeNs(0);
  }
  if (n != poses->size()) {
    throw InputError(path, reader.line(), "t",
                     "truncated: " + std::to_string(n) + " times for the " +
                         std::to_string(poses->size()) + " poses of " + kitti_path);
  }
}

std::vector<StampedPose> ReadKitti(const std::string& path) {
  CsvOptions options;
  options.delimiter = ' ';
  options.header = false;
  options.skip_comments = true;  // evo accepts '#' comments in KITTI files
  CsvReader reader(path, KittiColumns(), options);
  std::vector<StampedPose> poses;
  while (reader.Next()) {
    Eigen::Matrix3d R_w_b;
    StampedPose pose;
    for (int row = 0; row < 3; ++row) {
      for (int col = 0; col < 3; ++col) R_w_b(row, col) = reader.GetDouble(4 * row + col);
      pose.p_w_b[row] = reader.GetDouble(4 * row + 3);
    }
    const double error =
        (R_w_b.transpose() * R_w_b - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    if (!(error <= kKittiRotationTolerance)) {
      reader.FailField("rotation", "not orthonormal (max |R^T R - I| = " + FormatDouble(error) +
                                       ", tolerance " + FormatDouble(kKittiRotationTolerance) +
                                       ")");
    }
    if (R_w_b.determinant() < 0.0) reader.FailField("rotation", "a reflection (det R < 0)");
    // Nearest rotation in the Frobenius norm: U V^T of the SVD (polar decomposition).
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(R_w_b, Eigen::ComputeFullU | Eigen::ComputeFullV);
    pose.q_w_b = Eigen::Quaterniond(svd.matrixU() * svd.matrixV().transpose()).normalized();
    if (pose.q_w_b.w() < 0.0) pose.q_w_b.coeffs() *= -1.0;  // same rotation, w >= 0 for reading
    pose.t_ns = SecondsToNs(static_cast<double>(poses.size()));
    poses.push_back(pose);
  }
  if (fs::exists(KittiTimesPath(path))) {
    ReadKittiTimes(path, &poses);
  } else {
    spdlog::warn("{}: no {} beside it: taking the times as 0, 1, 2, ... s", path,
                 fs::path(KittiTimesPath(path)).filename().string());
  }
  return poses;
}

void WriteKitti(const std::string& path, const std::vector<StampedPose>& poses) {
  AtomicFile out_file(path);
  std::ofstream& out = out_file.stream();
  const std::string times_path = KittiTimesPath(path);
  AtomicFile times_file(times_path);
  std::ofstream& times = times_file.stream();
  for (const StampedPose& pose : poses) {
    const Eigen::Matrix3d R_w_b = pose.q_w_b.normalized().toRotationMatrix();
    for (int row = 0; row < 3; ++row) {
      for (int col = 0; col < 3; ++col) out << FormatDouble(R_w_b(row, col)) << ' ';
      out << FormatDouble(pose.p_w_b[row]) << (row < 2 ? ' ' : '\n');
    }
    times << FormatSeconds(pose.t_ns) << '\n';
  }
  out_file.Commit();
  times_file.Commit();
}

// ---------------------------------------------------------------------------------------------
// EuRoC CSV

constexpr int kEurocPoseColumns = 8;

// Accepted names of the 8 pose columns, per column: ASL's, and the short spelling of the
// open_vins / Kimera ground-truth files. Names are compared after trimming.
const std::array<std::vector<std::string>, kEurocPoseColumns>& EurocAcceptedNames() {
  static const std::array<std::vector<std::string>, kEurocPoseColumns> kNames = {{
      {"timestamp", "timestamp [ns]", "time(ns)"},
      {"p_RS_R_x [m]", "px"},
      {"p_RS_R_y [m]", "py"},
      {"p_RS_R_z [m]", "pz"},
      {"q_RS_w []", "qw"},
      {"q_RS_x []", "qx"},
      {"q_RS_y []", "qy"},
      {"q_RS_z []", "qz"},
  }};
  return kNames;
}

}  // namespace

const std::vector<std::string>& EurocAslStateColumns() {
  static const std::vector<std::string> kColumns = {"timestamp",
                                                    "p_RS_R_x [m]",
                                                    "p_RS_R_y [m]",
                                                    "p_RS_R_z [m]",
                                                    "q_RS_w []",
                                                    "q_RS_x []",
                                                    "q_RS_y []",
                                                    "q_RS_z []",
                                                    "v_RS_R_x [m s^-1]",
                                                    "v_RS_R_y [m s^-1]",
                                                    "v_RS_R_z [m s^-1]",
                                                    "b_w_RS_S_x [rad s^-1]",
                                                    "b_w_RS_S_y [rad s^-1]",
                                                    "b_w_RS_S_z [rad s^-1]",
                                                    "b_a_RS_S_x [m s^-2]",
                                                    "b_a_RS_S_y [m s^-2]",
                                                    "b_a_RS_S_z [m s^-2]"};
  return kColumns;
}

namespace {

std::string Trimmed(const std::string& s) {
  const std::size_t first = s.find_first_not_of(" \t\r");
  if (first == std::string::npos) return "";
  const std::size_t last = s.find_last_not_of(" \t\r");
  return s.substr(first, last - first + 1);
}

// The column names of the header row (first non-blank line), checked against the accepted
// spellings of the 8 pose columns; more columns may follow under any names. CsvReader then
// enforces that every row has exactly as many fields.
std::vector<std::string> ReadEurocHeader(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, 0, "", "cannot open file");
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (!Trimmed(line).empty()) break;
  }
  std::string header = Trimmed(line);
  if (header.empty()) throw InputError(path, 0, "", "empty file: missing header row");
  if (std::isdigit(static_cast<unsigned char>(header.front())) != 0 || header.front() == '-') {
    throw InputError(path, line_number, "header",
                     "missing header row (expected \"#timestamp,p_RS_R_x [m],...\"; it fixes "
                     "the quaternion order)");
  }
  if (header.front() == '#') header.erase(0, 1);
  std::vector<std::string> names;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = header.find(',', start);
    names.push_back(Trimmed(header.substr(start, comma - start)));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  const auto& accepted = EurocAcceptedNames();
  for (int col = 0; col < kEurocPoseColumns; ++col) {
    const std::string expected = "\"" + accepted[col].front() + "\"";
    if (col >= static_cast<int>(names.size())) {
      throw InputError(path, line_number, accepted[col].front(),
                       "header has only " + std::to_string(names.size()) +
                           " columns; a EuRoC trajectory needs at least 8 (column " +
                           std::to_string(col + 1) + ": " + expected + ")");
    }
    bool ok = false;
    for (const std::string& name : accepted[col]) ok = ok || names[col] == name;
    if (!ok) {
      throw InputError(path, line_number, accepted[col].front(),
                       "unexpected header column " + std::to_string(col + 1) + " \"" + names[col] +
                           "\", expected " + expected);
    }
  }
  return names;
}

std::vector<StampedPose> ReadEuroc(const std::string& path) {
  CsvReader reader(path, ReadEurocHeader(path));
  std::vector<StampedPose> poses;
  while (reader.Next()) {
    StampedPose pose;
    pose.t_ns = reader.GetInt64(0);
    reader.CheckIncreasing(0, pose.t_ns);
    pose.p_w_b = Eigen::Vector3d(reader.GetDouble(1), reader.GetDouble(2), reader.GetDouble(3));
    pose.q_w_b = ReadUnitQuaternionWxyz(reader, 4);
    // Velocity, biases or whatever follows: not kept, but they must be numbers too.
    for (int col = kEurocPoseColumns; col < reader.column_count(); ++col) reader.GetDouble(col);
    poses.push_back(pose);
  }
  return poses;
}

void WriteEurocHeader(std::ofstream& out, int columns) {
  const std::vector<std::string>& names = EurocAslStateColumns();
  for (int col = 0; col < columns; ++col) out << (col > 0 ? "," : "#") << names[col];
  out << '\n';
}

void WriteEurocPose(std::ofstream& out,
                    TimeNs t_ns,
                    const Eigen::Vector3d& p_w_b,
                    const Eigen::Quaterniond& q_w_b) {
  out << t_ns;
  for (int i = 0; i < 3; ++i) out << ',' << FormatDouble(p_w_b[i]);
  for (double c : {q_w_b.w(), q_w_b.x(), q_w_b.y(), q_w_b.z()}) out << ',' << FormatDouble(c);
}

void WriteEuroc(const std::string& path, const std::vector<StampedPose>& poses) {
  AtomicFile out_file(path);
  std::ofstream& out = out_file.stream();
  WriteEurocHeader(out, kEurocPoseColumns);
  for (const StampedPose& pose : poses) {
    WriteEurocPose(out, pose.t_ns, pose.p_w_b, pose.q_w_b);
    out << '\n';
  }
  out_file.Commit();
}

void WriteEuroc(const std::string& path, const std::vector<EstimateRecord>& records) {
  AtomicFile out_file(path);
  std::ofstream& out = out_file.stream();
  WriteEurocHeader(out, static_cast<int>(EurocAslStateColumns().size()));
  for (const EstimateRecord& record : records) {
    const NavState& s = record.state;
    WriteEurocPose(out, s.t_ns, s.p_w_b, s.q_w_b);
    for (const Eigen::Vector3d* v : {&s.v_w, &s.bg, &s.ba}) {
      for (int i = 0; i < 3; ++i) out << ',' << FormatDouble((*v)[i]);
    }
    out << '\n';
  }
  out_file.Commit();
}

}  // namespace

TrajectoryFormat ParseTrajectoryFormat(const std::string& name) {
  if (name == "tum") return TrajectoryFormat::kTum;
  if (name == "kitti") return TrajectoryFormat::kKitti;
  if (name == "euroc") return TrajectoryFormat::kEuroc;
  throw InputError(kCommandLine, 0, "format",
                   "\"" + name + "\" is not a trajectory format (tum, kitti or euroc)");
}

std::string TrajectoryFormatName(TrajectoryFormat format) {
  switch (format) {
    case TrajectoryFormat::kTum:
      return "tum";
    case TrajectoryFormat::kKitti:
      return "kitti";
    case TrajectoryFormat::kEuroc:
      return "euroc";
  }
  return "?";
}

TrajectoryFormat TrajectoryFormatFromPath(const std::string& path) {
  const std::string ext = fs::path(path).extension().string();
  if (ext == ".tum" || ext == ".txt") return TrajectoryFormat::kTum;
  if (ext == ".kitti") return TrajectoryFormat::kKitti;
  if (ext == ".csv") return TrajectoryFormat::kEuroc;
  throw InputError(path, 0, "extension",
                   "cannot tell the trajectory format from \"" + ext +
                       "\" (.tum or .txt: TUM, .kitti: KITTI, .csv: EuRoC); give the format");
}

TrajectoryFormat TrajectoryFormatFor(const std::string& path, const std::string& name) {
  return name.empty() ? TrajectoryFormatFromPath(path) : ParseTrajectoryFormat(name);
}

bool IsStatesCsv(const std::string& path) {
  std::ifstream in(path);
  std::string line;
  return static_cast<bool>(std::getline(in, line)) && line.rfind("t,px", 0) == 0;
}

std::string KittiTimesPath(const std::string& kitti_path) { return kitti_path + ".times"; }

std::vector<StampedPose> ReadTrajectory(const std::string& path, TrajectoryFormat format) {
  switch (format) {
    case TrajectoryFormat::kTum:
      return ReadTum(path);
    case TrajectoryFormat::kKitti:
      return ReadKitti(path);
    case TrajectoryFormat::kEuroc:
      return ReadEuroc(path);
  }
  return {};
}

void WriteTrajectory(const std::string& path,
                     const std::vector<StampedPose>& poses,
                     TrajectoryFormat format) {
  switch (format) {
    case TrajectoryFormat::kTum:
      WriteTum(path, poses);
      return;
    case TrajectoryFormat::kKitti:
      WriteKitti(path, poses);
      return;
    case TrajectoryFormat::kEuroc:
      WriteEuroc(path, poses);
      return;
  }
}

void WriteTrajectory(const std::string& path,
                     const std::vector<EstimateRecord>& records,
                     TrajectoryFormat format) {
  if (format == TrajectoryFormat::kEuroc) {
    WriteEuroc(path, records);
  } else {
    WriteTrajectory(path, ToPoses(records), format);
  }
}

}  // namespace skerry
