/// \file
/// Prior work's protocol on skerry's simulated frames, both methods on the same frames in one
/// table (docs/results.md, "Skyline: single frames, prior work's protocol").
///
/// Frames: a vessel at sea off Nice (SRTM N43E007), camera 4 m above the water, 1920 x 1080,
/// 70 deg, mild barrel distortion, heading towards the coast and the Maritime Alps (-30..90 deg),
/// roll and pitch of a few degrees; masks rendered by the simulator's independent renderer.
/// Per frame and prior sigma: the intended waypoint = truth + N(0, sigma^2) per axis, the true
/// previous position 300 m back along the heading (a minute at 5 m/s), roll and pitch known (IMU).
///   baseline: prior work's morphology, hilltops, SAD, ray trace and adaptive grid search over
///             2-D position with the heading implied by the path (baseline_grid_search.h);
///   skerry:   the mask's skyline, the global search within 3 sigma of the waypoint and LM on
///             position and heading with the waypoint as a prior of that sigma (frame_locator.h);
///   from the truth: the same refinement started at the true pose (RefineFrame), the minimum of
///             the frame's cost nearest the truth, and the frames where its cost is lower than
///             the search's (there the search missed it; elsewhere the cost's lowest minimum
///             lies farther from the truth than this one); and the search's own sigma (its
///             horizontal covariance, RMS over the two axes) and its horizontal ANEES (the
///             mean of e' P^-1 e over the located frames: 2 for a consistent covariance).
/// DEM_SIGMA_M: the map's height error skerry's residual assumes (skyline.dem_sigma_m, default 4
/// as in the preset; its correlation on the ground that of frame_correlation_m, 90 m); the frames
/// themselves are rendered from the same DEM, only resampled on another grid.
/// GRID_M: 0 (the default) renders the frames from the simulator's world (sim::WorldTerrain, the
/// raster at half its cell off the map's nodes, as in the 20-minute scenarios) and gives both
/// methods skerry's default map (skyline::HorizonForTrack: half the raster's cell); a spacing > 0
/// resamples both at that spacing on nodes (41, 23) m apart instead (90: every table up to stop
/// 68, whose world and map each lost the raster's crests at 90 m).
/// Both are timed with OpenCV on one thread (cv::setNumThreads(1)).
/// Usage: skerry_skyline_protocol [SHARED_DATA_DIR] [frames] [DEM_SIGMA_M] [GRID_M]

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <opencv2/core/utility.hpp>
#include <random>
#include <string>
#include <vector>

#include "skerry/geo/dem.h"
#include "skerry/sim/terrain_renderer.h"
#include "skerry/sim/world_terrain.h"
#include "skerry/skyline/baseline_grid_search.h"
#include "skerry/skyline/frame_locator.h"
#include "skerry/skyline/horizon_for_track.h"
#include "skerry/skyline/skyline_extraction.h"

using namespace skerry;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

double Median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

double Mean(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x;
  return v.empty() ? std::nan("") : s / v.size();
}

struct Frame {
  Eigen::Vector3d p_w_c;
  double heading;
  Eigen::Matrix3d r_level_c;
  Eigen::Matrix3d r_w_c;  ///< the true camera attitude, Rz(-heading) r_level_c
  cv::Mat mask;
};

}  // namespace

int main(int argc, char** argv) {
  const std::string data = argc > 1 ? argv[1] : "../shared/data";
  const int n_frames = argc > 2 ? std::atoi(argv[2]) : 30;
  const double dem_sigma_m = argc > 3 ? std::atof(argv[3]) : 4.0;
  const double grid_m = argc > 4 ? std::atof(argv[4]) : 0.0;
  if (n_frames <= 0 || !(dem_sigma_m >= 0) || !std::isfinite(dem_sigma_m) || !(grid_m >= 0) ||
      !std::isfinite(grid_m)) {
    std::fprintf(stderr,
                 "usage: skerry_skyline_protocol [SHARED_DATA_DIR] [frames > 0] "
                 "[DEM_SIGMA_M >= 0] [GRID_M >= 0]\n");
    return 2;
  }
  const LocalFrame frame({43.62, 7.25, 48.23});
  const geo::Dem dem(data + "/dem/N43E007.hgt", frame, geo::DemOptions(geo::VerticalDatum::kEgm96));
  // The frames are drawn in [0, 4000] x [0, 2000] m.
  const std::vector<Eigen::Vector3d> area = {Eigen::Vector3d::Zero(),
                                             Eigen::Vector3d(4000.0, 2000.0, 0.0)};
  const SkylineConfig map_config;  // skerry's defaults
  const Eigen::AlignedBox2d box =
      skyline::HorizonBox(area, map_config.max_range_m).intersection(dem.footprint_enu());
  // The renderer's world and the estimators' map are the same DEM sampled at different nodes.
  const sim::TerrainRenderer renderer(grid_m > 0 ? dem.ResampleToEnu(box, grid_m)
                                                 : sim::WorldTerrain(dem, box));
  const auto horizon =
      grid_m > 0 ? std::make_shared<const skyline::HorizonPredictor>(dem.ResampleToEnu(
                       Eigen::AlignedBox2d(box.min() + Eigen::Vector2d(41, 23), box.max()), grid_m))
                 : skyline::HorizonForTrack(dem, area, map_config);
  const geo::EnuHeightGrid& grid = horizon->grid();
  CameraConfig config = skyline::PinholeFromFov("camera", 1920, 1080, 70.0);
  config.distortion = {-0.05, 0.01, 0.0, 0.0};
  const skyline::CameraModel camera(config);

  std::mt19937_64 rng(2026);
  std::uniform_real_distribution<double> ux(0.0, 4000.0), uy(0.0, 2000.0), uh(-30.0, 90.0),
      ut(-1.0, 1.0);
  std::vector<Frame> frames;
  while (static_cast<int>(frames.size()) < n_frames) {
    Frame f;
    const double x = ux(rng), y = uy(rng);
    const auto sea = grid.UpAt(x, y);
    if (!sea) continue;
    f.p_w_c = Eigen::Vector3d(x, y, *sea + 4.0);
    f.heading = uh(rng) * kDeg;
    const double roll = 2.0 * ut(rng) * kDeg, pitch = 1.0 * ut(rng) * kDeg;
    const Eigen::Matrix3d level_b = (Eigen::AngleAxisd(kPi / 2, Eigen::Vector3d::UnitZ()) *
                                     Eigen::AngleAxisd(pitch, Eigen::Vector3d::UnitY()) *
                                     Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()))
                                        .toRotationMatrix();
    f.r_level_c = level_b * skyline::LevelCameraRotation(0.0).toRotationMatrix();
    f.r_w_c =
        Eigen::AngleAxisd(-f.heading, Eigen::Vector3d::UnitZ()).toRotationMatrix() * f.r_level_c;
    f.mask = renderer.Render(config, Eigen::Quaterniond(f.r_w_c), f.p_w_c, false, 1).mask;
    frames.push_back(f);
  }
  // Both methods timed on one thread: OpenCV's own pool would otherwise spread their morphology
  // over every core.
  cv::setNumThreads(1);
  std::printf(
      "%d frames rendered from %s; map at %.1f m; skerry's residual with the map's error %.1f m; "
      "both methods timed on one thread\n\n",
      n_frames, grid_m > 0 ? "the DEM resampled at GRID_M" : "the simulator's world",
      grid.spacing_m, dem_sigma_m);
  std::printf(
      "| prior sigma m | prior mean error m | baseline mean error m | baseline vs prior | "
      "baseline failed | skerry mean error m | skerry vs prior | skerry failed | "
      "baseline / skerry error | heading error deg, skerry (median) | time per frame "
      "s, baseline / skerry (median) | skerry from the truth, mean error m | skerry's own sigma m "
      "(median) | skerry's horizontal ANEES | frames where the truth's start found a lower cost "
      "|\n"
      "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  std::normal_distribution<double> normal;
  for (double sigma : {10.0, 35.0, 70.0, 120.0, 170.0}) {
    std::vector<double> prior_err, base_err, sk_err, base_t, sk_t, sk_head, floor_err, sk_sigma,
        sk_nees;
    int base_failed = 0, sk_failed = 0, search_missed = 0;
    for (const Frame& f : frames) {
      const Eigen::Vector2d truth = f.p_w_c.head<2>();
      const Eigen::Vector2d intended = truth + sigma * Eigen::Vector2d(normal(rng), normal(rng));
      const Eigen::Vector2d previous =
          truth - 300.0 * Eigen::Vector2d(std::sin(f.heading), std::cos(f.heading));
      prior_err.push_back((intended - truth).norm());

      skyline::baseline::BaselineInput in;
      in.intended_xy = intended;
      in.previous_xy = previous;
      in.camera_z = f.p_w_c.z();
      in.r_level_c = f.r_level_c;
      const auto b = skyline::baseline::LocateFrameBaseline(grid, camera, f.mask, in);
      base_failed += !b.ok;
      base_err.push_back((b.xy - truth).norm());
      base_t.push_back(b.seconds);

      const auto t0 = std::chrono::steady_clock::now();
      const skyline::Skyline sky = skyline::ExtractSkylineFromMask(f.mask);
      const auto samples = skyline::SkylineSamples(sky, 8, 0.5);
      skyline::FrameLocatorOptions o;
      o.planar = true;
      o.search_radius_m = 3.0 * sigma;
      o.grid_step_m = std::max(o.search_radius_m / 4.0, 5.0);
      o.horizontal_sigma_m = sigma;
      const Eigen::Vector2d path = intended - previous;
      o.prior_heading_deg = std::atan2(path.x(), path.y()) / kDeg;
      o.heading_window_deg = std::min(180.0, std::atan2(3.0 * sigma, 300.0) / kDeg + 10.0);
      o.refine_candidates = 4;
      o.dem_sigma_m = dem_sigma_m;
      o.map_correlation_m = 90.0;
      const Eigen::Vector3d prior(intended.x(), intended.y(), f.p_w_c.z());
      const auto loc = skyline::LocateFrame(horizon, camera, samples, f.r_level_c, prior, o);
      sk_t.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      sk_failed += !loc.ok;
      const Eigen::Vector2d xy = loc.ok ? Eigen::Vector2d(loc.p_w_c.head<2>()) : intended;
      sk_err.push_back((xy - truth).norm());
      const auto fl = skyline::RefineFrame(horizon, camera, samples, Eigen::Quaterniond(f.r_w_c),
                                           f.p_w_c, f.r_level_c, prior, o);
      // The search missed a lower minimum of the same cost (relative 1e-6: solver tolerance).
      search_missed += fl.ok && (!loc.ok || fl.cost < loc.cost * (1.0 - 1e-6));
      floor_err.push_back(
          ((fl.ok ? Eigen::Vector2d(fl.p_w_c.head<2>()) : intended) - truth).norm());
      if (loc.ok) {
        sk_sigma.push_back(std::sqrt(0.5 * (loc.covariance(3, 3) + loc.covariance(4, 4))));
        const Eigen::Vector2d e = loc.p_w_c.head<2>() - truth;
        sk_nees.push_back(e.dot(loc.covariance.block<2, 2>(3, 3).inverse() * e));
        const Eigen::Vector3d axis = loc.q_w_c * Eigen::Vector3d::UnitZ();
        const Eigen::Vector3d true_axis = f.r_w_c * Eigen::Vector3d::UnitZ();
        sk_head.push_back(std::abs(std::remainder(std::atan2(axis.x(), axis.y()) -
                                                      std::atan2(true_axis.x(), true_axis.y()),
                                                  2 * kPi)) /
                          kDeg);
      }
    }
    const double pe = Mean(prior_err), be = Mean(base_err), se = Mean(sk_err);
    std::printf(
        "| %.0f | %.1f | %.1f | %+.1f %% | %d / %d | %.2f | %+.1f %% | %d / %d | %.0fx | %.3f "
        "| %.3f / %.3f | %.2f | %.2f | %.1f | %d / %d |\n",
        sigma, pe, be, 100.0 * (pe - be) / pe, base_failed, n_frames, se, 100.0 * (pe - se) / pe,
        sk_failed, n_frames, be / se, Median(sk_head), Median(base_t), Median(sk_t),
        Mean(floor_err), Median(sk_sigma), Mean(sk_nees), search_missed, n_frames);
    std::fflush(stdout);
  }
  std::printf(
      "\n(improvement = how much lower than the prior's error; a failed match keeps the "
      "waypoint)\n");
  return 0;
}
