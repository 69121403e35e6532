#include "skerry/core/earth_model.h"

#include <GeographicLib/Geocentric.hpp>
#include <GeographicLib/NormalGravity.hpp>
#include <vector>

namespace skerry {

namespace {
// Row-major 3x3 as GeographicLib writes it (its M maps local ENU to geocentric).
Eigen::Matrix3d FromRowMajor(const std::vector<double>& m) {
  Eigen::Matrix3d R;
  R << m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8];
  return R;
}
}  // namespace

std::string EarthKindName(EarthKind kind) { return kind == EarthKind::kFlat ? "flat" : "wgs84"; }

bool ParseEarthKind(const std::string& name, EarthKind* kind) {
  if (name == "wgs84") {
    *kind = EarthKind::kWgs84;
  } else if (name == "flat") {
    *kind = EarthKind::kFlat;
  } else {
    return false;
  }
  return true;
}

struct EarthModel::Impl {
  Eigen::Vector3d origin_e;  ///< origin in ECEF, m
  Eigen::Matrix3d R_e_w;     ///< w (ENU at the origin) -> ECEF

  Eigen::Vector3d ToEcef(const Eigen::Vector3d& p_w) const { return origin_e + R_e_w * p_w; }
};

EarthModel::EarthModel(const GeoOrigin& origin,
                       const EarthConfig& config,
                       std::shared_ptr<const Impl> impl,
                       const Eigen::Vector3d& omega_ie_w)
    : origin_(origin), config_(config), impl_(std::move(impl)), omega_ie_w_(omega_ie_w) {}

EarthModel::EarthModel(const GeoOrigin& origin, const EarthConfig& config)
    : origin_(origin), config_(config) {
  if (config_.kind == EarthKind::kFlat) return;
  auto impl = std::make_shared<Impl>();
  std::vector<double> m(9);
  GeographicLib::Geocentric::WGS84().Forward(origin.lat_deg, origin.lon_deg, origin.height_m,
                                             impl->origin_e.x(), impl->origin_e.y(),
                                             impl->origin_e.z(), m);
  impl->R_e_w = FromRowMajor(m);
  // The Earth turns about the ECEF z axis at the WGS84 rate.
  const double omega = GeographicLib::NormalGravity::WGS84().AngularVelocity();
  omega_ie_w_ = impl->R_e_w.transpose() * Eigen::Vector3d(0.0, 0.0, omega);
  impl_ = std::move(impl);
}

EarthModel EarthModel::Flat(double gravity_m_s2) {
  EarthConfig c;
  c.kind = EarthKind::kFlat;
  c.gravity_m_s2 = gravity_m_s2;
  return EarthModel(GeoOrigin{}, c, nullptr, Eigen::Vector3d::Zero());
}

Eigen::Vector3d EarthModel::Gravity(const Eigen::Vector3d& p_w) const {
  if (!impl_) return Eigen::Vector3d(0.0, 0.0, -config_.gravity_m_s2);
  const Eigen::Vector3d x = impl_->ToEcef(p_w);
  Eigen::Vector3d g_e;
  GeographicLib::NormalGravity::WGS84().U(x.x(), x.y(), x.z(), g_e.x(), g_e.y(), g_e.z());
  return impl_->R_e_w.transpose() * g_e;
}

LocalGravity EarthModel::GravityNear(const Eigen::Vector3d& p_w) const {
  LocalGravity lg;
  lg.p_ref_w = p_w;
  lg.g_ref_w = Gravity(p_w);
  if (!impl_) return lg;
  // Central differences over 10 m: the gradient is ~3e-6 1/s^2 and its own change over 10 m
  // ~5e-12, so the truncation error is ~1e-10 relative and the round-off (1e-15 m/s^2 over 20 m)
  // smaller still.
  constexpr double kStep = 10.0;
  for (int k = 0; k < 3; ++k) {
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    d[k] = kStep;
    lg.dg_dp.col(k) = (Gravity(p_w + d) - Gravity(p_w - d)) / (2.0 * kStep);
  }
  return lg;
}

Eigen::Matrix3d EarthModel::LocalLevel(const Eigen::Vector3d& p_w) const {
  if (!impl_) return Eigen::Matrix3d::Identity();
  const Eigen::Vector3d x = impl_->ToEcef(p_w);
  double lat, lon, h;
  std::vector<double> m(9);
  GeographicLib::Geocentric::WGS84().Reverse(x.x(), x.y(), x.z(), lat, lon, h, m);
  return impl_->R_e_w.transpose() * FromRowMajor(m);
}

}  // namespace skerry
