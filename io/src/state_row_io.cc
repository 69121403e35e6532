#include "skerry/io/state_row_io.h"

#include <cmath>

namespace skerry {
namespace {

Eigen::Quaterniond CheckedNormalised(const CsvReader& reader,
                                     const Eigen::Quaterniond& q,
                                     int w_col) {
  if (!IsUnitQuaternion(q)) {
    reader.Fail(w_col, "quaternion is not unit (norm " + FormatDouble(q.norm()) + ")");
  }
  return q.normalized();
}

Eigen::Vector3d ReadVector3(const CsvReader& reader, int first_col) {
  return Eigen::Vector3d(reader.GetDouble(first_col), reader.GetDouble(first_col + 1),
                         reader.GetDouble(first_col + 2));
}

void AppendVector3(const Eigen::Vector3d& v, std::string* out) {
  for (int i = 0; i < 3; ++i) {
    *out += ',';
    AppendDouble(v[i], out);
  }
}

}  // namespace

bool IsUnitQuaternion(const Eigen::Quaterniond& q) {
  return std::fabs(q.norm() - 1.0) < kQuaternionNormTolerance;
}

Eigen::Quaterniond ReadUnitQuaternion(const CsvReader& reader, int first_col) {
  // Eigen's constructor takes (w, x, y, z).
  const Eigen::Quaterniond q(reader.GetDouble(first_col + 3), reader.GetDouble(first_col),
                             reader.GetDouble(first_col + 1), reader.GetDouble(first_col + 2));
  return CheckedNormalised(reader, q, first_col + 3);
}

Eigen::Quaterniond ReadUnitQuaternionWxyz(const CsvReader& reader, int first_col) {
  const Eigen::Quaterniond q(reader.GetDouble(first_col), reader.GetDouble(first_col + 1),
                             reader.GetDouble(first_col + 2), reader.GetDouble(first_col + 3));
  return CheckedNormalised(reader, q, first_col);
}

std::vector<std::string> NavStateColumns() {
  return {"t",  "px", "py",  "pz",  "qx",  "qy",  "qz",  "qw", "vx",
          "vy", "vz", "bgx", "bgy", "bgz", "bax", "bay", "baz"};
}

NavState ReadNavStateRow(CsvReader* reader) {
  NavState state;
  state.t_ns = reader->GetIncreasingTimeNs(0);
  state.p_w_b = ReadVector3(*reader, 1);
  state.q_w_b = ReadUnitQuaternion(*reader, 4);
  state.v_w = ReadVector3(*reader, 8);
  state.bg = ReadVector3(*reader, 11);
  state.ba = ReadVector3(*reader, 14);
  return state;
}

void AppendNavStateRow(const NavState& state, std::string* out) {
  AppendSeconds(state.t_ns, out);
  AppendVector3(state.p_w_b, out);
  const Eigen::Quaterniond& q = state.q_w_b;
  for (double c : {q.x(), q.y(), q.z(), q.w()}) {
    *out += ',';
    AppendDouble(c, out);
  }
  AppendVector3(state.v_w, out);
  AppendVector3(state.bg, out);
  AppendVector3(state.ba, out);
}

std::string FormatNavStateRow(const NavState& state) {
  std::string out;
  AppendNavStateRow(state, &out);
  return out;
}

}  // namespace skerry
