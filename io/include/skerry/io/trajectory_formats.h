#pragma once
/// \file
/// Trajectories in the three text formats that the `evo` tools (evo_traj, evo_ape, evo_rpe) and
/// most SLAM benchmarks read. Every pose is T_w_b: the body in the local ENU frame.
///
/// - TUM (`.tum`, `.txt`): `t x y z qx qy qz qw`, space separated, seconds, '#' comments (see
///   trajectory.h; written with 9-decimal seconds).
/// - KITTI (`.kitti`): one line per pose, the 12 numbers of the top three rows of the 4x4 matrix
///   T_w_b, row by row (`r11 r12 r13 tx r21 r22 r23 ty r31 r32 r33 tz`), space separated, no
///   time stamps and no header. The times live in a sidecar `<path>.times` in the style of KITTI
///   odometry's times.txt: one time in seconds per line (9 decimals when we write it). When the
///   sidecar is missing the times are taken as 0, 1, 2, ... s (one second per pose) and a warning
///   says so. Rotations read must be orthonormal to kKittiRotationTolerance and are then
///   re-orthonormalised (the nearest rotation, by SVD).
/// - EuRoC CSV (`.csv`, as ASL's `state_groundtruth_estimate0/data.csv`): header
///   `#timestamp,p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],q_RS_z []`
///   optionally followed by more columns (ASL adds velocity and biases); integer nanosecond
///   stamps, quaternion w first. The reader also accepts `timestamp [ns]` as the first name and
///   the short spelling `#time(ns),px,py,pz,qw,qx,qy,qz,...` (open_vins / Kimera ground truth).
///   A header is required: it is what pins the quaternion order.
///
/// Readers throw InputError naming file, line and field on wrong column counts, non-numbers,
/// NaN/Inf, non-increasing time, truncated rows and non-unit quaternions (or non-orthonormal
/// rotations).

#include <string>
#include <vector>

#include "skerry/io/estimate_io.h"
#include "skerry/io/trajectory.h"

namespace skerry {

enum class TrajectoryFormat { kTum, kKitti, kEuroc };

/// Tolerance on max |R^T R - I| (element-wise) for KITTI rotations read from files.
constexpr double kKittiRotationTolerance = 1e-3;

/// "tum", "kitti" or "euroc". Throws InputError (file kCommandLine, field "format")
/// otherwise.
TrajectoryFormat ParseTrajectoryFormat(const std::string& name);

/// "tum", "kitti" or "euroc".
std::string TrajectoryFormatName(TrajectoryFormat format);

/// The 17 columns of ASL's EuRoC state ground truth (`state_groundtruth_estimate0/data.csv`):
/// timestamp, p_RS_R, q_RS (w first), v_RS_R, b_w_RS_S, b_a_RS_S, with ASL's names. Its header
/// starts with '#', which CsvReader drops; WriteEuroc writes it.
const std::vector<std::string>& EurocAslStateColumns();

/// By extension: .tum / .txt -> TUM, .kitti -> KITTI, .csv -> EuRoC. Throws InputError
/// (field "extension") for anything else.
TrajectoryFormat TrajectoryFormatFromPath(const std::string& path);

/// The format named by `name` if it is not empty (an explicit --format option), else the one
/// TrajectoryFormatFromPath(path) gives.
TrajectoryFormat TrajectoryFormatFor(const std::string& path, const std::string& name);

/// True if `path`'s first line is a skerry states.csv header (starts with `t,px`), which also
/// ends in `.csv` but is not EuRoC. False if the file cannot be read.
bool IsStatesCsv(const std::string& path);

/// The KITTI sidecar with the times of `kitti_path`: `<kitti_path>.times`.
std::string KittiTimesPath(const std::string& kitti_path);

std::vector<StampedPose> ReadTrajectory(const std::string& path, TrajectoryFormat format);

/// Writes `poses` in `format` (KITTI: also the `.times` sidecar; EuRoC: the 8 pose columns).
void WriteTrajectory(const std::string& path,
                     const std::vector<StampedPose>& poses,
                     TrajectoryFormat format);

/// As above, from estimator records. EuRoC gets all 17 ASL columns (pose, v_RS_R, b_w_RS_S,
/// b_a_RS_S: velocity in the world frame, gyro and accelerometer biases in m/s, rad/s, m/s^2);
/// TUM and KITTI get the poses.
void WriteTrajectory(const std::string& path,
                     const std::vector<EstimateRecord>& records,
                     TrajectoryFormat format);

}  // namespace skerry
