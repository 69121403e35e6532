#include "skerry/frontends/pose_fix_frontend.h"

#include <cmath>
#include <stdexcept>

#include "skerry/factors/pose_fix_factor.h"
#include "skerry/frontends/mounted_sensor_spec.h"

namespace skerry {

PoseFixFrontend::PoseFixFrontend(const SensorMount& mount,
                                 const SensorOptions& options,
                                 const EarthModel& earth)
    : mount_(mount), options_(options), earth_(earth) {}

SensorSpec PoseFixFrontend::Spec() const { return MountedSensorSpec(kName, mount_, options_); }

SensorMeasurement PoseFixFrontend::Measurement(const PoseFix& fix) const {
  if (id_ < 0) throw std::logic_error("PoseFixFrontend: Register before Measurement");
  SensorMeasurement m;
  m.sensor = id_;
  m.t_ns = fix.t_ns;
  // Heading from the local north at the fix, as GNSS headings (gnss_heading_factor.h).
  m.cost = PoseFixFactor::Create(fix, earth_.LocalLevel(fix.p_w).transpose());
  m.slots = {Slot::kQ, Slot::kP};
  return m;
}

}  // namespace skerry
