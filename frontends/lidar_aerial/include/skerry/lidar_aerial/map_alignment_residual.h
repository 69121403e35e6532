#pragma once
/// \file
/// The fine residual of LiDAR-to-aerial alignment: for each structure point of a scan, its
/// distance to the nearest edge of the aerial image (aerial_map.h), read from the distance field
/// by bicubic interpolation (ceres::BiCubicInterpolator: C1, so Gauss-Newton sees a gradient
/// pointing to the nearest edge) at the point's horizontal position under the current pose.
/// Chamfer matching as a least-squares residual (Barrow et al. 1977; Fitzgibbon 2003, "Robust
/// registration of 2D and 3D point sets", sec. 4: the distance transform as a residual for LM).
///
/// Robustness and weight, inside the residual. A point with no edge under it (a boat only in
/// the LiDAR, a wall hidden by a roof) must not pull, nor a point drawn to the outline of a boat
/// only in the photograph: distances are clipped by the map (AerialMapOptions::max_distance_m,
/// zero gradient beyond) and each is passed through a robust function, r_i = sqrt(rho(d_i^2 /
/// sigma^2)), which distances (never negative) allow inside one residual block with one residual
/// per point. Huber's, or Geman and McClure's rho(s) = k^2 s / (k^2 + s) (Geman and McClure
/// 1987; Black and Rangarajan 1996, "On the unification of line processes, outlier rejection,
/// and robust statistics", table 1): redescending, a point k sigmas off pulls a quarter as hard
/// as under least squares and one far off not at all, where Huber's keeps pulling with a constant
/// force (on the simulated harbour, most of a scan's error at the truth: docs/results.md). The
/// frontend gives the window's blocks Huber's and the batch's Geman-McClure's
/// (LidarAerialConfig::loss, batch_loss). The points of one scan are not independent (their
/// errors come from one map, one blur, one mis-registration of the image), so the scan is
/// weighted as `effective_points` independent points at most: every residual is scaled by
/// sqrt(min(1, effective_points / N) information_share). Without that, thousands of points would
/// drown the IMU and GNSS in the window.
///
/// Thin adapters over the same model: `MapAlignmentCost` on the body pose (q_w_b, p_w_b) with a
/// fixed sensor extrinsic, `DeskewedMapAlignmentCost` on the pose and velocity of a deskewed scan
/// (the window and the batch), `MountedMapAlignmentCost` on those and the LiDAR's mounting (when
/// it is calibrated), `PlanarAlignmentCost` on a planar pose (yaw, x, y) of the levelled scan
/// (single-scan registration, scan_registration.h).

#include <ceres/ceres.h>
#include <ceres/cubic_interpolation.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <string>
#include <vector>

#include "skerry/lidar_aerial/aerial_map.h"

namespace skerry::lidar_aerial {

/// The robust function of a point's distance (above).
enum class DistanceLoss { kGemanMcClure, kHuber };

/// "geman_mcclure", "huber" -> DistanceLoss; std::invalid_argument otherwise.
DistanceLoss ParseDistanceLoss(const std::string& name);
const char* ToString(DistanceLoss loss);

struct MapAlignmentOptions {
  double sigma_m = 0.5;  ///< one point's distance noise
  DistanceLoss loss = DistanceLoss::kHuber;
  double loss_sigmas = 2.0;         ///< the loss's scale k in sigmas (0: plain least squares)
  double effective_points = 100.0;  ///< a scan weighs at most this many independent points
  /// The scan's share of that information (0 < s <= 1): consecutive scans repeat one map's
  /// errors (LidarAerialConfig::scan_correlation_s). Every residual is scaled by sqrt(s) on top,
  /// so that it is exactly sqrt(s) times the scan's own (SensorMeasurement::gate_scale).
  double information_share = 1.0;
};

/// The map's distance field with bicubic interpolation at ENU positions.
class EdgeDistanceField {
 public:
  explicit EdgeDistanceField(const AerialMap& map);

  /// Distance (m) to the nearest edge at ENU (x, y); clamped to the grid's border outside it.
  template <typename T>
  T operator()(const T& x_w, const T& y_w) const {
    T d;
    interpolator_.Evaluate((T(y1_) - y_w) / resolution_m_, (x_w - T(x0_)) / resolution_m_, &d);
    return d;
  }

 private:
  cv::Mat distance_;  // keeps the data the grid points to
  double x0_, y1_, resolution_m_;
  ceres::Grid2D<float, 1> grid_;
  ceres::BiCubicInterpolator<ceres::Grid2D<float, 1>> interpolator_;
};

/// r = sqrt(rho(d^2 / sigma^2)) for d >= 0, with rho at scale k (in sigmas; k <= 0: r = d / sigma).
/// Geman-McClure: r = k z / sqrt(k^2 + z^2), z = d / sigma. Huber: z up to k, then
/// sqrt(2 k z - k^2).
template <typename T>
T RobustDistanceResidual(const T& d, double sigma_m, DistanceLoss loss, double k) {
  const T z = d / sigma_m;
  if (k <= 0.0) return z;
  if (loss == DistanceLoss::kGemanMcClure) return T(k) * z / sqrt(T(k * k) + z * z);
  if (z <= T(k)) return z;
  return sqrt(2.0 * k * z - k * k);
}

/// One scan on the body pose: residuals for the points p_s (sensor frame), parameters
/// q_w_b (4, Eigen order) and p_w_b (3); T_b_s fixed.
class MapAlignmentCost {
 public:
  static std::unique_ptr<ceres::CostFunction> Create(std::shared_ptr<const EdgeDistanceField> field,
                                                     std::vector<Eigen::Vector3d> points_s,
                                                     const Eigen::Quaterniond& q_b_s,
                                                     const Eigen::Vector3d& p_b_s,
                                                     const MapAlignmentOptions& options);

  template <typename T>
  bool operator()(const T* q_w_b, const T* p_w_b, T* r) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q(q_w_b);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> p(p_w_b);
    for (size_t i = 0; i < points_b_.size(); ++i) {
      const Eigen::Matrix<T, 3, 1> x = q * points_b_[i].cast<T>() + p;
      r[i] = scale_ * RobustDistanceResidual((*field_)(x.x(), x.y()), options_.sigma_m,
                                             options_.loss, options_.loss_sigmas);
    }
    return true;
  }

 private:
  MapAlignmentCost(std::shared_ptr<const EdgeDistanceField> field,
                   std::vector<Eigen::Vector3d> points_b,
                   const MapAlignmentOptions& options);
  std::shared_ptr<const EdgeDistanceField> field_;
  std::vector<Eigen::Vector3d> points_b_;  // in the body frame
  MapAlignmentOptions options_;
  double scale_;
};

/// What point i of a scan with N points reads from the map once placed at x_w: the distance
/// where the photograph shows its outline (with `relief`, one factor k_i per point,
/// relief_displacement.h: at u_i = x_i + k_i (x_i - nadir_w); without, at x_i), through the
/// robust function, times the scan's weight. The per-point residual of the deskewed adapters.
class PointReading {
 public:
  /// std::invalid_argument naming `who` when `relief` is neither empty nor one per point.
  PointReading(std::shared_ptr<const EdgeDistanceField> field,
               size_t points,
               const MapAlignmentOptions& options,
               std::vector<double> relief,
               const Eigen::Vector2d& nadir_w,
               const std::string& who);

  template <typename T>
  T operator()(size_t i, const Eigen::Matrix<T, 3, 1>& x_w) const {
    Eigen::Matrix<T, 2, 1> u = x_w.template head<2>();
    if (!relief_.empty()) u += T(relief_[i]) * (u - nadir_w_.cast<T>());
    return scale_ * RobustDistanceResidual((*field_)(u.x(), u.y()), options_.sigma_m, options_.loss,
                                           options_.loss_sigmas);
  }

 private:
  std::shared_ptr<const EdgeDistanceField> field_;
  MapAlignmentOptions options_;
  double scale_;
  std::vector<double> relief_;  // empty: none
  Eigen::Vector2d nadir_w_;
};

/// One scan on the keyframe's body pose and velocity, deskewed: point i was measured tau_i
/// seconds after the keyframe's time, `points_b` are in the body frame at the keyframe's time
/// (already turned back by the body's rotation over tau_i, which the gyro measures), and the body
/// moved v_w_b tau_i meanwhile: x_i = q_w_b p_b,i + p_w_b + v_w_b tau_i (constant velocity over
/// the sweep, as LOAM's linear interpolation of the sweep's motion: Zhang and Singh 2014, "LOAM:
/// Lidar Odometry and Mapping in Real-time", sec. V-B). Parameters q_w_b (4), p_w_b (3), v_w_b (3).
///
/// With `relief` (one factor k_i per point, relief_displacement.h) the distance is read where the
/// photograph shows point i's outline, u_i = x_i + k_i (x_i - nadir_w), not at x_i itself.
class DeskewedMapAlignmentCost {
 public:
  static std::unique_ptr<ceres::CostFunction> Create(std::shared_ptr<const EdgeDistanceField> field,
                                                     std::vector<Eigen::Vector3d> points_b,
                                                     std::vector<double> tau_s,
                                                     const MapAlignmentOptions& options,
                                                     std::vector<double> relief = {},
                                                     const Eigen::Vector2d& nadir_w = {0.0, 0.0});

  template <typename T>
  bool operator()(const T* q_w_b, const T* p_w_b, const T* v_w_b, T* r) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q(q_w_b);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> p(p_w_b);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> v(v_w_b);
    for (size_t i = 0; i < points_b_.size(); ++i) {
      r[i] = reading_(i, Eigen::Matrix<T, 3, 1>(q * points_b_[i].cast<T>() + p + v * T(tau_s_[i])));
    }
    return true;
  }

 private:
  DeskewedMapAlignmentCost(std::shared_ptr<const EdgeDistanceField> field,
                           std::vector<Eigen::Vector3d> points_b,
                           std::vector<double> tau_s,
                           const MapAlignmentOptions& options,
                           std::vector<double> relief,
                           const Eigen::Vector2d& nadir_w);
  std::vector<Eigen::Vector3d> points_b_;
  std::vector<double> tau_s_;
  PointReading reading_;
};

/// DeskewedMapAlignmentCost with the LiDAR's planar mounting estimated as well
/// (sensors.NAME.calibrate): its yaw about the body's z axis and its horizontal lever arm, the
/// part of T_b_s a top-down map observes. The points are given as that cost takes them, in the
/// body frame at the keyframe's time, put there with the mounting the dataset declares
/// (q_b_s0, p_b_s0) and turned back by the body's rotation D_i over tau_i (the gyro's, `deskew`).
/// The cost takes each back to the sensor frame once, p_s,i = R_b_s0^T (D_i^T p_b,i - p_b_s0), and
/// places it with the mounting being estimated, x_i = q_w_b D_i (R_b_s p_s,i + p_b_s) + p_w_b +
/// v_w_b tau_i (the body-to-sensor chain of a hand-eye calibration: Horaud and Dornaika 1995,
/// eq. 1, here against the map), where R_b_s = Rz(yaw(q_b_s q_b_s0^-1)) R_b_s0 and p_b_s keeps
/// p_b_s0's height: the roll, pitch and height of q_b_s and p_b_s do not enter (a wall seen from
/// above barely moves with them, and left free they took up 2.3 degrees of roll on the simulated
/// harbour's turn run whose mounting was exact), so only their prior holds them. At the declared
/// mounting it equals DeskewedMapAlignmentCost on the same points. Parameters q_w_b (4), p_w_b
/// (3), v_w_b (3), q_b_s (4), p_b_s (3): the seam's order for a sensor with an extrinsic
/// (sensor_block.h).
class MountedMapAlignmentCost {
 public:
  static std::unique_ptr<ceres::CostFunction> Create(std::shared_ptr<const EdgeDistanceField> field,
                                                     const std::vector<Eigen::Vector3d>& points_b,
                                                     std::vector<double> tau_s,
                                                     std::vector<Eigen::Matrix3d> deskew,
                                                     const Eigen::Quaterniond& q_b_s0,
                                                     const Eigen::Vector3d& p_b_s0,
                                                     const MapAlignmentOptions& options,
                                                     std::vector<double> relief = {},
                                                     const Eigen::Vector2d& nadir_w = {0.0, 0.0});

  template <typename T>
  bool operator()(
      const T* q_w_b, const T* p_w_b, const T* v_w_b, const T* q_b_s, const T* p_b_s, T* r) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q(q_w_b);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> p(p_w_b);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> v(v_w_b);
    // The yaw of q_b_s q_b_s0^-1 about the body's z axis (ZYX Euler angles' first).
    const Eigen::Quaternion<T> d =
        Eigen::Map<const Eigen::Quaternion<T>>(q_b_s) * q_b_s0_.conjugate().cast<T>();
    const T yaw = atan2(T(2) * (d.w() * d.z() + d.x() * d.y()),
                        d.w() * d.w() + d.x() * d.x() - d.y() * d.y() - d.z() * d.z());
    const T c = cos(yaw), s = sin(yaw);
    const Eigen::Matrix<T, 3, 1> p_bs(p_b_s[0], p_b_s[1], T(height_m_));
    for (size_t i = 0; i < points_s0_b_.size(); ++i) {
      // R_b_s p_s = Rz(yaw) (R_b_s0 p_s), with R_b_s0 p_s precomputed.
      const Eigen::Vector3d& a = points_s0_b_[i];
      const Eigen::Matrix<T, 3, 1> turned(c * a.x() - s * a.y(), s * a.x() + c * a.y(), T(a.z()));
      const Eigen::Matrix<T, 3, 1> b = deskew_[i].cast<T>() * (turned + p_bs);
      r[i] = reading_(i, Eigen::Matrix<T, 3, 1>(q * b + p + v * T(tau_s_[i])));
    }
    return true;
  }

 private:
  MountedMapAlignmentCost(std::shared_ptr<const EdgeDistanceField> field,
                          std::vector<Eigen::Vector3d> points_s0_b,
                          std::vector<double> tau_s,
                          std::vector<Eigen::Matrix3d> deskew,
                          const Eigen::Quaterniond& q_b_s0,
                          double height_m,
                          const MapAlignmentOptions& options,
                          std::vector<double> relief,
                          const Eigen::Vector2d& nadir_w);
  std::vector<Eigen::Vector3d> points_s0_b_;  // R_b_s0 p_s: sensor frame, body's axes
  Eigen::Quaterniond q_b_s0_;
  double height_m_;  // p_b_s0.z
  std::vector<double> tau_s_;
  std::vector<Eigen::Matrix3d> deskew_;
  PointReading reading_;
};

/// One levelled scan on a planar pose x = (yaw, x, y): p_w = R(yaw) p_l + (x, y).
class PlanarAlignmentCost {
 public:
  static std::unique_ptr<ceres::CostFunction> Create(std::shared_ptr<const EdgeDistanceField> field,
                                                     std::vector<Eigen::Vector2d> points_l,
                                                     const MapAlignmentOptions& options);

  template <typename T>
  bool operator()(const T* pose, T* r) const {
    const T c = cos(pose[0]), s = sin(pose[0]);
    for (size_t i = 0; i < points_l_.size(); ++i) {
      const Eigen::Vector2d& p = points_l_[i];
      const T x = c * p.x() - s * p.y() + pose[1];
      const T y = s * p.x() + c * p.y() + pose[2];
      r[i] = scale_ * RobustDistanceResidual((*field_)(x, y), options_.sigma_m, options_.loss,
                                             options_.loss_sigmas);
    }
    return true;
  }

 private:
  PlanarAlignmentCost(std::shared_ptr<const EdgeDistanceField> field,
                      std::vector<Eigen::Vector2d> points_l,
                      const MapAlignmentOptions& options);
  std::shared_ptr<const EdgeDistanceField> field_;
  std::vector<Eigen::Vector2d> points_l_;
  MapAlignmentOptions options_;
  double scale_;
};

}  // namespace skerry::lidar_aerial
