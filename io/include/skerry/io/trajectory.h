#pragma once
/// \file
/// Stamped poses and the TUM trajectory format (`t x y z qx qy qz qw`, seconds, body pose in the
/// local ENU frame).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <ostream>
#include <string>
#include <vector>

#include "skerry/core/time.h"

namespace skerry {

struct StampedPose {
  TimeNs t_ns = 0;
  Eigen::Vector3d p_w_b = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_w_b = Eigen::Quaterniond::Identity();
};

/// Reads a TUM file; '#' lines are comments. Throws InputError naming file, line and field on
/// malformed rows, NaN, non-unit quaternions or non-increasing time.
std::vector<StampedPose> ReadTum(const std::string& path);

/// Writes a TUM file with nanosecond-exact seconds (9 decimals).
void WriteTum(const std::string& path, const std::vector<StampedPose>& poses);
/// The header line WriteTum writes, and one pose as a row of it.
inline constexpr const char* kTumHeader = "# t x y z qx qy qz qw\n";
void WriteTumRow(std::ostream* out, const StampedPose& pose);
/// The row of WriteTumRow appended to `out` (with its line end).
void AppendTumRow(const StampedPose& pose, std::string* out);

/// Pose at time t by linear/slerp interpolation between neighbours; false outside the span or
/// across a gap longer than max_gap_ns.
bool InterpolatePose(const std::vector<StampedPose>& poses,
                     TimeNs t_ns,
                     StampedPose* out,
                     TimeNs max_gap_ns = 1'000'000'000);

}  // namespace skerry
