#include "skerry/frontends/mounted_sensor_spec.h"

#include <cmath>

namespace skerry {

SensorSpec MountedSensorSpec(const std::string& name,
                             const SensorMount& mount,
                             const SensorOptions& options) {
  SensorSpec spec;
  spec.name = name;
  spec.loss = options.loss;
  spec.gate_probability = options.gate_probability;
  spec.has_extrinsic = true;
  spec.q_b_s = mount.q_b_s;
  spec.p_b_s = mount.p_b_s;
  spec.calibrate = options.calibrate;
  spec.extrinsic_prior_sigma_rad = options.extrinsic_prior_sigma_deg * M_PI / 180.0;
  spec.extrinsic_prior_sigma_m = options.extrinsic_prior_sigma_m;
  return spec;
}

}  // namespace skerry
