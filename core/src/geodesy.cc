#include "skerry/core/geodesy.h"

#include <GeographicLib/LocalCartesian.hpp>

namespace skerry {

struct LocalFrame::Impl {
  explicit Impl(const GeoOrigin& origin)
      : frame(origin.lat_deg, origin.lon_deg, origin.height_m, GeographicLib::Geocentric::WGS84()) {
  }
  GeographicLib::LocalCartesian frame;
};

LocalFrame::LocalFrame(const GeoOrigin& origin)
    : origin_(origin), impl_(std::make_unique<Impl>(origin)) {}

LocalFrame::~LocalFrame() = default;

LocalFrame::LocalFrame(const LocalFrame& other)
    : origin_(other.origin_), impl_(std::make_unique<Impl>(*other.impl_)) {}

LocalFrame& LocalFrame::operator=(const LocalFrame& other) {
  if (this != &other) {
    origin_ = other.origin_;
    impl_ = std::make_unique<Impl>(*other.impl_);
  }
  return *this;
}

Eigen::Vector3d LocalFrame::ToEnu(double lat_deg, double lon_deg, double height_m) const {
  Eigen::Vector3d p;
  impl_->frame.Forward(lat_deg, lon_deg, height_m, p.x(), p.y(), p.z());
  return p;
}

Eigen::Vector3d LocalFrame::ToGeodetic(const Eigen::Vector3d& p_enu) const {
  Eigen::Vector3d llh;
  impl_->frame.Reverse(p_enu.x(), p_enu.y(), p_enu.z(), llh.x(), llh.y(), llh.z());
  return llh;
}

}  // namespace skerry
