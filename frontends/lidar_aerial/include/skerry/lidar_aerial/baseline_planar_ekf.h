#pragma once
/// \file
/// Prior work's estimator, reimplemented as a baseline to run beside skerry on the same data: a
/// planar extended Kalman filter over x = [east, north, v_surge, v_sway, psi] (psi the heading,
/// here anticlockwise from east), predicted at 20 Hz with the gyro's yaw rate and a constant
/// body-frame velocity, corrected by GNSS positions (10 Hz) and by the LiDAR/aerial matcher's
/// pose (baseline_pso_matcher.h) at 1 Hz, its prior the filter's estimate.
///
/// Its noise tuning is prior work's: process noise alpha1 = 10, GNSS noise alpha2 = 10 (1000
/// during a loss: prior work deweighted GNSS where it knew it was disturbed, which here is the
/// dataset's jump and outage intervals: knowledge skerry is not given), matcher noise
/// alpha3 = 0.5, each multiplying a unit covariance in SI units (m^2, (m/s)^2 per second for the
/// process; m^2 for the fixes; m^2 and deg^2 for the matcher). The base matrices are this
/// reimplementation's reading (prior work prints only the alphas).

#include <Eigen/Core>
#include <functional>
#include <optional>
#include <vector>

#include "skerry/core/time.h"
#include "skerry/lidar_aerial/planar_pose.h"

namespace skerry::lidar_aerial::baseline {

struct PlanarEkfOptions {
  double rate_hz = 20.0;  ///< prediction rate
  double alpha1 = 10.0;   ///< process noise
  double alpha2 = 10.0;   ///< GNSS noise
  double alpha2_loss = 1000.0;
  double alpha3 = 0.5;  ///< matcher noise
  /// Unit process noise per second: position (m^2/s), body velocity ((m/s)^2/s), heading
  /// (deg^2/s).
  double q_position = 0.01;
  double q_velocity = 0.1;
  double q_heading_deg2 = 0.1;
};

/// One estimate of the filter.
struct PlanarEstimate {
  TimeNs t_ns = 0;
  Eigen::Matrix<double, 5, 1> x = Eigen::Matrix<double, 5, 1>::Zero();
  Eigen::Matrix<double, 5, 5> P = Eigen::Matrix<double, 5, 5>::Identity();
  PlanarPose pose() const { return {x.head<2>(), x(4)}; }
};

class PlanarEkf {
 public:
  PlanarEkf(const PlanarEstimate& start, const PlanarEkfOptions& options = {});

  /// Predicts to `t_ns` with the yaw rate `yaw_rate_rad_s` (anticlockwise), in steps of at most
  /// 1 / rate_hz. Time must not go back (std::invalid_argument).
  void Predict(TimeNs t_ns, double yaw_rate_rad_s);
  /// A GNSS position (ENU east, north); `loss`: the receiver is known disturbed (alpha2_loss).
  void UpdatePosition(const Eigen::Vector2d& p, bool loss);
  /// The matcher's pose (east, north, heading anticlockwise from east).
  void UpdatePose(const PlanarPose& pose);

  const PlanarEstimate& estimate() const { return est_; }

 private:
  void Update(const Eigen::MatrixXd& H,
              const Eigen::VectorXd& innovation,
              const Eigen::MatrixXd& R);
  PlanarEstimate est_;
  PlanarEkfOptions options_;
};

}  // namespace skerry::lidar_aerial::baseline
