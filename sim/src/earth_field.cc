#include "skerry/sim/earth_field.h"

#include <GeographicLib/LocalCartesian.hpp>
#include <GeographicLib/NormalGravity.hpp>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace skerry::sim {
namespace {

constexpr double kDeg = 3.14159265358979323846 / 180.0;

Eigen::Matrix3d FromRowMajor(const std::vector<double>& m) {
  Eigen::Matrix3d R;
  R << m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8];
  return R;
}

}  // namespace

struct EarthField::Impl {
  explicit Impl(const GeoOrigin& o)
      : frame(o.lat_deg, o.lon_deg, o.height_m, GeographicLib::Geocentric::WGS84()) {}
  GeographicLib::LocalCartesian frame;
};

EarthField::EarthField(const GeoOrigin& origin, const EarthConfig& earth)
    : origin_(origin), earth_(earth) {
  if (earth_.kind == EarthKind::kFlat) return;
  impl_ = std::make_unique<Impl>(origin);
  const double W = GeographicLib::NormalGravity::WGS84().AngularVelocity();
  // The Earth's axis in the origin's ENU: north tilted up by the latitude.
  omega_ie_w_ =
      W * Eigen::Vector3d(0.0, std::cos(origin.lat_deg * kDeg), std::sin(origin.lat_deg * kDeg));
}

EarthField::~EarthField() = default;
EarthField::EarthField(EarthField&&) noexcept = default;
EarthField& EarthField::operator=(EarthField&&) noexcept = default;

Eigen::Vector3d EarthField::ToGeodetic(const Eigen::Vector3d& p_w) const {
  if (!impl_) throw std::logic_error("EarthField::ToGeodetic on the flat Earth");
  Eigen::Vector3d llh;
  impl_->frame.Reverse(p_w.x(), p_w.y(), p_w.z(), llh.x(), llh.y(), llh.z());
  return llh;
}

Eigen::Vector3d EarthField::FromGeodetic(double lat_deg,
                                         double lon_deg,
                                         double height_m,
                                         Eigen::Matrix3d* R_w_n) const {
  if (!impl_) throw std::logic_error("EarthField::FromGeodetic on the flat Earth");
  std::vector<double> m(9);
  Eigen::Vector3d p;
  impl_->frame.Forward(lat_deg, lon_deg, height_m, p.x(), p.y(), p.z(), m);
  if (R_w_n != nullptr) *R_w_n = FromRowMajor(m);
  return p;
}

Eigen::Matrix3d EarthField::LocalLevelAt(const Eigen::Vector3d& p_w) const {
  if (!impl_) return Eigen::Matrix3d::Identity();
  double lat, lon, h;
  std::vector<double> m(9);
  impl_->frame.Reverse(p_w.x(), p_w.y(), p_w.z(), lat, lon, h, m);
  return FromRowMajor(m);
}

Eigen::Vector3d EarthField::GravityAt(const Eigen::Vector3d& p_w) const {
  if (!impl_) return Eigen::Vector3d(0.0, 0.0, -earth_.gravity_m_s2);
  double lat, lon, h;
  std::vector<double> m(9);
  impl_->frame.Reverse(p_w.x(), p_w.y(), p_w.z(), lat, lon, h, m);
  double g_north, g_up;
  GeographicLib::NormalGravity::WGS84().Gravity(lat, h, g_north, g_up);
  return FromRowMajor(m) * Eigen::Vector3d(0.0, g_north, g_up);
}

}  // namespace skerry::sim
