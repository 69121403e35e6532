#pragma once
/// \file
/// The water-surface frontend: a vessel floats, so the height of its body origin is known up to
/// the waves (factors/water_surface_factor.h). It hands the back end one block a `rate_hz` on the
/// keyframe at that time, through the same seam as any sensor (solvers/sensor_block.h): gated,
/// so that a surface that is not where the dataset says (a tide, a lock, a wrong datum) shows in
/// summary.json as rejections rather than as a pulled estimate. Without GNSS it is what keeps
/// the vertical channel, which horizontal aids (pose fixes, a skyline's bearings) leave to the
/// IMU, from diverging.

#include <vector>

#include "skerry/core/earth_model.h"
#include "skerry/core/sensor_config.h"
#include "skerry/solvers/estimator_config.h"
#include "skerry/solvers/sensor_block.h"

namespace skerry {

class WaterSurfaceFrontend {
 public:
  static constexpr char kName[] = "water_surface";

  WaterSurfaceFrontend(const WaterSurfaceConfig& surface,
                       const SensorOptions& options,
                       const EarthModel& earth);

  SensorSpec Spec() const;
  template <typename Estimator>
  void Register(Estimator* estimator) {
    id_ = estimator->RegisterSensor(Spec());
  }
  SensorId id() const { return id_; }

  /// The block at time t.
  SensorMeasurement Measurement(TimeNs t_ns) const;
  /// The times of its blocks over [t0, t1]: t0 + k / rate_hz.
  std::vector<TimeNs> Times(TimeNs t0_ns, TimeNs t1_ns) const;

 private:
  WaterSurfaceConfig surface_;
  SensorOptions options_;
  double origin_height_m_ = 0.0;
  double radius_m_ = 0.0;
  SensorId id_ = -1;
};

}  // namespace skerry
