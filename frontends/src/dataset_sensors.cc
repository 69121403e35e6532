#include "skerry/frontends/dataset_sensors.h"

#include <chrono>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "skerry/core/input_error.h"
#include "skerry/frontends/dataset_maps.h"
#include "skerry/frontends/pose_fix_frontend.h"
#include "skerry/frontends/water_surface_frontend.h"
#include "skerry/io/csv_reader.h"
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
    double extraction_s = 0.0;
    for (const SensorFrame& f : data.camera_frames.at(k)) {
      const std::string path = (std::filesystem::path(camera.image_dir) / f.file).string();
      const auto t0 = std::chrono::steady_clock::now();
      const cv::Mat image = cv::imread(path, cv::IMREAD_UNCHANGED);
      if (image.empty()) throw InputError(path, 0, "image", "cannot be read as an image");
      skyline::Skyline sky;
      try {
        skyline::RequireCameraSize(image, frontend.camera());
        const bool mask =
            sc.source == "mask" || (sc.source == "auto" && skyline::LooksLikeMask(image));
        if (mask) {
          if (image.type() != CV_8UC1) {
            throw std::invalid_argument("a segmentation mask must be 8-bit single-channel");
          }
          sky = skyline::ExtractSkylineFromMask(image);
        } else {
          cv::Mat photo = image;
          if (image.type() == CV_8UC4) cv::cvtColor(image, photo, cv::COLOR_BGRA2BGR);
          sky = skyline::ExtractSkylineFromImage(photo);
        }
      } catch (const std::invalid_argument& e) {
        throw InputError(path, 0, "image",
                         std::string("camera '") + camera.name + "': " + e.what());
      }
      const auto samples = skyline::SkylineSamples(sky, sc.column_stride_px, sc.min_confidence);
      extraction_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      if (auto m = frontend.Measurement(f.t_ns, samples)) log->measurements.push_back(*m);
    }
    const skyline::SkylineFrameStats& st = frontend.stats();
    log->frontend_stats[camera.name] = {
        {"frames", st.frames},
        {"blocks", st.measurements},
        {"skipped_no_sky", st.skipped_no_sky},
        {"skipped_few_samples", st.skipped_few_samples},
        {"extraction_ms_per_frame", st.frames > 0 ? 1e3 * extraction_s / st.frames : 0.0}};
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

}  // namespace

SensorLog DatasetSensors(const Dataset& data, const EstimatorConfig& config) {
  SensorLog log;
  // The maps are checked now, before any estimation: a DEM or orthophoto that misses the track
  // is an error at load time.
  DatasetMaps maps;
  if (data.dem || data.orthophoto) maps = LoadDatasetMaps(data);
  for (const auto& [name, options] : config.sensors) {
    bool camera = false;
    for (const CameraConfig& c : data.cameras) camera |= c.name == name;
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
  return log;
}

}  // namespace skerry
