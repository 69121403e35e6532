#include "skerry/io/trajectory.h"

#include <algorithm>
#include <cmath>
#include <fstream>

#include "skerry/core/input_error.h"
#include "skerry/io/atomic_file.h"
#include "skerry/io/csv_reader.h"
#include "skerry/io/state_row_io.h"

namespace skerry {

std::vector<StampedPose> ReadTum(const std::string& path) {
  CsvOptions options;
  options.delimiter = ' ';
  options.header = false;
  options.skip_comments = true;
  CsvReader reader(path, {"t", "x", "y", "z", "qx", "qy", "qz", "qw"}, options);
  std::vector<StampedPose> poses;
  poses.reserve(reader.RowsAtMost());
  while (reader.Next()) {
    StampedPose pose;
    pose.t_ns = reader.GetIncreasingTimeNs(0);
    pose.p_w_b = Eigen::Vector3d(reader.GetDouble(1), reader.GetDouble(2), reader.GetDouble(3));
    pose.q_w_b = ReadUnitQuaternion(reader, 4);
    poses.push_back(pose);
  }
  return poses;
}

void AppendTumRow(const StampedPose& pose, std::string* out) {
  const Eigen::Quaterniond& q = pose.q_w_b;
  AppendSeconds(pose.t_ns, out);
  for (double v : {pose.p_w_b.x(), pose.p_w_b.y(), pose.p_w_b.z(), q.x(), q.y(), q.z(), q.w()}) {
    *out += ' ';
    AppendDouble(v, out);
  }
  *out += '\n';
}

void WriteTumRow(std::ostream* out, const StampedPose& pose) {
  std::string row;
  AppendTumRow(pose, &row);
  *out << row;
}

void WriteTum(const std::string& path, const std::vector<StampedPose>& poses) {
  AtomicFile file(path);
  std::ofstream& out = file.stream();
  out << kTumHeader;
  std::string row;
  for (const StampedPose& pose : poses) {
    row.clear();
    AppendTumRow(pose, &row);
    out << row;
  }
  file.Commit();
}

bool InterpolatePose(const std::vector<StampedPose>& poses,
                     TimeNs t_ns,
                     StampedPose* out,
                     TimeNs max_gap_ns) {
  if (poses.empty() || t_ns < poses.front().t_ns || t_ns > poses.back().t_ns) return false;
  // First pose strictly after t; its predecessor is at or before t.
  const auto it = std::upper_bound(poses.begin(), poses.end(), t_ns,
                                   [](TimeNs t, const StampedPose& p) { return t < p.t_ns; });
  const StampedPose& p0 = *std::prev(it);
  if (p0.t_ns == t_ns) {
    *out = p0;
    return true;
  }
  const StampedPose& p1 = *it;  // exists: t < back().t_ns here
  if (p1.t_ns - p0.t_ns > max_gap_ns) return false;
  const double s = static_cast<double>(t_ns - p0.t_ns) / static_cast<double>(p1.t_ns - p0.t_ns);
  out->t_ns = t_ns;
  out->p_w_b = (1.0 - s) * p0.p_w_b + s * p1.p_w_b;
  out->q_w_b = p0.q_w_b.slerp(s, p1.q_w_b).normalized();  // Eigen's slerp takes the short arc
  return true;
}

}  // namespace skerry
