#include "skerry/frontends/water_surface_frontend.h"

#include <cmath>
#include <stdexcept>

#include "skerry/factors/water_surface_factor.h"

namespace skerry {

namespace {
// Gaussian mean radius of curvature sqrt(M N) of the WGS84 ellipsoid at a latitude.
double GaussianRadius(double lat_deg) {
  constexpr double a = 6378137.0;
  constexpr double f = 1.0 / 298.257223563;
  constexpr double e2 = f * (2.0 - f);
  const double s = std::sin(lat_deg * M_PI / 180.0);
  const double w = 1.0 - e2 * s * s;
  return a * std::sqrt(1.0 - e2) / w;
}
}  // namespace

WaterSurfaceFrontend::WaterSurfaceFrontend(const WaterSurfaceConfig& surface,
                                           const SensorOptions& options,
                                           const EarthModel& earth)
    : surface_(surface), options_(options), origin_height_m_(earth.origin().height_m) {
  if (!(surface.sigma_m > 0.0) || !(surface.rate_hz > 0.0)) {
    throw std::invalid_argument("water_surface: sigma_m and rate_hz must be positive");
  }
  // A flat world has no curvature: its "height" is z above the origin.
  radius_m_ = earth.kind() == EarthKind::kFlat ? 1e30 : GaussianRadius(earth.origin().lat_deg);
}

SensorSpec WaterSurfaceFrontend::Spec() const {
  SensorSpec spec;
  spec.name = kName;
  spec.loss = options_.loss;
  spec.gate_probability = options_.gate_probability;
  return spec;
}

SensorMeasurement WaterSurfaceFrontend::Measurement(TimeNs t_ns) const {
  if (id_ < 0) throw std::logic_error("WaterSurfaceFrontend: Register before Measurement");
  SensorMeasurement m;
  m.sensor = id_;
  m.t_ns = t_ns;
  m.cost = std::make_shared<WaterSurfaceFactor>(origin_height_m_, radius_m_, surface_.height_m,
                                                surface_.sigma_m);
  m.slots = {Slot::kP};
  return m;
}

std::vector<TimeNs> WaterSurfaceFrontend::Times(TimeNs t0_ns, TimeNs t1_ns) const {
  std::vector<TimeNs> times;
  const double period_ns = 1e9 / surface_.rate_hz;
  for (std::int64_t k = 0;; ++k) {
    const TimeNs t = t0_ns + static_cast<TimeNs>(std::llround(k * period_ns));
    if (t > t1_ns) break;
    times.push_back(t);
  }
  return times;
}

}  // namespace skerry
