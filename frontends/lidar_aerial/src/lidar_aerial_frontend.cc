#include "skerry/lidar_aerial/lidar_aerial_frontend.h"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <stdexcept>

#include "skerry/core/input_error.h"
#include "skerry/io/csv_reader.h"
#include "skerry/lidar_aerial/information_at_scale.h"
#include "skerry/lidar_aerial/planar_minimum.h"
#include "skerry/lidar_aerial/relief_displacement.h"
#include "skerry/lidar_aerial/scan_registration.h"

namespace skerry::lidar_aerial {

namespace {

double SecondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

LidarAerialFrontend::Scan FromCloud(TimeNs stamp_ns, const geo::PointCloud& cloud) {
  LidarAerialFrontend::Scan scan;
  scan.stamp_ns = stamp_ns;
  scan.points_l = cloud.points;
  if (cloud.intensity.size() == cloud.points.size()) scan.intensity = cloud.intensity;
  if (cloud.time_s.size() == cloud.points.size()) {
    scan.time_s.assign(cloud.time_s.begin(), cloud.time_s.end());
  }
  return scan;
}

// Rotation that levels the body: R_w_b with its heading taken out (roll and pitch remain).
Eigen::Quaterniond LevelRotation(const Eigen::Quaterniond& q_w_b) {
  const Eigen::Quaterniond q = q_w_b.normalized();
  return Eigen::AngleAxisd(-YawOf(q), Eigen::Vector3d::UnitZ()) * q;
}

// The window's block without the points that lie off every edge where the scan on its own fits
// best near `at` (lidar_aerial.window_trim_sigmas). That fit, made with every point, is itself
// pulled towards what only the scan shows; fitted again with the points kept and trimmed again,
// as ICP re-pairs after each step (Zhang 1994, sec. 4), until the points kept no longer change
// (three rounds at most). Fewer than min_points kept: every point. The distances are the block's
// own, read from its twin without loss or weight (r_i = d_i / sigma). `minimum` is set to the
// returned block's planar minimum from `at` when the rounds found it (not after a last refit),
// and `kept_points` to the points the block keeps (empty: all of them).
std::shared_ptr<ceres::CostFunction> TrimmedBlock(
    const LidarAerialFrontend::Context& c,
    const std::shared_ptr<const EdgeDistanceField>& field,
    const std::vector<Eigen::Vector3d>& points_b,
    const std::vector<double>& tau_s,
    const std::vector<double>& relief,
    const Eigen::Vector2d& nadir,
    const MapAlignmentOptions& o,
    const NavState& at,
    int* trimmed,
    std::optional<NavState>* minimum,
    std::vector<char>* kept_points) {
  MapAlignmentOptions plain = o;
  plain.loss_sigmas = 0.0;
  plain.effective_points = std::numeric_limits<double>::infinity();
  plain.information_share = 1.0;
  const std::unique_ptr<ceres::CostFunction> distances =
      DeskewedMapAlignmentCost::Create(field, points_b, tau_s, plain, relief, nadir);
  std::vector<double> z(points_b.size());
  std::shared_ptr<ceres::CostFunction> fit =
      DeskewedMapAlignmentCost::Create(field, points_b, tau_s, o, relief, nadir);
  *trimmed = 0;
  std::vector<char> keep;
  for (int round = 0; round < 3; ++round) {
    const NavState m = PlanarMinimum(*fit, at);
    *minimum = m;
    const double* values[] = {m.q_w_b.coeffs().data(), m.p_w_b.data(), m.v_w.data()};
    if (!distances->Evaluate(values, z.data(), nullptr)) break;
    std::vector<char> kept(points_b.size(), 0);
    std::vector<Eigen::Vector3d> kept_b;
    std::vector<double> kept_tau, kept_relief;
    for (size_t i = 0; i < points_b.size(); ++i) {
      if (z[i] > c.config.window_trim_sigmas) continue;
      kept[i] = 1;
      kept_b.push_back(points_b[i]);
      kept_tau.push_back(tau_s[i]);
      if (!relief.empty()) kept_relief.push_back(relief[i]);
    }
    if (static_cast<int>(kept_b.size()) < c.config.min_points || kept == keep) break;
    keep = std::move(kept);
    *trimmed = static_cast<int>(points_b.size() - kept_b.size());
    minimum->reset();
    fit = DeskewedMapAlignmentCost::Create(field, std::move(kept_b), std::move(kept_tau), o,
                                           std::move(kept_relief), nadir);
  }
  *kept_points = keep;
  return fit;
}

// The block on the keyframe's states and the LiDAR's mounting (MountedMapAlignmentCost) over the
// points `kept` marks (empty: all), deskewed by the gyro as PreparedPoints deskews them.
std::shared_ptr<ceres::CostFunction> MountedBlock(
    const LidarAerialFrontend::Context& c,
    const std::shared_ptr<const EdgeDistanceField>& field,
    const std::vector<Eigen::Vector3d>& points_b,
    const std::vector<double>& tau_s,
    const std::vector<double>& relief,
    const Eigen::Vector2d& nadir,
    const MapAlignmentOptions& o,
    const Eigen::Vector3d& gyro_rad_s,
    const std::vector<char>& kept) {
  const double rate = gyro_rad_s.norm();
  const Eigen::Vector3d axis =
      rate > 0.0 ? Eigen::Vector3d(gyro_rad_s / rate) : Eigen::Vector3d::UnitZ();
  std::vector<Eigen::Vector3d> b;
  std::vector<double> tau, k;
  std::vector<Eigen::Matrix3d> deskew;
  for (size_t i = 0; i < points_b.size(); ++i) {
    if (!kept.empty() && !kept[i]) continue;
    b.push_back(points_b[i]);
    tau.push_back(tau_s[i]);
    if (!relief.empty()) k.push_back(relief[i]);
    deskew.push_back(rate > 0.0 && std::isfinite(tau_s[i])
                         ? Eigen::AngleAxisd(rate * tau_s[i], axis).toRotationMatrix()
                         : Eigen::Matrix3d::Identity());
  }
  return MountedMapAlignmentCost::Create(field, b, std::move(tau), std::move(deskew),
                                         c.lidar.T_b_l.q_b_s, c.lidar.T_b_l.p_b_s, o, std::move(k),
                                         nadir);
}

// A scan's edge points in the body frame at `at`'s time, deskewed with the gyro and levelled
// with `at`'s roll and pitch, and their structure (out.geometry); no block yet.
LidarAerialFrontend::Prepared PreparedPoints(const LidarAerialFrontend::Context& c,
                                             const LidarAerialFrontend::Scan& scan,
                                             const NavState& at,
                                             const Eigen::Vector3d& gyro_rad_s) {
  LidarAerialFrontend::Prepared out;
  // Each return in the body frame at the keyframe's time: measured tau after it, while the body
  // turned by Exp(omega tau) (the keyframe's gyro, constant over the sweep).
  const Eigen::Matrix3d R_b_l = c.lidar.T_b_l.q_b_s.normalized().toRotationMatrix();
  const Eigen::Vector3d& p_b_l = c.lidar.T_b_l.p_b_s;
  const double stamp_tau = NsToSeconds(scan.stamp_ns - at.t_ns);
  std::vector<Eigen::Vector3d> points_b(scan.points_l.size());
  std::vector<double> tau(scan.points_l.size());
  const double rate = gyro_rad_s.norm();
  const Eigen::Vector3d axis =
      rate > 0.0 ? Eigen::Vector3d(gyro_rad_s / rate) : Eigen::Vector3d::UnitZ();
  for (size_t i = 0; i < scan.points_l.size(); ++i) {
    tau[i] = stamp_tau + (scan.time_s.empty() ? 0.0 : scan.time_s[i]);
    const Eigen::Vector3d p = R_b_l * scan.points_l[i] + p_b_l;
    points_b[i] = rate > 0.0 && std::isfinite(tau[i])
                      ? Eigen::Vector3d(Eigen::AngleAxisd(rate * tau[i], axis) * p)
                      : p;
  }
  // Levelled with the estimate's roll and pitch; the hull box is in the body frame.
  out.scan = PrepareScan(points_b, scan.intensity, LevelRotation(at.q_w_b), c.preparation, tau);
  out.points_b = out.scan.points_s;
  out.tau_s = out.scan.time_s;
  ScanGeometry& g = out.geometry;
  g.edge_points = static_cast<int>(out.points_b.size());
  g.walls = out.scan.wall_columns;
  g.rims = out.scan.rim_columns;
  g.intensity_edges = out.scan.intensity_columns;
  return out;
}

}  // namespace

SensorOptions DefaultLidarSensorOptions() {
  SensorOptions o;
  o.loss = RobustLoss{LossType::kNone, 1.0};
  return o;
}

LidarAerialFrontend::LidarAerialFrontend(const LidarConfig& lidar,
                                         std::shared_ptr<const AerialMap> map,
                                         const SensorOptions& sensor,
                                         const LidarAerialConfig& config)
    : LidarAerialFrontend(lidar,
                          map ? std::make_shared<const AerialMapTiles>(std::move(map)) : nullptr,
                          sensor,
                          config) {}

LidarAerialFrontend::LidarAerialFrontend(const LidarConfig& lidar,
                                         std::shared_ptr<const AerialMapTiles> tiles,
                                         const SensorOptions& sensor,
                                         const LidarAerialConfig& config)
    : tiles_(std::move(tiles)), sensor_(sensor), config_(config) {
  if (!tiles_) throw std::invalid_argument("LidarAerialFrontend: no map");
  auto context = std::make_shared<Context>();
  context->lidar = lidar;
  context->tiles = tiles_;
  context->config = config;
  context->calibrate_mount = sensor.calibrate;
  ScanPreparationOptions& p = context->preparation;
  p.max_range_m = config.max_range_m;
  p.min_height_m = config.min_height_m;
  const Eigen::Vector3d lo(config.hull_min_b_m[0], config.hull_min_b_m[1], config.hull_min_b_m[2]);
  const Eigen::Vector3d hi(config.hull_max_b_m[0], config.hull_max_b_m[1], config.hull_max_b_m[2]);
  if ((hi - lo).minCoeff() > 0.0) p.hull_s = Eigen::AlignedBox3d(lo, hi);  // body frame here
  p.cell_m = config.cell_m;
  p.front_edges = config.front_sector_deg > 0.0;
  p.front_sector_deg = config.front_sector_deg;
  p.max_wall_gap_per_m = config.wall_gap_per_m;
  p.max_edge_height_m = config.max_edge_height_m;
  p.max_points = config.max_points;
  context_ = std::move(context);
}

SensorSpec LidarAerialFrontend::Spec() const {
  SensorSpec spec;
  spec.name = context_->lidar.name;
  spec.loss = sensor_.loss;
  spec.gate_probability = sensor_.gate_probability;
  spec.gate_space = GateSpace::kState;
  spec.reacquire_after_rejections = config_.reacquire_after_rejections;
  spec.relocate_above_position_sigma_m = config_.relocate_above_position_sigma_m;
  spec.relocate_above_heading_sigma_rad = config_.relocate_above_heading_sigma_deg * M_PI / 180.0;
  spec.relocate_position_over_gnss = true;
  spec.relocate = [context = context_, scans = scans_, stats = stats_](
                      const SensorMeasurement& m, const NavState& x, const StateCovariance& p,
                      bool) -> std::optional<Relocation> {
    const auto it = scans->find(m.t_ns);
    if (it == scans->end()) return std::nullopt;
    return RelocateScan(*context, it->second(), x, p, stats.get());
  };
  if (sensor_.calibrate) {
    // The blocks take the mounting after the keyframe's blocks (MountedMapAlignmentCost).
    spec.has_extrinsic = true;
    spec.calibrate = true;
    spec.q_b_s = context_->lidar.T_b_l.q_b_s.normalized();
    spec.p_b_s = context_->lidar.T_b_l.p_b_s;
    spec.extrinsic_prior_sigma_rad = sensor_.extrinsic_prior_sigma_deg * M_PI / 180.0;
    spec.extrinsic_prior_sigma_m = sensor_.extrinsic_prior_sigma_m;
  }
  return spec;  // otherwise T_b_l is inside the blocks (held constant)
}

std::optional<Relocation> LidarAerialFrontend::Relocate(const SensorMeasurement& block,
                                                        const NavState& estimate,
                                                        const StateCovariance& covariance) const {
  const auto it = scans_->find(block.t_ns);
  if (it == scans_->end()) return std::nullopt;
  return RelocateScan(*context_, it->second(), estimate, covariance, stats_.get());
}

std::vector<TimeNs> LidarAerialFrontend::BlockTimes() const {
  std::vector<TimeNs> times;
  for (const auto& [t, reload] : *scans_) times.push_back(t);
  return times;
}

std::optional<Relocation> LidarAerialFrontend::Locate(TimeNs t_ns,
                                                      const Eigen::Vector3d& up_b,
                                                      const Eigen::Vector3d& prior_p_w_b,
                                                      double radius_m) const {
  const auto it = scans_->find(t_ns);
  if (it == scans_->end() || !(up_b.norm() > 0.0)) return std::nullopt;
  // A guess levelled by the accelerometer, its heading arbitrary: its covariance says the
  // heading is unknown (searched all round) and the position within radius_m (3 sigma).
  NavState guess;
  guess.t_ns = t_ns;
  guess.q_w_b = Eigen::Quaterniond::FromTwoVectors(up_b.normalized(), Eigen::Vector3d::UnitZ());
  guess.p_w_b = prior_p_w_b;
  StateCovariance p = StateCovariance::Zero();
  p.block<2, 2>(kRot, kRot).diagonal().setConstant(std::pow(2.0 * M_PI / 180.0, 2));
  p(kRot + 2, kRot + 2) = M_PI * M_PI;
  p.block<2, 2>(kPos, kPos).diagonal().setConstant(std::pow(radius_m / 3.0, 2));
  p(kPos + 2, kPos + 2) = 1.0;
  return RelocateScan(*context_, it->second(), guess, p, stats_.get());
}

std::optional<Relocation> RelocateScan(const LidarAerialFrontend::Context& c,
                                       const LidarAerialFrontend::Scan& scan,
                                       const NavState& estimate,
                                       const StateCovariance& covariance,
                                       LidarScanStats* stats) {
  ++stats->relocations_tried;
  const LidarAerialFrontend::Prepared p =
      PreparedPoints(c, scan, estimate, Eigen::Vector3d::Zero());
  if (static_cast<int>(p.points_b.size()) < c.config.min_points) return std::nullopt;
  // The edge points levelled with the estimate's roll and pitch (and moved by the estimated
  // velocity over their time): a planar registration.
  const Eigen::Quaterniond level = LevelRotation(estimate.q_w_b);
  const double yaw = YawOf(estimate.q_w_b);
  const Eigen::Matrix3d Rz_t = Eigen::AngleAxisd(-yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  std::vector<Eigen::Vector3d> points_l;
  for (size_t i = 0; i < p.points_b.size(); ++i) {
    Eigen::Vector3d l = level * p.points_b[i];
    if (!p.tau_s.empty()) l += Rz_t * (estimate.v_w * p.tau_s[i]);
    points_l.push_back(l);
  }
  const PlanarPose prior{estimate.p_w_b.head<2>(), yaw};
  const double sigma_p = std::sqrt(std::max(
      0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d>(covariance.block<2, 2>(kPos, kPos))
               .eigenvalues()(1)));
  const double sigma_yaw_deg =
      std::sqrt(std::max(0.0, covariance(kRot + 2, kRot + 2))) * 180.0 / M_PI;
  RegistrationOptions o;
  o.coarse.search_radius_m = std::clamp(3.0 * sigma_p, 10.0, kRelocationMaxRadiusM);
  // A heading known to no better than 60 degrees (a start at rest, no course over ground) is
  // searched all round.
  o.coarse.heading_range_deg =
      3.0 * sigma_yaw_deg > 60.0 ? 180.0 : std::clamp(3.0 * sigma_yaw_deg, 5.0, 20.0);
  o.fine.sigma_m = c.config.sigma_m;
  o.fine.loss = ParseDistanceLoss(c.config.loss);
  o.fine.loss_sigmas = c.config.loss_sigmas;
  o.fine.effective_points = c.config.effective_points;
  // The map around the estimate (the tile of its square when the map is tiled).
  const std::shared_ptr<const AerialMapTile> tile = c.tiles->At(estimate.p_w_b.head<2>());
  if (!tile) return std::nullopt;
  const Registration r = RegisterScan(*tile->map, FieldOf(tile), points_l, prior, o);
  if (!r.valid || r.coarse.ambiguous || !r.covariance.allFinite()) return std::nullopt;
  ++stats->relocations_found;
  Relocation out;
  out.q_w_b = Eigen::Quaterniond(Eigen::AngleAxisd(r.pose.yaw, Eigen::Vector3d::UnitZ())) * level;
  out.p_w_b = Eigen::Vector3d(r.pose.t.x(), r.pose.t.y(), estimate.p_w_b.z());
  // (rotation vector, position): roll, pitch and height the estimate's; heading and horizontal
  // position the registration's, at least 0.1 deg and 0.1 m.
  out.covariance.setZero();
  out.covariance.topLeftCorner<2, 2>() = covariance.block<2, 2>(kRot, kRot);
  out.covariance(2, 2) = r.covariance(2, 2) + std::pow(0.1 * M_PI / 180.0, 2);
  out.covariance.block<2, 2>(3, 3) =
      r.covariance.topLeftCorner<2, 2>() + 0.01 * Eigen::Matrix2d::Identity();
  out.covariance.block<2, 1>(3, 2) = r.covariance.block<2, 1>(0, 2);
  out.covariance.block<1, 2>(2, 3) = r.covariance.block<1, 2>(2, 0);
  out.covariance(5, 5) = covariance(kPos + 2, kPos + 2);
  char reason[96];
  std::snprintf(reason, sizeof(reason), "scan registration, score %.2f, ambiguity %.2f",
                r.coarse.score, r.coarse.ambiguity);
  out.reason = reason;
  return out;
}

std::optional<SensorMeasurement> LidarAerialFrontend::Measurement(Scan scan) {
  auto held = std::make_shared<const Scan>(std::move(scan));
  return Block(held->stamp_ns, *held, [held]() { return *held; });
}

std::optional<SensorMeasurement> LidarAerialFrontend::Measurement(TimeNs stamp_ns,
                                                                  const std::string& path) {
  const auto t0 = std::chrono::steady_clock::now();
  const Scan scan = FromCloud(stamp_ns, geo::LoadPointCloud(path));
  stats_->read_s += SecondsSince(t0);
  return Block(stamp_ns, scan,
               [stamp_ns, path]() { return FromCloud(stamp_ns, geo::LoadPointCloud(path)); });
}

std::optional<SensorMeasurement> LidarAerialFrontend::Block(TimeNs stamp_ns,
                                                            const Scan& scan,
                                                            std::function<Scan()> reload) {
  if (id_ < 0) throw std::logic_error("LidarAerialFrontend: Register before Measurement");
  ++stats_->scans;
  if (!scan.intensity.empty() && scan.intensity.size() != scan.points_l.size()) {
    throw std::invalid_argument("one intensity per return, or none");
  }
  if (!scan.time_s.empty() && scan.time_s.size() != scan.points_l.size()) {
    throw std::invalid_argument("one time per return, or none");
  }
  std::vector<double> times;
  for (size_t i = 0; i < scan.points_l.size(); ++i) {
    if (!scan.points_l[i].allFinite()) continue;
    if (!scan.time_s.empty()) {
      if (!std::isfinite(scan.time_s[i])) continue;
      times.push_back(scan.time_s[i]);
    } else {
      times.push_back(0.0);
    }
  }
  if (times.empty()) {
    ++stats_->skipped_no_returns;
    return std::nullopt;
  }
  stats_->without_point_times += scan.time_s.empty();
  // The block at the sweep's middle: the median return's time.
  std::nth_element(times.begin(), times.begin() + times.size() / 2, times.end());
  const TimeNs t_ns = stamp_ns + SecondsToNs(times[times.size() / 2]);
  if (t_ns <= last_block_ns_) {
    throw std::invalid_argument("scan at t=" + FormatSeconds(stamp_ns) +
                                ": its middle is not after the previous scan's");
  }
  // Consecutive scans repeat one map's errors: an AR(1) sequence's information per scan.
  double share = 1.0;
  if (last_block_ns_ >= 0 && config_.scan_correlation_s > 0.0) {
    const double rho = std::exp(-NsToSeconds(t_ns - last_block_ns_) / config_.scan_correlation_s);
    share = (1.0 - rho) / (1.0 + rho);
  }
  last_block_ns_ = t_ns;
  ++stats_->blocks;

  SensorMeasurement m;
  m.sensor = id_;
  m.t_ns = t_ns;
  m.slots = {Slot::kQ, Slot::kP, Slot::kV};
  // The scan's own misfit is its points' noise: the gate tests it without the share.
  m.gate_scale = std::sqrt(share);
  (*scans_)[t_ns] = reload;
  m.prepare = [context = context_, stats = stats_, reload = std::move(reload), share, t_ns](
                  const NavState& at, const Eigen::Vector3d& gyro,
                  BlockConsumer consumer) -> std::shared_ptr<ceres::CostFunction> {
    const Prepared p = PrepareScanBlock(*context, reload(), at, gyro, share, consumer);
    ++stats->prepared;
    stats->geometry[t_ns] = p.geometry;
    if (!p.cost) {
      ++(p.geometry.edge_points >= context->config.min_points ? stats->skipped_off_map
                                                              : stats->skipped_few_edges);
    }
    return p.cost;
  };
  return m;
}

LidarAerialFrontend::Prepared LidarAerialFrontend::Prepare(const Scan& scan,
                                                           const NavState& at,
                                                           const Eigen::Vector3d& gyro_rad_s,
                                                           double information_share,
                                                           BlockConsumer consumer) const {
  return PrepareScanBlock(*context_, scan, at, gyro_rad_s, information_share, consumer);
}

LidarAerialFrontend::Prepared PrepareScanBlock(const LidarAerialFrontend::Context& c,
                                               const LidarAerialFrontend::Scan& scan,
                                               const NavState& at,
                                               const Eigen::Vector3d& gyro_rad_s,
                                               double information_share,
                                               BlockConsumer consumer) {
  const auto t0 = std::chrono::steady_clock::now();
  LidarAerialFrontend::Prepared out = PreparedPoints(c, scan, at, gyro_rad_s);
  ScanGeometry& g = out.geometry;
  // The map at the body's position (the tile of its square when the map is tiled; none: every
  // point is off the map).
  const std::shared_ptr<const AerialMapTile> tile = c.tiles->At(at.p_w_b.head<2>());
  for (const Eigen::Vector3d& p_b : out.points_b) {
    g.on_map_points += tile && tile->map->Covers((at.q_w_b * p_b + at.p_w_b).head<2>());
  }
  if (g.edge_points >= c.config.min_points && g.on_map_points >= c.config.min_points) {
    MapAlignmentOptions o;
    o.sigma_m = c.config.sigma_m;
    o.loss =
        ParseDistanceLoss(consumer == BlockConsumer::kBatch ? c.config.batch_loss : c.config.loss);
    o.loss_sigmas = c.config.loss_sigmas;
    o.effective_points = c.config.effective_points;
    o.information_share = information_share;
    // Where the photograph shows each point's outline (relief_displacement.h), at this state:
    // its column's top over the lower of its local floor and the waterline (a vessel's body
    // origin; the LiDAR sees no water).
    std::vector<double> relief;
    const std::optional<Eigen::Vector3d>& viewpoint = c.tiles->map_options().viewpoint_w;
    const std::shared_ptr<const EdgeDistanceField> field = FieldOf(tile);
    if (viewpoint && out.scan.top_m.size() == out.points_b.size()) {
      relief.resize(out.points_b.size());
      for (size_t i = 0; i < out.points_b.size(); ++i) {
        const double z = (at.q_w_b * out.points_b[i]).z() + at.p_w_b.z();
        relief[i] = ReliefFactor(*viewpoint, z + out.scan.top_m[i],
                                 std::min(z + out.scan.floor_m[i], at.p_w_b.z()));
      }
    }
    const Eigen::Vector2d nadir =
        viewpoint ? viewpoint->head<2>().eval() : Eigen::Vector2d::Zero().eval();
    std::optional<NavState> minimum;  // of out.cost from `at`, when trimming found it
    std::vector<char> kept;           // the points out.cost keeps (empty: all)
    out.cost =
        consumer == BlockConsumer::kWindow && c.config.window_trim_sigmas > 0.0
            ? TrimmedBlock(c, field, out.points_b, out.tau_s, relief, nadir, o, at,
                           &g.trimmed_points, &minimum, &kept)
            : DeskewedMapAlignmentCost::Create(field, out.points_b, out.tau_s, o, relief, nadir);
    // The block the consumer gets: on the mounting too when it is calibrated, with the same
    // points, equal to out.cost at T_b_l (which the trimming and the measure below use).
    std::shared_ptr<ceres::CostFunction> block = out.cost;
    if (c.calibrate_mount) {
      block = MountedBlock(c, field, out.points_b, out.tau_s, relief, nadir, o, gyro_rad_s, kept);
    }
    // The block's information along its weakest horizontal direction, measured on the cost over
    // information_scale_m from the scan's own minimum near `at` (information_at_scale.h), and
    // the block keeping no more than that; its constraint ratio is the degeneracy measure.
    const NavState m = c.config.information_scale_m <= 0.0 ? at
                       : minimum                           ? *minimum
                                                           : PlanarMinimum(*out.cost, at);
    if (const std::optional<WeakDirection> weak =
            MeasureWeakDirection(*out.cost, m, c.config.information_scale_m)) {
      g.constraint_ratio = weak->constraint_ratio;
      g.weak_direction = weak->direction;
      g.weak_keep = weak->keep;
      block = KeepAlong(std::move(block), m.p_w_b, weak->direction, weak->keep);
    }
    out.cost = std::move(block);
  }
  g.prepare_s = SecondsSince(t0);
  return out;
}

namespace {

// A scan whose block was made: enough edge points, and enough of them on the map.
bool BlockMade(const ScanGeometry& g, int min_points) {
  return g.edge_points >= min_points && g.on_map_points >= min_points;
}

bool Degenerate(const ScanGeometry& g) { return g.constraint_ratio < kDegenerateConstraintRatio; }

}  // namespace

FrontendBlockTable LidarAerialFrontend::BlockTable() const {
  FrontendBlockTable table;
  table.columns = {"edge_points",        "on_map_points",  "walls",      "rims",
                   "intensity_edges",    "trimmed_points", "made",       "constraint_ratio",
                   "weak_direction_deg", "weak_keep",      "degenerate", "prepare_ms"};
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (const auto& [t, g] : stats_->geometry) {
    const bool made = BlockMade(g, config_.min_points);
    // The weak direction is an axis: east-north to clockwise from north, folded onto [0, 180).
    double weak_deg = std::atan2(g.weak_direction.x(), g.weak_direction.y()) * 180.0 / M_PI;
    weak_deg -= 180.0 * std::floor(weak_deg / 180.0);
    table.rows[t] = {static_cast<double>(g.edge_points),
                     static_cast<double>(g.on_map_points),
                     static_cast<double>(g.walls),
                     static_cast<double>(g.rims),
                     static_cast<double>(g.intensity_edges),
                     static_cast<double>(g.trimmed_points),
                     made ? 1.0 : 0.0,
                     made ? g.constraint_ratio : nan,
                     made ? weak_deg : nan,
                     made ? g.weak_keep : nan,
                     made ? (Degenerate(g) ? 1.0 : 0.0) : nan,
                     1e3 * g.prepare_s};
  }
  return table;
}

std::map<std::string, double> LidarAerialFrontend::SummaryStats() const {
  const LidarScanStats& s = *stats_;
  std::vector<double> edges, ratios, ms, trimmed, keep;
  int degenerate = 0;
  for (const auto& [t, g] : s.geometry) {
    edges.push_back(g.edge_points);
    ms.push_back(1e3 * g.prepare_s);
    if (BlockMade(g, config_.min_points)) {
      ratios.push_back(g.constraint_ratio);
      keep.push_back(g.weak_keep);
      trimmed.push_back(static_cast<double>(g.trimmed_points) / g.edge_points);
      degenerate += Degenerate(g);
    }
  }
  const auto median = [](std::vector<double> v) {
    if (v.empty()) return 0.0;
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  return {{"scans", s.scans},
          {"blocks", s.blocks},
          {"skipped_no_returns", s.skipped_no_returns},
          {"without_point_times", s.without_point_times},
          {"skipped_few_edges", s.skipped_few_edges},
          {"skipped_off_map", s.skipped_off_map},
          {"relocations_tried", s.relocations_tried},
          {"relocations_found", s.relocations_found},
          {"degenerate_scans", degenerate},
          {"median_edge_points", median(edges)},
          {"median_constraint_ratio", median(ratios)},
          {"median_trimmed_share", median(trimmed)},
          {"median_weak_keep", median(keep)},
          {"read_ms_per_scan", s.scans > 0 ? 1e3 * s.read_s / s.scans : 0.0},
          {"prepare_ms_per_scan", median(ms)},
          {"map_tiles", tiles_->tiled() ? tiles_->made() : 0},
          {"map_s", tiles_->make_s()}};
}

}  // namespace skerry::lidar_aerial
