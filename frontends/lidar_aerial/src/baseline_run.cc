#include "skerry/lidar_aerial/baseline_run.h"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <stdexcept>

#include "skerry/geo/point_cloud.h"

namespace skerry::lidar_aerial::baseline {

BaselineRun RunBaseline(const Dataset& data, const AerialMap& map, const BaselineRunOptions& o) {
  if (data.groundtruth.empty()) throw std::invalid_argument("RunBaseline: no ground truth");
  if (data.lidars.empty()) throw std::invalid_argument("RunBaseline: no LiDAR");
  if (data.imu_samples.empty()) throw std::invalid_argument("RunBaseline: no IMU samples");
  BaselineRun run;
  const double deg = M_PI / 180.0;
  // Start: the first ground-truth pose at or after the first IMU sample, at rest in the body.
  const TimeNs t0 = data.imu_samples.front().t_ns;
  size_t g = 0;
  while (g + 1 < data.groundtruth.size() && data.groundtruth[g].t_ns < t0) ++g;
  PlanarEstimate start;
  start.t_ns = data.groundtruth[g].t_ns;
  start.x.head<2>() = data.groundtruth[g].p_w_b.head<2>();
  start.x(4) = YawOf(data.groundtruth[g].q_w_b);
  if (g + 1 < data.groundtruth.size()) {  // body-frame velocity from the truth's next pose
    const StampedPose& a = data.groundtruth[g];
    const StampedPose& b = data.groundtruth[g + 1];
    const double dt = NsToSeconds(b.t_ns - a.t_ns);
    const Eigen::Vector2d v = (b.p_w_b - a.p_w_b).head<2>() / dt;
    const double c = std::cos(start.x(4)), s = std::sin(start.x(4));
    start.x(2) = c * v.x() + s * v.y();
    start.x(3) = -s * v.x() + c * v.y();
  }
  start.P.setZero();
  start.P.diagonal() << o.start_sigma_m * o.start_sigma_m, o.start_sigma_m * o.start_sigma_m, 0.25,
      0.25, std::pow(o.start_sigma_deg * deg, 2);
  PlanarEkf ekf(start, o.ekf);

  const LidarConfig& lidar = data.lidars.front();
  const std::vector<SensorFrame>& scans = data.lidar_scans.front();
  const Eigen::Matrix3d R_b_l = lidar.T_b_l.q_b_s.normalized().toRotationMatrix();
  // The body z axis in the IMU frame: the yaw rate is the gyro along it.
  const Eigen::Vector3d z_i = data.imu.q_b_i.inverse() * Eigen::Vector3d::UnitZ();
  const auto loss = [&data](TimeNs t) {
    for (const GnssEvent& e : data.events) {
      if (t >= e.t_start_ns && t < e.t_end_ns) return true;
    }
    return false;
  };
  size_t f = 0, k = 0;
  double yaw_rate = 0.0;
  for (const ImuSample& s : data.imu_samples) {
    if (s.t_ns < ekf.estimate().t_ns) continue;
    // Fixes and scans before this sample, in time order.
    while (true) {
      const TimeNs tf =
          f < data.gnss_fixes.size() ? data.gnss_fixes[f].t_ns : std::numeric_limits<TimeNs>::max();
      const TimeNs ts = k < scans.size() ? scans[k].t_ns : std::numeric_limits<TimeNs>::max();
      const TimeNs t = std::min(tf, ts);
      if (t > s.t_ns) break;
      if (t < ekf.estimate().t_ns) {  // before the start
        (tf <= ts ? f : k)++;
        continue;
      }
      ekf.Predict(t, yaw_rate);
      if (tf <= ts) {
        const GnssFix& fix = data.gnss_fixes[f++];
        const double psi = ekf.estimate().x(4);
        const Eigen::Vector2d lever =
            Eigen::Rotation2Dd(psi) * data.gnss.p_b_g.head<2>();  // antenna -> body origin
        ekf.UpdatePosition(fix.p_w.head<2>() - lever, loss(fix.t_ns));
      } else {
        const SensorFrame& frame = scans[k];
        const bool match = (static_cast<int>(k) % std::max(1, o.match_every)) == 0;
        ++k;
        ++run.scans;
        if (!match) continue;
        const geo::PointCloud cloud =
            geo::LoadPointCloud((std::filesystem::path(lidar.scan_dir) / frame.file).string());
        std::vector<Eigen::Vector3d> points_b;
        for (const Eigen::Vector3d& p : cloud.points) {
          if (!p.allFinite()) continue;
          const Eigen::Vector3d b = R_b_l * p + lidar.T_b_l.p_b_s;
          if (b.z() < o.min_height_m || (!o.hull_b.isEmpty() && o.hull_b.contains(b))) continue;
          points_b.push_back(b);
        }
        const auto t_match = std::chrono::steady_clock::now();
        const BaselineMatch m = MatchBaseline(map, points_b, ekf.estimate().pose(), o.matcher);
        run.match_s +=
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t_match).count();
        ++run.matches;
        if (!m.valid) {
          ++run.invalid;
        } else if (m.gated) {
          ++run.gated;
        } else {
          ++run.accepted;
          ekf.UpdatePose(m.pose);
        }
      }
      run.estimates.push_back(ekf.estimate());
    }
    // The yaw rate: the gyro about the body's z axis (the IMU's axes rotated into the body).
    yaw_rate = z_i.dot(s.gyro_rad_s);
    ekf.Predict(s.t_ns, yaw_rate);
  }
  return run;
}

}  // namespace skerry::lidar_aerial::baseline
