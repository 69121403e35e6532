#pragma once
/// \file
/// The LiDAR/aerial frontend of one LiDAR: scans in, one measurement block per scan out
/// (solvers/sensor_block.h), on the keyframe's pose and velocity, made at the estimate.
///
/// A scan is read when the dataset is; its block is made when it reaches its keyframe
/// (SensorMeasurement::prepare), from the state there: the returns are put in the body frame at
/// the keyframe's time, turned back by the body's rotation while the sweep measured them (the
/// keyframe's gyro over each point's time offset), levelled with the *estimated* roll and pitch
/// (prior work did not level: heel in a turn tilted a dock below its water threshold), cut to
/// what an aerial image can confirm (scan_preparation.h: walls, rims and ground-level intensity
/// edges, the water and the own hull dropped), and turned into the deskewed map-alignment
/// residual (map_alignment_residual.h: the body's motion over the sweep at the estimated
/// velocity). Its gate is in the state space (GateSpace::kState): a scan's thousands of
/// distances have a misfit at the truth that is the scene's (boats only in the LiDAR, edges only
/// in the image), and the gate tests the correction of the state the scan asks for.
///
/// Consecutive scans see one map through one mis-registration: a scan keeps the share
/// (1 - rho) / (1 + rho) of its information, rho = exp(-dt / scan_correlation_s), on top of the
/// residual's cap of effective_points per scan. At the state it is made at, each scan's position
/// information gives its degeneracy (the ratio of the weak to the strong eigenvalue and the
/// weak direction: only parallel quays in view), counted in summary.json.
///
/// The LiDAR's mounting T_b_l is the dataset's and held constant, unless the sensor is calibrated
/// (sensors.NAME.calibrate): then every block takes the mounting as the seam's extrinsic blocks,
/// estimated under a prior at T_b_l (extrinsic_prior_sigma_deg / _m), while the scan's
/// preparation, trimming, degeneracy measure and relocations stay at T_b_l.

#include <ceres/cost_function.h>

#include <Eigen/Core>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "skerry/core/nav_state.h"
#include "skerry/core/sensor_config.h"
#include "skerry/core/time.h"
#include "skerry/geo/point_cloud.h"
#include "skerry/lidar_aerial/aerial_map.h"
#include "skerry/lidar_aerial/aerial_map_tiles.h"
#include "skerry/lidar_aerial/map_alignment_residual.h"
#include "skerry/lidar_aerial/scan_preparation.h"
#include "skerry/solvers/estimator_config.h"
#include "skerry/solvers/sensor_block.h"

namespace skerry::lidar_aerial {

/// A scan's structure at the state its block was made at.
struct ScanGeometry {
  int edge_points = 0;
  /// Edge points over map cells that hold data (AerialMap::Covers) at the state the block was
  /// made at: off the map's edge or over an orthophoto's no-data, a point has nothing to align to.
  int on_map_points = 0;
  int walls = 0, rims = 0, intensity_edges = 0;
  /// Left out of the window's block: off every edge at the scan's own fit (window_trim_sigmas).
  int trimmed_points = 0;
  /// Smallest over largest eigenvalue of the block's 2x2 horizontal position information at the
  /// scan's own minimum, the smallest as the cost bears it out (weak_keep) (1: constrained alike
  /// in every direction; 0: not at all along `weak_direction`).
  double constraint_ratio = 0.0;
  Eigen::Vector2d weak_direction = Eigen::Vector2d::Zero();  ///< ENU, unit
  /// The share of its local information along weak_direction the block keeps: what its cost
  /// bears out over lidar_aerial.information_scale_m (information_at_scale.h).
  double weak_keep = 1.0;
  double prepare_s = 0.0;  ///< time to make the block
};

/// What happened to a LiDAR's scans.
struct LidarScanStats {
  int scans = 0;
  int blocks = 0;               ///< handed over
  int skipped_no_returns = 0;   ///< a scan without a finite return
  int without_point_times = 0;  ///< scans not deskewed (no per-point times)
  int prepared = 0;             ///< blocks made at a keyframe
  int skipped_few_edges = 0;    ///< made with fewer than min_points edge points: dropped
  int skipped_off_map = 0;      ///< made with enough, but fewer than min_points on the map
  int relocations_tried = 0;
  int relocations_found = 0;  ///< unambiguous registrations handed to the window
  double read_s = 0.0;        ///< reading the scan files
  /// Per scan time: its structure when last made (the window's, then the batch's).
  std::map<TimeNs, ScanGeometry> geometry;
};

/// The options of a LiDAR's blocks when the configuration does not name it: no loss on the whole
/// block (its points carry their own Huber), the state-space chi-square gate on.
SensorOptions DefaultLidarSensorOptions();

/// The degeneracy threshold of summary.json's `degenerate_scans`: a constraint ratio below this.
constexpr double kDegenerateConstraintRatio = 0.05;

/// The largest radius a relocation's (and the start's) coarse search covers, m.
constexpr double kRelocationMaxRadiusM = 50.0;

/// How far from the body a scan's blocks and relocations read the map, m: the LiDAR's range, a
/// relocation's search radius, the distance clip and a few cells of Canny's border (an
/// AerialMapTiles margin).
inline double MapReachM(const LidarAerialConfig& config) {
  return config.max_range_m + kRelocationMaxRadiusM + config.max_distance_m + 5.0;
}

class LidarAerialFrontend {
 public:
  /// `map`: the aerial map around the track (shared by the blocks).
  LidarAerialFrontend(const LidarConfig& lidar,
                      std::shared_ptr<const AerialMap> map,
                      const SensorOptions& sensor,
                      const LidarAerialConfig& config);
  /// `tiles`: the map as one map or as tiles (aerial_map_tiles.h); each block and relocation
  /// takes the tile at the body's position where it is made.
  LidarAerialFrontend(const LidarConfig& lidar,
                      std::shared_ptr<const AerialMapTiles> tiles,
                      const SensorOptions& sensor,
                      const LidarAerialConfig& config);

  SensorSpec Spec() const;
  template <typename Estimator>
  void Register(Estimator* estimator) {
    id_ = estimator->RegisterSensor(Spec());
  }
  SensorId id() const { return id_; }

  /// One scan: its time in lidar.csv (the sweep's start), its returns in the LiDAR's frame, their
  /// intensities (or none) and time offsets after the stamp (or none: not deskewed, counted).
  struct Scan {
    TimeNs stamp_ns = 0;
    std::vector<Eigen::Vector3d> points_l;
    std::vector<float> intensity;
    std::vector<double> time_s;
  };

  /// The block of a scan held in memory. Its time is the stamp plus the median time offset (the
  /// sweep's middle). nullopt (counted) when the scan has no finite return; a block time not
  /// after the previous one is an std::invalid_argument.
  std::optional<SensorMeasurement> Measurement(Scan scan);
  /// The block of a scan file (geo::LoadPointCloud: .pcd with fields x y z [intensity] [t], .ply,
  /// KITTI .bin): read now to check it (InputError naming the file), and again when the block is
  /// made, so that a long run does not hold its scans in memory.
  std::optional<SensorMeasurement> Measurement(TimeNs stamp_ns, const std::string& path);

  /// What a block's prepare does at a state (public for tests and the bench): the scan's edge
  /// points in the body frame, their time offsets from `at.t_ns`, the cost, and the geometry.
  /// `information_share`: the scan's share of its information (scan_correlation_s).
  struct Prepared {
    PreparedScan scan;
    std::vector<Eigen::Vector3d> points_b;
    std::vector<double> tau_s;
    /// null: fewer than min_points edge points, or fewer than that on the map
    std::shared_ptr<ceres::CostFunction> cost;
    ScanGeometry geometry;
  };
  Prepared Prepare(const Scan& scan,
                   const NavState& at,
                   const Eigen::Vector3d& gyro_rad_s,
                   double information_share = 1.0,
                   BlockConsumer consumer = BlockConsumer::kWindow) const;

  const std::shared_ptr<const AerialMapTiles>& tiles() const { return tiles_; }
  const LidarAerialConfig& config() const { return config_; }
  LidarScanStats& stats() { return *stats_; }
  const LidarScanStats& stats() const { return *stats_; }
  /// The scan of a block handed over earlier registered on its own around an estimate (coarse
  /// search within 3 sigma, at least 10 m and 5 degrees, then the fine step): the body pose with
  /// the registration's covariance (roll, pitch and height the estimate's); nullopt when the
  /// registration fails or is ambiguous. SensorSpec::relocate calls it.
  /// The times of the blocks made so far, in order.
  std::vector<TimeNs> BlockTimes() const;
  /// A global search for the block at t_ns with no estimate: the scan levelled with the body's
  /// `up_b` (from the accelerometer), registered with the heading searched all round within
  /// `radius_m` of prior_p_w_b (capped at kRelocationMaxRadiusM); nullopt when it is ambiguous
  /// or fails. Height: the prior's.
  std::optional<Relocation> Locate(TimeNs t_ns,
                                   const Eigen::Vector3d& up_b,
                                   const Eigen::Vector3d& prior_p_w_b,
                                   double radius_m) const;
  std::optional<Relocation> Relocate(const SensorMeasurement& block,
                                     const NavState& estimate,
                                     const StateCovariance& covariance) const;

  /// The figures of summary.json (solver.sensors.NAME.frontend).
  std::map<std::string, double> SummaryStats() const;
  /// Per scan, its structure when its block was last made (the window's blocks.csv): edge
  /// points, on the map, by kind, trimmed; the constraint ratio, the weak direction (degrees
  /// clockwise from north, in [0, 180)), what the block keeps along it, the degeneracy flag
  /// (kDegenerateConstraintRatio) and the time to make it. A scan whose block was not made
  /// (too few edge points, or too few on the map) has no ratio, direction, share or flag (NaN).
  FrontendBlockTable BlockTable() const;

  /// What the blocks need after the frontend is gone (they are made later, at the estimate).
  struct Context {
    LidarConfig lidar;
    std::shared_ptr<const AerialMapTiles> tiles;
    LidarAerialConfig config;
    ScanPreparationOptions preparation;
    /// sensors.NAME.calibrate: the blocks take the mounting as parameters after the keyframe's
    /// (MountedMapAlignmentCost); the scan is prepared and searched with lidar.T_b_l.
    bool calibrate_mount = false;
  };

 private:
  std::optional<SensorMeasurement> Block(TimeNs stamp_ns,
                                         const Scan& scan,
                                         std::function<Scan()> reload);

  std::shared_ptr<const AerialMapTiles> tiles_;
  SensorOptions sensor_;
  LidarAerialConfig config_;
  std::shared_ptr<const Context> context_;
  SensorId id_ = -1;
  TimeNs last_block_ns_ = -1;
  /// Shared with the blocks' prepare callbacks, which outlive a copied frontend.
  std::shared_ptr<LidarScanStats> stats_ = std::make_shared<LidarScanStats>();
  /// How to read each block's scan again, by block time (the relocation's).
  std::shared_ptr<std::map<TimeNs, std::function<Scan()>>> scans_ =
      std::make_shared<std::map<TimeNs, std::function<Scan()>>>();
};

/// Relocate on a context (LidarAerialFrontend::Relocate).
std::optional<Relocation> RelocateScan(const LidarAerialFrontend::Context& context,
                                       const LidarAerialFrontend::Scan& scan,
                                       const NavState& estimate,
                                       const StateCovariance& covariance,
                                       LidarScanStats* stats);

/// Prepare on a context (LidarAerialFrontend::Prepare).
LidarAerialFrontend::Prepared PrepareScanBlock(const LidarAerialFrontend::Context& context,
                                               const LidarAerialFrontend::Scan& scan,
                                               const NavState& at,
                                               const Eigen::Vector3d& gyro_rad_s,
                                               double information_share,
                                               BlockConsumer consumer);

}  // namespace skerry::lidar_aerial
