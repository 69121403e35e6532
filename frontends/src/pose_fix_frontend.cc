#include "skerry/frontends/pose_fix_frontend.h"

#include <cmath>
#include <stdexcept>

#include "skerry/factors/pose_fix_factor.h"

namespace skerry {

PoseFixFrontend::PoseFixFrontend(const SensorMount& mount,
                                 const SensorOptions& options,
                                 const EarthModel& earth)
    : mount_(mount), options_(options), earth_(earth) {}

SensorSpec PoseFixFrontend::Spec() const {
  SensorSpec spec;
  spec.name = kName;
  spec.loss = options_.loss;
  spec.gate_probability = options_.gate_probability;
  spec.has_extrinsic = true;
  spec.q_b_s = mount_.q_b_s;
  spec.p_b_s = mount_.p_b_s;
  spec.calibrate = options_.calibrate;
  spec.extrinsic_prior_sigma_rad = options_.extrinsic_prior_sigma_deg * M_PI / 180.0;
  spec.extrinsic_prior_sigma_m = options_.extrinsic_prior_sigma_m;
  return spec;
}

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
