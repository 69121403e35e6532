#include "skerry/skyline/skyline_frontend.h"

#include <stdexcept>

namespace skerry::skyline {

SensorOptions DefaultCameraSensorOptions() {
  SensorOptions o;
  o.loss = RobustLoss{LossType::kNone, 1.0};
  return o;
}

SkylineFrontend::SkylineFrontend(const CameraConfig& camera,
                                 std::shared_ptr<const HorizonPredictor> horizon,
                                 const SensorOptions& sensor, const SkylineConfig& config)
    : camera_(camera),
      mount_(camera.T_b_c),
      name_(camera.name),
      horizon_(std::move(horizon)),
      sensor_(sensor),
      config_(config) {
  if (!horizon_) throw std::invalid_argument("camera '" + name_ + "': no DEM to predict from");
}

SensorSpec SkylineFrontend::Spec() const {
  SensorSpec spec;
  spec.name = name_;
  spec.loss = sensor_.loss;
  spec.gate_probability = sensor_.gate_probability;
  spec.has_extrinsic = true;
  spec.q_b_s = mount_.q_b_s;
  spec.p_b_s = mount_.p_b_s;
  spec.calibrate = sensor_.calibrate;
  spec.extrinsic_prior_sigma_rad = sensor_.extrinsic_prior_sigma_deg * M_PI / 180.0;
  spec.extrinsic_prior_sigma_m = sensor_.extrinsic_prior_sigma_m;
  return spec;
}

SkylineResidualOptions SkylineFrontend::residual_options() const {
  SkylineResidualOptions o;
  o.sigma_px = config_.sigma_px;
  o.correlation_px = config_.correlation_px;
  o.huber_sigmas = config_.huber_sigmas;
  o.max_chain_gap_px = 5.0 * config_.column_stride_px;
  return o;
}

std::optional<SensorMeasurement> SkylineFrontend::Measurement(
    TimeNs t_ns, const std::vector<SkylineSample>& samples) {
  if (id_ < 0) throw std::logic_error("SkylineFrontend: Register before Measurement");
  ++stats_.frames;
  if (samples.empty()) {
    ++stats_.skipped_no_sky;
    return std::nullopt;
  }
  if (static_cast<int>(samples.size()) < config_.min_samples) {
    ++stats_.skipped_few_samples;
    return std::nullopt;
  }
  SensorMeasurement m;
  m.sensor = id_;
  m.t_ns = t_ns;
  m.cost = std::make_shared<SkylineCost>(
      std::make_shared<SkylineResidualModel>(horizon_, camera_, samples, residual_options()));
  m.slots = {Slot::kQ, Slot::kP};
  ++stats_.measurements;
  return m;
}

}  // namespace skerry::skyline
