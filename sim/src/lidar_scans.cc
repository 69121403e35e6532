#include "skerry/sim/lidar_scans.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <stdexcept>

#include "random.h"
#include "skerry/io/csv_reader.h"
#include "true_pose.h"

namespace skerry::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

}  // namespace

std::vector<double> LidarBeamElevations(const LidarModelSim& model) {
  std::vector<double> out;
  if (!model.elevations_deg.empty()) {
    for (const double e : model.elevations_deg) out.push_back(e * kDeg);
    std::sort(out.begin(), out.end());
    return out;
  }
  for (int k = 0; k < model.beams; ++k) {
    const double f = model.beams > 1 ? static_cast<double>(k) / (model.beams - 1) : 0.5;
    out.push_back(
        (model.min_elevation_deg + f * (model.max_elevation_deg - model.min_elevation_deg)) * kDeg);
  }
  return out;
}

LidarScan SimulateLidarScan(const HarbourWorld& world,
                            const LidarModelSim& model,
                            const BodyPoseAt& pose,
                            TimeNs t_start_ns,
                            std::uint64_t noise_seed) {
  if (!(model.rotation_rate_hz > 0.0) || !(model.azimuth_step_deg > 0.0)) {
    throw std::invalid_argument("SimulateLidarScan: rates and the azimuth step must be > 0");
  }
  const std::vector<double> elevations = LidarBeamElevations(model);
  std::vector<Eigen::Vector2d> cos_sin_elevation;
  for (const double e : elevations) cos_sin_elevation.emplace_back(std::cos(e), std::sin(e));
  const int steps = std::max(1, static_cast<int>(std::lround(360.0 / model.azimuth_step_deg)));
  const double sweep_s = 1.0 / model.rotation_rate_hz;
  const Eigen::Matrix3d R_b_l = model.T_b_l.q_b_s.normalized().toRotationMatrix();
  const Eigen::Vector3d& p_b_l = model.T_b_l.p_b_s;
  // The hull, in the body frame (rigid with the LiDAR, so its returns do not depend on the pose
  // except through the water line).
  OrientedBox hull;
  hull.centre_w = model.hull_centre_b_m;
  hull.half_size_m = 0.5 * model.hull_size_m;
  const bool has_hull = model.hull_size_m.minCoeff() > 0.0;
  const double water = world.water_level_m();

  Rng rng(noise_seed, RngStream::kLidarNoise);
  LidarScan scan;
  scan.t_ns = t_start_ns;
  scan.points.reserve(static_cast<size_t>(steps) * elevations.size() / 2);
  for (int k = 0; k < steps; ++k) {
    const double t_s = sweep_s * k / steps;
    const TimeNs t_ns = t_start_ns + SecondsToNs(t_s);
    Eigen::Quaterniond q_w_b;
    Eigen::Vector3d p_w_b;
    if (!pose(t_ns, &q_w_b, &p_w_b)) {
      throw std::invalid_argument("SimulateLidarScan: no pose at " + FormatSeconds(t_ns) + " s");
    }
    const Eigen::Matrix3d R_w_b = q_w_b.toRotationMatrix();
    const Eigen::Matrix3d R_w_l = R_w_b * R_b_l;
    const Eigen::Vector3d o_w = p_w_b + R_w_b * p_b_l;
    const double azimuth = -kPi + 2.0 * kPi * k / steps;
    const double ca = std::cos(azimuth), sa = std::sin(azimuth);
    for (const Eigen::Vector2d& ce : cos_sin_elevation) {
      const Eigen::Vector3d d_l(ce.x() * ca, ce.x() * sa, ce.y());
      const Eigen::Vector3d d_w = R_w_l * d_l;
      std::optional<RayHit> hit = world.Raycast(o_w, d_w, model.max_range_m, WorldView::kLidar);
      bool on_hull = false;
      if (has_hull) {
        const double max_range = hit ? hit->range_m : model.max_range_m;
        if (std::optional<RayHit> h = RaycastBox(hull, p_b_l, R_b_l * d_l, max_range)) {
          // Below the water line the hull is out of sight.
          if (o_w.z() + h->range_m * d_w.z() >= water) {
            hit = h;
            hit->normal_w = R_w_b * h->normal_w;
            hit->reflectivity = model.hull_reflectivity;
            on_hull = true;
          }
        }
      }
      if (!hit || hit->range_m < model.min_range_m) continue;
      const double r = hit->range_m;
      const double p_drop =
          model.dropout_at_max_range *
          std::pow(std::min(1.0, r / model.max_range_m), model.dropout_range_exponent);
      if (rng.Uniform() < p_drop) continue;
      const double measured = r + model.range_noise_sigma_m * rng.Normal();
      const double cos_incidence = std::abs(d_w.dot(hit->normal_w));
      LidarPoint p;
      p.p_l = (measured * d_l).cast<float>();
      p.intensity = static_cast<float>(100.0 * hit->reflectivity * cos_incidence);
      p.t_s = static_cast<float>(t_s);
      p.hull = on_hull;
      scan.points.push_back(p);
    }
  }
  return scan;
}

void WriteLidarScanPcd(const LidarScan& scan, const std::string& path) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw std::runtime_error("cannot write " + path);
  const size_t n = scan.points.size();
  // PCD v0.7 (pointclouds.org, "The PCD (Point Cloud Data) file format"): an ASCII header, then
  // the points' fields packed in order, little-endian.
  out << "# .PCD v0.7 - Point Cloud Data file format\n"
      << "# skerry simulated LiDAR scan; t: seconds after the scan's stamp "
      << FormatSeconds(scan.t_ns) << " s\n"
      << "VERSION 0.7\nFIELDS x y z intensity t\nSIZE 4 4 4 4 4\nTYPE F F F F F\n"
      << "COUNT 1 1 1 1 1\nWIDTH " << n << "\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " << n
      << "\nDATA binary\n";
  std::vector<float> data;
  data.reserve(5 * n);
  for (const LidarPoint& p : scan.points) {
    data.insert(data.end(), {p.p_l.x(), p.p_l.y(), p.p_l.z(), p.intensity, p.t_s});
  }
  out.write(reinterpret_cast<const char*>(data.data()),
            static_cast<std::streamsize>(data.size() * sizeof(float)));
  if (!out) throw std::runtime_error("cannot write " + path);
}

void RenderLidarScans(const ScenarioConfig& config,
                      std::uint64_t seed,
                      Dataset* data,
                      const std::string& out_dir,
                      const std::function<void(double)>& progress) {
  if (data->lidars.empty()) return;
  if (!config.harbour.enabled) {
    throw std::invalid_argument("RenderLidarScans: the scenario has no harbour to scan");
  }
  const HarbourWorld world = BuildHarbour(config.harbour, seed);
  const std::vector<NavState>& truth = data->truth_states;
  const BodyPoseAt pose = [&truth](TimeNs t, Eigen::Quaterniond* q, Eigen::Vector3d* p) {
    return TruePose(truth, t, q, p);
  };
  size_t total = 0, done = 0;
  for (const auto& scans : data->lidar_scans) total += scans.size();
  Rng rng(seed, RngStream::kLidarNoise);
  for (size_t k = 0; k < data->lidars.size(); ++k) {
    LidarConfig& lidar = data->lidars[k];
    const std::filesystem::path dir = std::filesystem::absolute(out_dir) / lidar.name;
    std::filesystem::create_directories(dir);
    lidar.scan_dir = dir.string();
    LidarModelSim model = config.lidar;
    model.T_b_l = lidar.T_b_l;
    for (const SensorFrame& f : data->lidar_scans.at(k)) {
      const std::uint64_t noise_seed = static_cast<std::uint64_t>(rng.Uniform() * 0x1.0p53);
      const LidarScan scan = SimulateLidarScan(world, model, pose, f.t_ns, noise_seed);
      WriteLidarScanPcd(scan, (dir / f.file).string());
      if (progress) progress(static_cast<double>(++done) / total);
    }
  }
}

}  // namespace skerry::sim
