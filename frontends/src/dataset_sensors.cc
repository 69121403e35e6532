#include "skerry/frontends/dataset_sensors.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <optional>
#include <stdexcept>
#include <vector>

#include "skerry/core/input_error.h"
#include "skerry/core/parallel_for.h"
#include "skerry/frontends/dataset_maps.h"
#include "skerry/frontends/pose_fix_frontend.h"
#include "skerry/frontends/water_surface_frontend.h"
#include "skerry/io/csv_reader.h"
#include "skerry/lidar_aerial/lidar_aerial_frontend.h"
#include "skerry/lidar_aerial/lidar_start.h"
#include "skerry/skyline/camera_frame.h"
#include "skerry/skyline/horizon_for_track.h"
#include "skerry/skyline/skyline_extraction.h"
#include "skerry/skyline/skyline_frontend.h"
#include "skerry/skyline/skyline_start.h"

namespace skerry {

namespace {

// The cameras through the skyline frontend: each frame's image read, its skyline extracted and
// turned into one block; frames without a usable skyline are skipped and counted.
void AddCameras(const Dataset& data,
                const EstimatorConfig& config,
                const DatasetMaps& maps,
                SensorLog* log) {
  if (data.cameras.empty()) return;
  if (!maps.dem) {
    throw std::invalid_argument("dataset '" + data.name +
                                "' has cameras but no maps.dem: the skyline frontend needs a DEM");
  }
  const SkylineConfig& sc = config.skyline;
  const auto horizon = skyline::HorizonForTrack(*maps.dem, DatasetTrack(data), sc);
  std::vector<skyline::SkylineFrontend> frontends;
  for (size_t k = 0; k < data.cameras.size(); ++k) {
    const CameraConfig& camera = data.cameras[k];
    const auto it = config.sensors.find(camera.name);
    const SensorOptions options =
        it != config.sensors.end() ? it->second : skyline::DefaultCameraSensorOptions();
    skyline::SkylineFrontend frontend(camera, horizon, options, sc);
    frontend.Register(log);
    // Every frame read and its skyline extracted on skyline.threads threads, each into its own
    // slot; the blocks made from them in time order. A frame that cannot be read stops the run
    // with the first such frame's error, as on one thread: the threads stop at the first they
    // meet, and the frames before it that they had not reached are read here, in order.
    const std::vector<SensorFrame>& frames = data.camera_frames.at(k);
    std::vector<std::vector<skyline::SkylineSample>> samples(frames.size());
    std::vector<double> seconds(frames.size(), 0.0);
    std::vector<std::optional<InputError>> errors(frames.size());
    std::vector<char> done(frames.size(), 0);
    auto extract = [&](size_t i) {
      done[i] = 1;
      const std::string path = (std::filesystem::path(camera.image_dir) / frames[i].file).string();
      const auto t0 = std::chrono::steady_clock::now();
      try {
        const cv::Mat image = skyline::ReadCameraFrame(path, frontend.camera());
        samples[i] = skyline::FrameSamples(image, frontend.camera(), sc.source, sc.column_stride_px,
                                           sc.min_confidence);
      } catch (const InputError& e) {
        errors[i] = InputError(path, 0, "image", "camera '" + camera.name + "': " + e.message());
        return false;
      } catch (const std::invalid_argument& e) {
        errors[i] =
            InputError(path, 0, "image", std::string("camera '") + camera.name + "': " + e.what());
        return false;
      }
      seconds[i] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      return true;
    };
    ParallelFor(frames.size(), sc.threads, extract);
    double extraction_s = 0.0;
    for (size_t i = 0; i < frames.size(); ++i) {
      if (!done[i]) extract(i);
      if (errors[i]) throw *errors[i];
      extraction_s += seconds[i];
      if (auto m = frontend.Measurement(frames[i].t_ns, samples[i])) {
        log->measurements.push_back(*m);
      }
    }
    const skyline::SkylineFrameStats& st = frontend.stats();
    log->frontend_stats[camera.name] = {
        {"frames", st.frames},
        {"blocks", st.measurements},
        {"skipped_no_sky", st.skipped_no_sky},
        {"skipped_few_samples", st.skipped_few_samples},
        {"extraction_ms_per_frame", st.frames > 0 ? 1e3 * extraction_s / st.frames : 0.0}};
    if (sc.frame_correlation_m > 0 || sc.dem_sigma_m > 0) {
      // The frames' weights are made as the window reaches them (crest_correlation.h,
      // SkylineResidualModel::AddMapError).
      log->live_frontend_stats[camera.name] = [frontend]() {
        const skyline::SkylineFrameStats& s = frontend.stats();
        return std::map<std::string, double>{
            {"mean_frame_weight",
             s.weighted_frames > 0 ? s.frame_weight_sum / s.weighted_frames : 0.0},
            {"mean_crest_shift_m", s.crest_frames > 0 ? s.crest_shift_m_sum / s.crest_frames : 0.0},
            {"mean_map_sigma_px",
             s.weighted_frames > 0 ? s.map_sigma_px_sum / s.weighted_frames : 0.0}};
      };
    }
    log->live_frontend_blocks[camera.name] = [frontend]() { return frontend.BlockTable(); };
    frontends.push_back(frontend);
  }
  // init.mode skyline: the first state from the first camera's first frames, searched around
  // the dataset origin at the water's height (or the origin's).
  if (config.init.mode == "skyline") {
    Eigen::Vector3d prior = Eigen::Vector3d::Zero();
    if (data.water_surface) prior.z() = data.water_surface->height_m - data.origin.height_m;
    skyline::SkylineStartOptions o;
    o.search_radius_m = sc.start_radius_m;
    log->start =
        skyline::SkylineStartState(frontends.front(), data.imu_samples, data.imu, prior, o);
    if (!log->start) {
      throw std::invalid_argument(
          "init.mode skyline: the global search located none of the first " +
          std::to_string(o.max_frames) + " frames of camera '" + data.cameras.front().name +
          "' within " + std::to_string(sc.start_radius_m) + " m of the origin");
    }
  }
}

// The LiDARs through the LiDAR/aerial frontend: the map around the track from the orthophoto (one
// map of the track's box, or tiles made as the scans reach them when that box is large), each
// scan read (and checked) now and turned into a block made at the estimate.
void AddLidars(const Dataset& data,
               const EstimatorConfig& config,
               std::shared_ptr<const geo::Orthophoto> orthophoto,
               SensorLog* log) {
  if (data.lidars.empty()) return;
  if (!orthophoto) {
    throw std::invalid_argument(
        "dataset '" + data.name +
        "' has LiDARs but no maps.orthophoto: the LiDAR/aerial frontend needs an aerial image");
  }
  const LidarAerialConfig& lc = config.lidar_aerial;
  // The orthophoto within map_margin_m of the track's box (a photo of a whole county is not
  // resampled whole).
  Eigen::AlignedBox2d box;
  for (const Eigen::Vector3d& p : DatasetTrack(data)) box.extend(p.head<2>().eval());
  if (box.isEmpty()) box = orthophoto->footprint_box_enu();
  box.min().array() -= lc.map_margin_m;
  box.max().array() += lc.map_margin_m;
  box = box.intersection(orthophoto->footprint_box_enu());
  lidar_aerial::AerialMapOptions mo;
  mo.resolution_m = lc.resolution_m;
  mo.max_distance_m = lc.max_distance_m;
  mo.blur_m = lc.map_blur_m;
  mo.canny_high_quantile = lc.canny_high_quantile;
  mo.canny_low_quantile = lc.canny_low_quantile;
  if (data.orthophoto && data.orthophoto->viewpoint && lc.model_relief) {
    const GeoOrigin& v = *data.orthophoto->viewpoint;
    mo.viewpoint_w = LocalFrame(data.origin).ToEnu(v.lat_deg, v.lon_deg, v.height_m);
  }
  // One map while the box holds at most map_tile_above_mcells million cells; tiles beyond, each
  // holding what a scan in its square reaches (MapReachM).
  const double mcells =
      box.isEmpty() ? 0.0 : box.volume() / (lc.resolution_m * lc.resolution_m) / 1e6;
  std::shared_ptr<const lidar_aerial::AerialMapTiles> tiles;
  if (mcells <= lc.map_tile_above_mcells) {
    const auto t0 = std::chrono::steady_clock::now();
    auto map = std::make_shared<const lidar_aerial::AerialMap>(*orthophoto, box, mo);
    tiles = std::make_shared<const lidar_aerial::AerialMapTiles>(
        std::move(map),
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  } else {
    lidar_aerial::AerialMapTilesOptions to;
    to.tile_m = lc.map_tile_m;
    to.margin_m = lidar_aerial::MapReachM(lc);
    tiles = std::make_shared<const lidar_aerial::AerialMapTiles>(orthophoto, box, mo, to);
  }
  for (size_t k = 0; k < data.lidars.size(); ++k) {
    const LidarConfig& lidar = data.lidars[k];
    const auto it = config.sensors.find(lidar.name);
    const SensorOptions options =
        it != config.sensors.end() ? it->second : lidar_aerial::DefaultLidarSensorOptions();
    lidar_aerial::LidarAerialFrontend frontend(lidar, tiles, options, lc);
    frontend.Register(log);
    for (const SensorFrame& f : data.lidar_scans.at(k)) {
      const std::string path = (std::filesystem::path(lidar.scan_dir) / f.file).string();
      try {
        if (auto m = frontend.Measurement(f.t_ns, path)) log->measurements.push_back(*m);
      } catch (const std::invalid_argument& e) {
        throw InputError(path, 0, "scan", std::string("LiDAR '") + lidar.name + "': " + e.what());
      }
    }
    log->frontend_stats[lidar.name] = frontend.SummaryStats();
    log->live_frontend_stats[lidar.name] = [frontend]() { return frontend.SummaryStats(); };
    log->live_frontend_blocks[lidar.name] = [frontend]() { return frontend.BlockTable(); };
    // init.mode lidar, and auto without a dual-antenna heading: the first state from the first
    // LiDAR's first scans, searched around the receiver's fix nearest each scan (else the
    // origin), at the water's height when known. auto falls back to the course over ground (or
    // align) when no scan locates; lidar is an error then.
    const bool dual_antenna = std::any_of(data.gnss_fixes.begin(), data.gnss_fixes.end(),
                                          [](const GnssFix& f) { return f.has_heading; });
    const bool lidar_start =
        config.init.mode == "lidar" || (config.init.mode == "auto" && !dual_antenna);
    if (k == 0 && lidar_start && !data.imu_samples.empty()) {
      const double water_z =
          data.water_surface ? data.water_surface->height_m - data.origin.height_m : 0.0;
      // The receiver's fix as the vessel's position: its sigma and its drift's stationary sigma
      // as the window would start from it (StartPositionVariance), the antenna's horizontal
      // lever arm L at a heading not yet known, as a variance of L^2 per axis (the offset's
      // largest square), and the way made between the fix and the scan at the speed between
      // the fixes around it, squared likewise. A fix more than kMaxFixOffsetS from the scan
      // centres the search but tests nothing.
      constexpr double kMaxFixOffsetS = 2.0;
      const double lever_arm2 = data.gnss.p_b_g.head<2>().squaredNorm();
      const auto prior = [&data, &config, water_z, lever_arm2](TimeNs t) {
        lidar_aerial::StartPrior p;
        p.p_w_b = Eigen::Vector3d(0.0, 0.0, water_z);
        if (!data.gnss_fixes.empty()) {
          auto it = std::lower_bound(data.gnss_fixes.begin(), data.gnss_fixes.end(), t,
                                     [](const GnssFix& f, TimeNs v) { return f.t_ns < v; });
          if (it == data.gnss_fixes.end()) --it;
          p.p_w_b.head<2>() = it->p_w.head<2>();
          if (!data.water_surface) p.p_w_b.z() = it->p_w.z();
          const double offset_s = std::abs(NsToSeconds(it->t_ns - t));
          if (offset_s <= kMaxFixOffsetS) {
            double speed = 0.0;  // between the fix and its neighbour towards the scan, if any
            const auto other = it->t_ns >= t ? (it == data.gnss_fixes.begin() ? it : it - 1)
                                             : (it + 1 == data.gnss_fixes.end() ? it : it + 1);
            if (other != it && other->t_ns != it->t_ns) {
              speed = (other->p_w - it->p_w).head<2>().norm() /
                      std::abs(NsToSeconds(other->t_ns - it->t_ns));
            }
            const double extra = lever_arm2 + std::pow(speed * offset_s, 2);
            const Eigen::Vector3d var = config.StartPositionVariance(it->sigma_enu_m);
            p.horizontal_cov =
                Eigen::Vector2d(var.x() + extra, var.y() + extra).asDiagonal().toDenseMatrix();
          }
        }
        return p;
      };
      lidar_aerial::LidarStartOptions o;
      o.search_radius_m = lc.start_radius_m;
      log->start = lidar_aerial::LidarStartState(frontend, data.imu_samples, data.imu, prior, o);
      if (!log->start && config.init.mode == "lidar") {
        throw std::invalid_argument("init.mode lidar: the registration located none of the first " +
                                    std::to_string(o.max_scans) + " scans of LiDAR '" + lidar.name +
                                    "' within " + std::to_string(lc.start_radius_m) +
                                    " m of the receiver's fixes (or the origin)");
      }
    }
  }
}

}  // namespace

SensorLog DatasetSensors(const Dataset& data, const EstimatorConfig& config) {
  SensorLog log;
  // The maps are checked now, before any estimation: a DEM or orthophoto that misses the track
  // is an error at load time.
  DatasetMaps maps;
  if (data.dem || data.orthophoto) maps = LoadDatasetMaps(data, 0.0, config.skyline.max_range_m);
  for (const auto& [name, options] : config.sensors) {
    bool camera = false;  // or a LiDAR
    for (const CameraConfig& c : data.cameras) camera |= c.name == name;
    for (const LidarConfig& l : data.lidars) camera |= l.name == name;
    const bool known = (name == PoseFixFrontend::kName && data.has_pose_fixes) ||
                       (name == WaterSurfaceFrontend::kName && data.water_surface.has_value()) ||
                       camera;
    if (!known) {
      throw std::invalid_argument("configuration sensors." + name + ": dataset '" + data.name +
                                  "' has no such sensor");
    }
  }
  if (data.has_pose_fixes) {
    PoseFixFrontend frontend(data.pose_fix_mount, config.SensorOptionsFor(PoseFixFrontend::kName),
                             data.Earth());
    frontend.Register(&log);
    for (const PoseFix& fix : data.pose_fixes) {
      try {
        log.measurements.push_back(frontend.Measurement(fix));
      } catch (const std::invalid_argument& e) {
        throw InputError(data.pose_fix_path, 0, "t=" + FormatSeconds(fix.t_ns), e.what());
      }
    }
  }
  if (data.water_surface && !data.imu_samples.empty()) {
    WaterSurfaceFrontend frontend(
        *data.water_surface, config.SensorOptionsFor(WaterSurfaceFrontend::kName), data.Earth());
    frontend.Register(&log);
    for (TimeNs t : frontend.Times(data.imu_samples.front().t_ns, data.imu_samples.back().t_ns)) {
      log.measurements.push_back(frontend.Measurement(t));
    }
  }
  AddCameras(data, config, maps, &log);
  // The LiDARs' map reads the orthophoto after this (tiles made as the scans reach them): they
  // share it.
  std::shared_ptr<const geo::Orthophoto> orthophoto;
  if (maps.orthophoto)
    orthophoto = std::make_shared<const geo::Orthophoto>(std::move(*maps.orthophoto));
  AddLidars(data, config, std::move(orthophoto), &log);
  return log;
}

}  // namespace skerry
