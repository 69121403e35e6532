#include "skerry/skyline/skyline_residual.h"

#include <cmath>
#include <limits>
#include <stdexcept>

#include "skerry/core/parallel_for.h"
#include "skerry/skyline/crest_correlation.h"

namespace skerry::skyline {
namespace {

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

// d(phi)/d(q) for Ceres' EigenQuaternionManifold (q <- Exp(phi) * q, coefficients x, y, z, w):
// phi = 2 vec(dq * conj(q)), so dphi/dq = 2 [w I + [v]x, -v].
Eigen::Matrix<double, 3, 4> LeftTangentOfQuaternion(const double* q) {
  const Eigen::Vector3d v(q[0], q[1], q[2]);
  Eigen::Matrix<double, 3, 4> m;
  m.leftCols<3>() = 2.0 * (q[3] * Eigen::Matrix3d::Identity() + Skew(v));
  m.col(3) = -2.0 * v;
  return m;
}

}  // namespace

SkylineResidualModel::SkylineResidualModel(std::shared_ptr<const HorizonPredictor> horizon,
                                           const CameraModel& camera,
                                           const std::vector<SkylineSample>& samples,
                                           const SkylineResidualOptions& options)
    : horizon_(std::move(horizon)), options_(options) {
  if (!horizon_) throw std::invalid_argument("SkylineResidualModel: no horizon predictor");
  if (!(options.sigma_px > 0) || !(options.correlation_px >= 0)) {
    throw std::invalid_argument("SkylineResidualModel: sigma_px must be > 0, correlation_px >= 0");
  }
  double prev_u = std::numeric_limits<double>::quiet_NaN();
  for (const SkylineSample& s : samples) {
    if (!s.pixel.allFinite() || !(s.weight > 0)) continue;
    const auto xy = camera.Undistort(s.pixel);
    if (!xy) continue;
    const Eigen::Vector3d ray = Eigen::Vector3d(xy->x(), xy->y(), 1.0).normalized();
    // Pixels per radian of elevation: how far the pixel moves when its ray is raised by a small
    // angle about the horizontal axis across it (the optical frame's up is -y), distortion
    // included.
    const Eigen::Vector3d axis = ray.cross(-Eigen::Vector3d::UnitY()).normalized();
    const double d = 1e-5;
    const auto raised = camera.Project(Eigen::AngleAxisd(d, axis) * ray);
    const double px_per_rad = raised ? (*raised - s.pixel).norm() / d : camera.fy();
    rays_c_.push_back(ray);
    px_per_rad_.push_back(px_per_rad);
    weight_.push_back(s.weight);
    const double du = std::abs(s.pixel.x() - prev_u);
    const bool chained = std::isfinite(du) && du <= options.max_chain_gap_px;
    chained_.push_back(chained);
    rho_px_.push_back(chained && options.correlation_px > 0 ? std::exp(-du / options.correlation_px)
                                                            : 0.0);
    prev_u = s.pixel.x();
  }
  if (rays_c_.empty()) throw std::invalid_argument("SkylineResidualModel: no usable sample");
  map_sigma_px_.assign(rays_c_.size(), 0.0);
  rho_map_.assign(rays_c_.size(), 0.0);
  UpdateScales();
}

void SkylineResidualModel::UpdateScales() {
  const size_t n = rays_c_.size();
  scale_.resize(n);
  rho_.resize(n);
  std::vector<double> sigma_px(n), sigma_map(n);
  for (size_t i = 0; i < n; ++i) {
    sigma_px[i] = options_.sigma_px / std::sqrt(weight_[i]);
    sigma_map[i] = map_sigma_px_[i];
    const double sigma = std::hypot(sigma_px[i], sigma_map[i]);
    scale_[i] = px_per_rad_[i] * options_.frame_weight / sigma;
    // The lag-1 correlation of the sum of the two independent errors (the extraction's along the
    // skyline, the map's on the ground), each sample's error normalised by its sigma.
    double rho = 0.0;
    if (i > 0 && chained_[i]) {
      if (sigma_map[i] == 0.0 && sigma_map[i - 1] == 0.0) {
        rho = rho_px_[i];  // the extraction's alone
      } else {
        rho = (sigma_px[i] * sigma_px[i - 1] * rho_px_[i] +
               sigma_map[i] * sigma_map[i - 1] * rho_map_[i]) /
              (sigma * std::hypot(sigma_px[i - 1], sigma_map[i - 1]));
      }
    }
    rho_[i] = std::min(rho, 0.999);
  }
}

void SkylineResidualModel::SetFrameWeight(double frame_weight) {
  if (!(frame_weight > 0)) {
    throw std::invalid_argument("SkylineResidualModel: frame_weight must be > 0");
  }
  options_.frame_weight = frame_weight;
  UpdateScales();
}

double SkylineResidualModel::AddMapError(const Eigen::Matrix3d& r_w_c,
                                         const Eigen::Vector3d& p_w_c,
                                         double dem_sigma_m,
                                         double correlation_m) {
  if (!(dem_sigma_m >= 0) || !std::isfinite(dem_sigma_m) || !(correlation_m >= 0) ||
      !std::isfinite(correlation_m)) {
    throw std::invalid_argument(
        "SkylineResidualModel: dem_sigma_m and correlation_m must be finite and >= 0");
  }
  double sum = 0.0;
  int n = 0;
  std::vector<TracedSample> traces;
  if (dem_sigma_m > 0) TraceAll(r_w_c, p_w_c, &traces);
  for (size_t i = 0; i < rays_c_.size(); ++i) {
    map_sigma_px_[i] = 0.0;
    rho_map_[i] = 0.0;
    if (dem_sigma_m == 0.0) continue;
    const TracedSample& h = traces[i];
    // dE / dz at the horizon's point: 0 on water, which the DEM sets level and exact.
    if (!h.usable || !(h.d_elevation_d_crest > 0)) continue;
    map_sigma_px_[i] = px_per_rad_[i] * dem_sigma_m * h.d_elevation_d_crest;
    // Neighbours on the skyline share the map's error as their ground points are near (the
    // field's exponential correlation, crest_correlation.h).
    if (i > 0 && chained_[i] && map_sigma_px_[i - 1] > 0 && correlation_m > 0) {
      rho_map_[i] = std::exp(-(h.point_w - traces[i - 1].point_w).head<2>().norm() / correlation_m);
    }
    sum += map_sigma_px_[i];
    ++n;
  }
  UpdateScales();
  return n > 0 ? sum / n : 0.0;
}

void SkylineResidualModel::TraceAll(const Eigen::Matrix3d& r_w_c,
                                    const Eigen::Vector3d& p_w_c,
                                    double refraction_k,
                                    std::vector<TracedSample>* out) const {
  {
    const std::lock_guard<std::mutex> lock(cache_->mutex);
    if (!cache_->samples.empty() && cache_->r_w_c == r_w_c && cache_->p_w_c == p_w_c &&
        cache_->refraction_k == refraction_k) {
      *out = cache_->samples;
      return;
    }
  }
  out->assign(rays_c_.size(), TracedSample{});
  // Each sample's trace on whichever thread, written to its own slot: the same on any number.
  ParallelFor(rays_c_.size(), options_.threads, [&](size_t i) {
    const Eigen::Vector3d r = r_w_c * rays_c_[i];
    if (std::sqrt(r.x() * r.x() + r.y() * r.y()) < 1e-9) return true;  // straight up or down
    const HorizonSample h = horizon_->Trace(p_w_c, std::atan2(r.x(), r.y()), refraction_k);
    if (!h.valid || h.truncated) return true;
    TracedSample& t = (*out)[i];
    t.elevation_rad = h.elevation_rad;
    t.d_elevation_d_azimuth = h.d_elevation_d_azimuth;
    t.d_elevation_d_p = h.d_elevation_d_p;
    t.point_w = h.point_w;
    t.distance_m = h.distance_m;
    t.d_elevation_d_refraction = h.d_elevation_d_refraction;
    // The land's dE / dz at the point (AddMapError, the crest offset and the gain); water is
    // level and exact.
    if (h.distance_m > 0 && !HorizonOnWater(*horizon_, h.point_w)) {
      const double c = std::cos(h.elevation_rad);
      t.d_elevation_d_crest = c * c / h.distance_m;
      t.detail_m = horizon_->DetailAt(h.point_w.x(), h.point_w.y());
    }
    t.usable = true;
    return true;
  });
  const std::lock_guard<std::mutex> lock(cache_->mutex);
  cache_->r_w_c = r_w_c;
  cache_->p_w_c = p_w_c;
  cache_->refraction_k = refraction_k;
  cache_->samples = *out;
  ++cache_->traced_poses;
}

long SkylineResidualModel::traced_poses() const {
  const std::lock_guard<std::mutex> lock(cache_->mutex);
  return cache_->traced_poses;
}

int SkylineResidualModel::Evaluate(const Eigen::Matrix3d& r_w_c,
                                   const Eigen::Vector3d& p_w_c,
                                   const SkylineMapParameters& map,
                                   double* residuals,
                                   Eigen::Matrix<double, Eigen::Dynamic, 3>* jac_rot,
                                   Eigen::Matrix<double, Eigen::Dynamic, 3>* jac_pos,
                                   const SkylineMapJacobians& jac_map) const {
  const int n = size();
  const bool jac = jac_rot != nullptr || jac_pos != nullptr || jac_map.refraction_k != nullptr ||
                   jac_map.crest_offset_m != nullptr || jac_map.detail_gain != nullptr;
  // The Jacobian rows before whitening, by column: rotation (3), position (3), then the map's
  // refraction_k, crest_offset_m and detail_gain.
  enum Column { kRot = 0, kPos = 3, kRefraction = 6, kCrest = 7, kGain = 8, kColumns = 9 };
  Eigen::Matrix<double, Eigen::Dynamic, kColumns> J;
  if (jac) J.setZero(n, kColumns);
  const double c = options_.huber_sigmas;
  int active = 0;
  thread_local std::vector<TracedSample> traces;
  TraceAll(r_w_c, p_w_c, map.refraction_k, &traces);
  // Per-sample robustified errors f_i and their Jacobian rows (before whitening).
  std::vector<double> f(n, 0.0);
  for (int i = 0; i < n; ++i) {
    const TracedSample& h = traces[static_cast<size_t>(i)];
    if (!h.usable) continue;
    const Eigen::Vector3d r = r_w_c * rays_c_[i];
    const double rho2 = r.x() * r.x() + r.y() * r.y();
    const double rho = std::sqrt(rho2);
    const double e_obs = std::atan2(r.z(), rho);
    ++active;
    const double raise_m = map.crest_offset_m + map.detail_gain * h.detail_m;
    const double e = scale_[i] * (e_obs - (h.elevation_rad + raise_m * h.d_elevation_d_crest));
    double g = 1.0;  // d f / d e
    if (c > 0 && std::abs(e) > c) {
      const double fe = std::sqrt(2.0 * c * std::abs(e) - c * c);
      f[i] = e > 0 ? fe : -fe;
      g = c / fe;
    } else {
      f[i] = e;
    }
    if (jac) {
      const double n2 = rho2 + r.z() * r.z();
      const Eigen::Vector3d de_obs(-r.z() * r.x() / (rho * n2), -r.z() * r.y() / (rho * n2),
                                   rho / n2);
      const Eigen::Vector3d daz(r.y() / rho2, -r.x() / rho2, 0.0);
      const Eigen::Vector3d d_dr = de_obs - h.d_elevation_d_azimuth * daz;
      // r <- Exp(theta) r: dr/dtheta = -[r]x.
      J.block<1, 3>(i, kRot) = g * scale_[i] * (d_dr.transpose() * -Skew(r));
      J.block<1, 3>(i, kPos) = -g * scale_[i] * h.d_elevation_d_p.transpose();
      J(i, kRefraction) = -g * scale_[i] * h.d_elevation_d_refraction;
      J(i, kCrest) = -g * scale_[i] * h.d_elevation_d_crest;
      J(i, kGain) = J(i, kCrest) * h.detail_m;
    }
  }
  // AR(1) whitening along the skyline.
  for (int i = 0; i < n; ++i) {
    const double rho = rho_[i];
    if (rho == 0.0) {
      residuals[i] = f[i];
    } else {
      const double k = 1.0 / std::sqrt(1.0 - rho * rho);
      residuals[i] = k * (f[i] - rho * f[i - 1]);
    }
  }
  if (jac) {
    Eigen::Matrix<double, Eigen::Dynamic, kColumns> W(n, kColumns);
    for (int i = 0; i < n; ++i) {
      const double rho = rho_[i];
      if (rho == 0.0) {
        W.row(i) = J.row(i);
      } else {
        const double k = 1.0 / std::sqrt(1.0 - rho * rho);
        W.row(i) = k * (J.row(i) - rho * J.row(i - 1));
      }
    }
    if (jac_rot) *jac_rot = W.middleCols<3>(kRot);
    if (jac_pos) *jac_pos = W.middleCols<3>(kPos);
    if (jac_map.refraction_k) *jac_map.refraction_k = W.col(kRefraction);
    if (jac_map.crest_offset_m) *jac_map.crest_offset_m = W.col(kCrest);
    if (jac_map.detail_gain) *jac_map.detail_gain = W.col(kGain);
  }
  return active;
}

std::vector<Eigen::Vector3d> SkylineResidualModel::HorizonPoints(
    const Eigen::Matrix3d& r_w_c, const Eigen::Vector3d& p_w_c) const {
  std::vector<TracedSample> traces;
  TraceAll(r_w_c, p_w_c, &traces);
  std::vector<Eigen::Vector3d> out(
      traces.size(), Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN()));
  for (size_t i = 0; i < traces.size(); ++i) {
    if (traces[i].usable) out[i] = traces[i].point_w;
  }
  return out;
}

std::vector<double> SkylineResidualModel::PixelErrors(const Eigen::Matrix3d& r_w_c,
                                                      const Eigen::Vector3d& p_w_c) const {
  std::vector<double> out(size(), std::numeric_limits<double>::quiet_NaN());
  std::vector<TracedSample> traces;
  TraceAll(r_w_c, p_w_c, &traces);
  for (int i = 0; i < size(); ++i) {
    const TracedSample& h = traces[static_cast<size_t>(i)];
    if (!h.usable) continue;
    const Eigen::Vector3d r = r_w_c * rays_c_[i];
    const double raise_m = options_.crest_offset_m + options_.detail_gain * h.detail_m;
    out[i] = px_per_rad_[i] * (std::atan2(r.z(), std::hypot(r.x(), r.y())) -
                               (h.elevation_rad + raise_m * h.d_elevation_d_crest));
  }
  return out;
}

SkylineCost::SkylineCost(std::shared_ptr<const SkylineResidualModel> model,
                         SkylineParameter parameter)
    : model_(std::move(model)), parameter_(parameter) {
  if (parameter_ == SkylineParameter::kDetailGain && !model_->horizon().has_detail()) {
    throw std::invalid_argument("SkylineCost: a sharpening gain needs a map with its detail");
  }
  set_num_residuals(model_->size());
  *mutable_parameter_block_sizes() = {4, 3, 4, 3};
  if (parameter_ != SkylineParameter::kNone) mutable_parameter_block_sizes()->push_back(1);
}

void SkylineCost::CameraPose(const Eigen::Quaterniond& q_w_b,
                             const Eigen::Vector3d& p_w_b,
                             const Eigen::Quaterniond& q_b_c,
                             const Eigen::Vector3d& p_b_c,
                             Eigen::Matrix3d* r_w_c,
                             Eigen::Vector3d* p_w_c) {
  const Eigen::Matrix3d r_w_b = q_w_b.normalized().toRotationMatrix();
  *r_w_c = r_w_b * q_b_c.normalized().toRotationMatrix();
  *p_w_c = p_w_b + r_w_b * p_b_c;
}

bool SkylineCost::Evaluate(double const* const* parameters,
                           double* residuals,
                           double** jacobians) const {
  const Eigen::Map<const Eigen::Quaterniond> q_w_b(parameters[0]);
  const Eigen::Map<const Eigen::Vector3d> p_w_b(parameters[1]);
  const Eigen::Map<const Eigen::Quaterniond> q_b_c(parameters[2]);
  const Eigen::Map<const Eigen::Vector3d> p_b_c(parameters[3]);
  Eigen::Matrix3d r_w_c;
  Eigen::Vector3d p_w_c;
  CameraPose(q_w_b, p_w_b, q_b_c, p_b_c, &r_w_c, &p_w_c);
  const Eigen::Matrix3d r_w_b = q_w_b.normalized().toRotationMatrix();
  const Eigen::Vector3d lever_w = r_w_b * p_b_c;
  if (!r_w_c.allFinite() || !p_w_c.allFinite()) return false;
  // The estimated number replaces the model's, and its derivative is the one asked for.
  SkylineMapParameters map = model_->MapParameters();
  Eigen::VectorXd j_map;
  SkylineMapJacobians want;
  double* estimated = nullptr;
  switch (parameter_) {
    case SkylineParameter::kRefraction:
      estimated = &map.refraction_k;
      want.refraction_k = &j_map;
      break;
    case SkylineParameter::kCrestOffset:
      estimated = &map.crest_offset_m;
      want.crest_offset_m = &j_map;
      break;
    case SkylineParameter::kDetailGain:
      estimated = &map.detail_gain;
      want.detail_gain = &j_map;
      break;
    case SkylineParameter::kNone:
      break;
  }
  if (estimated != nullptr) {
    *estimated = parameters[4][0];
    if (!std::isfinite(*estimated)) return false;
  }
  const int n = model_->size();
  if (!jacobians) {
    model_->Evaluate(r_w_c, p_w_c, map, residuals, nullptr, nullptr);
    return true;
  }
  Eigen::Matrix<double, Eigen::Dynamic, 3> jr, jp;
  model_->Evaluate(r_w_c, p_w_c, map, residuals, &jr, &jp, want);
  if (estimated != nullptr && jacobians[4]) Eigen::Map<Eigen::VectorXd>(jacobians[4], n) = j_map;
  using RowMajor4 = Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor>;
  using RowMajor3 = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
  if (jacobians[0]) {
    // R_w_b <- Exp(phi) R_w_b turns R_w_c by phi and the lever arm by -[lever]x phi.
    const Eigen::Matrix<double, Eigen::Dynamic, 3> j_phi = jr - jp * Skew(lever_w);
    Eigen::Map<RowMajor4>(jacobians[0], n, 4) = j_phi * LeftTangentOfQuaternion(parameters[0]);
  }
  if (jacobians[1]) Eigen::Map<RowMajor3>(jacobians[1], n, 3) = jp;
  if (jacobians[2]) {
    // R_b_c <- Exp(psi) R_b_c turns R_w_c by R_w_b psi.
    Eigen::Map<RowMajor4>(jacobians[2], n, 4) =
        (jr * r_w_b) * LeftTangentOfQuaternion(parameters[2]);
  }
  if (jacobians[3]) Eigen::Map<RowMajor3>(jacobians[3], n, 3) = jp * r_w_b;
  return true;
}

}  // namespace skerry::skyline
