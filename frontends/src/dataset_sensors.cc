#include "skerry/frontends/dataset_sensors.h"

#include <stdexcept>

#include "skerry/core/input_error.h"
#include "skerry/frontends/dataset_maps.h"
#include "skerry/frontends/pose_fix_frontend.h"
#include "skerry/frontends/water_surface_frontend.h"
#include "skerry/io/csv_reader.h"

namespace skerry {

SensorLog DatasetSensors(const Dataset& data, const EstimatorConfig& config) {
  SensorLog log;
  // The maps are checked now, before any estimation: a DEM or orthophoto that misses the track
  // is an error at load time (the frontends that read them come with their own issues).
  if (data.dem || data.orthophoto) LoadDatasetMaps(data);
  for (const auto& [name, options] : config.sensors) {
    const bool known = (name == PoseFixFrontend::kName && data.has_pose_fixes) ||
                       (name == WaterSurfaceFrontend::kName && data.water_surface.has_value());
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
  return log;
}

}  // namespace skerry
