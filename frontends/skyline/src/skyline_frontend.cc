#include "skerry/skyline/skyline_frontend.h"

#include <spdlog/fmt/fmt.h>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <mutex>
#include <optional>
#include <stdexcept>

#include "skerry/core/heading.h"
#include "skerry/frontends/mounted_sensor_spec.h"
#include "skerry/skyline/crest_correlation.h"

namespace skerry::skyline {

SensorOptions DefaultCameraSensorOptions() {
  SensorOptions o;
  o.loss = RobustLoss{LossType::kNone, 1.0};
  return o;
}

SkylineFrontend::SkylineFrontend(const CameraConfig& camera,
                                 std::shared_ptr<const HorizonPredictor> horizon,
                                 const SensorOptions& sensor,
                                 const SkylineConfig& config)
    : camera_(camera),
      mount_(camera.T_b_c),
      name_(camera.name),
      horizon_(std::move(horizon)),
      sensor_(sensor),
      config_(config) {
  if (!horizon_) throw std::invalid_argument("camera '" + name_ + "': no DEM to predict from");
  if (EstimatedParameter() == SkylineParameter::kDetailGain && !horizon_->has_detail()) {
    throw std::invalid_argument("camera '" + name_ +
                                "': skyline.dem_sharpening_sigma needs the map's detail "
                                "(HorizonForTrack attaches it)");
  }
}

SensorSpec SkylineFrontend::Spec() const {
  SensorSpec spec = MountedSensorSpec(name_, mount_, sensor_);
  spec.reacquire_after_rejections = config_.reacquire_after_rejections;
  // A copy of what the search needs: the spec outlives this object.
  const SkylineFrontend self = *this;
  spec.relocate = [self](const SensorMeasurement& m, const NavState& x, const StateCovariance& p,
                         bool after_rejections) {
    return self.Relocate(m, x, p, after_rejections);
  };
  spec.relocate_above_heading_sigma_rad = config_.relocate_above_heading_sigma_deg * M_PI / 180.0;
  // The refraction coefficient, the map's sharpening gain or its crest offset as the camera's
  // parameter, estimated with the states (skyline.refraction_k_sigma, dem_sharpening_sigma,
  // crest_offset_sigma_m): the last block of every SkylineCost of this camera.
  const auto estimate = [&spec](double prior, double sigma, const char* name) {
    spec.has_parameter = true;
    spec.parameter = prior;
    spec.parameter_prior_sigma = sigma;
    spec.parameter_name = name;
  };
  switch (EstimatedParameter()) {
    case SkylineParameter::kRefraction:
      estimate(config_.refraction_k, config_.refraction_k_sigma, "refraction_k");
      break;
    case SkylineParameter::kCrestOffset:
      estimate(config_.crest_offset_m, config_.crest_offset_sigma_m, "crest_offset_m");
      break;
    case SkylineParameter::kDetailGain:
      estimate(config_.dem_sharpening, config_.dem_sharpening_sigma, "dem_sharpening");
      break;
    case SkylineParameter::kNone:
      break;
  }
  return spec;
}

SkylineResidualOptions SkylineFrontend::residual_options() const {
  SkylineResidualOptions o;
  o.sigma_px = config_.sigma_px;
  o.correlation_px = config_.correlation_px;
  o.huber_sigmas = config_.huber_sigmas;
  o.max_chain_gap_px = 5.0 * config_.column_stride_px;
  o.threads = config_.threads;
  o.crest_offset_m = config_.crest_offset_m;
  // An estimated gain's prior; a fixed one is in the map already (HorizonForTrack).
  o.detail_gain = config_.dem_sharpening_sigma > 0 ? config_.dem_sharpening : 0.0;
  return o;
}

SkylineParameter SkylineFrontend::EstimatedParameter() const {
  const int estimated = (config_.refraction_k_sigma > 0) + (config_.crest_offset_sigma_m > 0) +
                        (config_.dem_sharpening_sigma > 0);
  if (estimated > 1) {
    throw std::invalid_argument("camera '" + name_ +
                                "': estimate one of refraction_k, crest_offset_m and "
                                "dem_sharpening, not several");
  }
  if (config_.refraction_k_sigma > 0) return SkylineParameter::kRefraction;
  if (config_.crest_offset_sigma_m > 0) return SkylineParameter::kCrestOffset;
  if (config_.dem_sharpening_sigma > 0) return SkylineParameter::kDetailGain;
  return SkylineParameter::kNone;
}

std::optional<SensorMeasurement> SkylineFrontend::Measurement(
    TimeNs t_ns, const std::vector<SkylineSample>& samples) {
  if (id_ < 0) throw std::logic_error("SkylineFrontend: Register before Measurement");
  ++stats_->frames;
  if (samples.empty()) {
    ++stats_->skipped_no_sky;
    return std::nullopt;
  }
  if (static_cast<int>(samples.size()) < config_.min_samples) {
    ++stats_->skipped_few_samples;
    return std::nullopt;
  }
  (*frames_)[t_ns] = samples;
  stats_->per_frame[t_ns].samples = static_cast<int>(samples.size());
  SkylineResidualOptions options = residual_options();
  // The share of the frame's information that is its own (skyline_residual.h, frame_weight): an
  // AR(1) sequence from frame to frame keeps (1 - rho) / (1 + rho) of each frame's.
  double rho_time = 1.0;
  if (config_.frame_correlation_s > 0 && last_frame_ns_ >= 0) {
    rho_time = std::exp(-NsToSeconds(t_ns - last_frame_ns_) / config_.frame_correlation_s);
  } else if (config_.frame_correlation_s > 0 || config_.frame_correlation_m <= 0) {
    rho_time = 0.0;  // the first frame, or frames not correlated in time or on the ground
  }
  last_frame_ns_ = t_ns;
  SensorMeasurement m;
  m.sensor = id_;
  m.t_ns = t_ns;
  m.slots = {Slot::kQ, Slot::kP};
  const SkylineParameter estimated = EstimatedParameter();
  if (config_.frame_correlation_m <= 0 && config_.dem_sigma_m <= 0) {
    options.frame_weight = std::sqrt((1.0 - rho_time) / (1.0 + rho_time));
    m.cost = std::make_shared<SkylineCost>(
        std::make_shared<SkylineResidualModel>(horizon_, camera_, samples, options), estimated);
    // The frame's own misfit is its pixels' noise: the gate tests it unweighted.
    m.gate_scale = options.frame_weight;
    stats_->per_frame[t_ns].frame_weight = options.frame_weight;
    stats_->per_frame[t_ns].map_sigma_px = 0.0;
  } else {
    // The crest's motion and the range to the terrain making the skyline depend on where the
    // camera is: measured when the frame reaches a consumer, at that consumer's state (the crest
    // against the frame before it there). The samples are read from frames_ (held for
    // relocation) rather than copied into each block.
    m.prepare = [horizon = horizon_, camera = camera_, mount = mount_, frames = frames_, options,
                 rho_time, length_m = config_.frame_correlation_m,
                 dem_sigma_m = config_.dem_sigma_m, crests = crests_, stats = stats_, t_ns,
                 estimated](const NavState& at, const Eigen::Vector3d&,
                            BlockConsumer consumer) -> PreparedBlock {
      const std::vector<SkylineSample>& samples = frames->at(t_ns);
      auto model = std::make_shared<SkylineResidualModel>(horizon, camera, samples, options);
      // The camera pose as the cost computes it from the blocks, so that the consumer's first
      // evaluation at `at` re-uses the horizon traced here.
      Eigen::Matrix3d r_w_c;
      Eigen::Vector3d p_w_c;
      SkylineCost::CameraPose(at.q_w_b, at.p_w_b, mount.q_b_s, mount.p_b_s, &r_w_c, &p_w_c);
      // Without the ground term the frame's correlation is the time's alone (rho_time).
      double rho_ground = 1.0;
      std::optional<CrestMotion> motion;
      if (length_m > 0) {
        std::lock_guard<std::mutex> lock(crests->mutex);
        auto& seen = crests->camera_positions[consumer];
        const auto after = seen.lower_bound(t_ns);
        rho_ground = 0.0;
        if (after != seen.begin()) {
          motion = MeasureCrestMotion(*horizon, model->HorizonPoints(r_w_c, p_w_c),
                                      std::prev(after)->second, length_m);
          rho_ground = motion->rho;
        }
        seen[t_ns] = p_w_c;
      }
      // A frame's own information never vanishes (extraction noise is its own): as the
      // residual caps its samples' correlation.
      const double rho = std::min(rho_ground * rho_time, 0.999);
      const double frame_weight = std::sqrt((1.0 - rho) / (1.0 + rho));
      model->SetFrameWeight(frame_weight);
      // The map's error field on the ground has the ground term's correlation length.
      const double map_sigma_px =
          dem_sigma_m > 0 ? model->AddMapError(r_w_c, p_w_c, dem_sigma_m, length_m) : 0.0;
      if (consumer == BlockConsumer::kWindow) {
        std::lock_guard<std::mutex> lock(crests->mutex);
        stats->frame_weight_sum += frame_weight;
        ++stats->weighted_frames;
        if (motion) {
          stats->crest_shift_m_sum += motion->median_shift_m;
          ++stats->crest_frames;
        }
        stats->map_sigma_px_sum += map_sigma_px;
        SkylineFrameFigures& f = stats->per_frame[t_ns];
        f.frame_weight = frame_weight;
        f.crest_shift_m =
            motion ? motion->median_shift_m : std::numeric_limits<double>::quiet_NaN();
        f.map_sigma_px = map_sigma_px;
      }
      return PreparedBlock(std::make_shared<SkylineCost>(model, estimated), frame_weight);
    };
  }
  ++stats_->measurements;
  return m;
}

FrontendBlockTable SkylineFrontend::BlockTable() const {
  FrontendBlockTable table;
  table.columns = {"samples", "frame_weight", "crest_shift_m", "map_sigma_px"};
  for (const auto& [t, f] : stats_->per_frame) {
    table.rows[t] = {static_cast<double>(f.samples), f.frame_weight, f.crest_shift_m,
                     f.map_sigma_px};
  }
  return table;
}

std::optional<Relocation> SkylineFrontend::Relocate(const SensorMeasurement& rejected,
                                                    const NavState& estimate,
                                                    const StateCovariance& covariance,
                                                    bool after_rejections) const {
  const auto frame = frames_->find(rejected.t_ns);
  if (frame == frames_->end()) return std::nullopt;
  ++stats_->relocations_tried;
  // The estimate's camera pose; its heading is what the search sweeps, its tilt is kept.
  const Eigen::Quaterniond q_b_c = mount_.q_b_s;
  const Eigen::Matrix3d r_w_c = (estimate.q_w_b * q_b_c).toRotationMatrix();
  const Eigen::Vector3d p_w_c = estimate.p_w_b + estimate.q_w_b * mount_.p_b_s;
  const double heading = HeadingRad(estimate.q_w_b);
  // R_w_c = Rz(-heading) r_level: the levelled attitude at heading 0.
  const Eigen::Matrix3d r_level = Eigen::AngleAxisd(heading, Eigen::Vector3d::UnitZ()) * r_w_c;
  const double sigma_h = std::sqrt(covariance(kPos, kPos) + covariance(kPos + 1, kPos + 1));
  const double sigma_psi = std::sqrt(covariance(kRot + 2, kRot + 2));
  FrameLocatorOptions o;
  o.residual = residual_options();
  o.dem_sigma_m = config_.dem_sigma_m;
  o.map_correlation_m = config_.frame_correlation_m;
  o.min_samples = config_.min_samples;
  // After rejections the estimate may be overconfident: search at least relocate_min_radius_m.
  // An uncertain heading with a well-known position (GNSS) needs only its 3 sigma.
  o.search_radius_m =
      std::clamp(3.0 * sigma_h, after_rejections ? config_.relocate_min_radius_m : 10.0, 3000.0);
  o.grid_step_m = o.search_radius_m / (after_rejections ? 8.0 : 2.0);
  o.prior_heading_deg = heading * 180.0 / M_PI;
  o.heading_window_deg = std::max(10.0, 3.0 * sigma_psi * 180.0 / M_PI);
  o.tilt_sigma_rad = 2.0 * M_PI / 180.0;
  o.height_sigma_m = std::max(1.0, std::sqrt(covariance(kPos + 2, kPos + 2)));
  const FrameLocation loc = LocateFrame(horizon_, camera_, frame->second, r_level, p_w_c, o);
  if (!loc.ok || loc.ambiguity > 0.5 || !loc.covariance.allFinite()) return std::nullopt;
  ++stats_->relocations_found;
  Relocation r;
  r.q_w_b = loc.q_w_c * q_b_c.conjugate();
  r.p_w_b = loc.p_w_c - r.q_w_b * mount_.p_b_s;
  r.covariance = loc.covariance;
  r.reason = fmt::format("global search: {:.0f} m and {:.1f} deg from the estimate, RMS {:.2f} px",
                         (r.p_w_b - estimate.p_w_b).head<2>().norm(),
                         r.q_w_b.angularDistance(estimate.q_w_b) * 180.0 / M_PI, loc.rms_px);
  return r;
}

std::optional<Relocation> SkylineFrontend::Locate(TimeNs t_ns,
                                                  const Eigen::Vector3d& up_b,
                                                  const Eigen::Vector3d& prior_p_w_b,
                                                  double radius_m) const {
  const auto frame = frames_->find(t_ns);
  if (frame == frames_->end() || !(up_b.norm() > 0)) return std::nullopt;
  // A body attitude with that up and some heading: the search sweeps the heading.
  const Eigen::Quaterniond q_tilt =
      Eigen::Quaterniond::FromTwoVectors(up_b.normalized(), Eigen::Vector3d::UnitZ());
  const Eigen::Matrix3d r_level = (q_tilt * mount_.q_b_s).toRotationMatrix();
  const Eigen::Vector3d p_w_c = prior_p_w_b + q_tilt * mount_.p_b_s;
  FrameLocatorOptions o;
  o.residual = residual_options();
  o.dem_sigma_m = config_.dem_sigma_m;
  o.map_correlation_m = config_.frame_correlation_m;
  o.min_samples = config_.min_samples;
  o.search_radius_m = radius_m;
  o.grid_step_m = std::max(25.0, radius_m / 10.0);
  o.tilt_sigma_rad = 2.0 * M_PI / 180.0;
  const FrameLocation loc = LocateFrame(horizon_, camera_, frame->second, r_level, p_w_c, o);
  if (!loc.ok || loc.ambiguity > 0.5 || !loc.covariance.allFinite()) return std::nullopt;
  Relocation r;
  r.q_w_b = loc.q_w_c * mount_.q_b_s.conjugate();
  r.p_w_b = loc.p_w_c - r.q_w_b * mount_.p_b_s;
  r.covariance = loc.covariance;
  r.reason = fmt::format("global search within {:.0f} m: RMS {:.2f} px, ambiguity {:.2f}", radius_m,
                         loc.rms_px, loc.ambiguity);
  return r;
}

std::vector<TimeNs> SkylineFrontend::FrameTimes() const {
  std::vector<TimeNs> t;
  for (const auto& [time, samples] : *frames_) t.push_back(time);
  return t;
}

}  // namespace skerry::skyline
