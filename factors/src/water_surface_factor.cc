#include "skerry/factors/water_surface_factor.h"

#include <cmath>
#include <stdexcept>

namespace skerry {

WaterSurfaceFactor::WaterSurfaceFactor(double origin_height_m,
                                       double radius_m,
                                       double height_m,
                                       double sigma_m)
    : offset_m_(origin_height_m - height_m),
      inv_two_radius_(0.5 / radius_m),
      inv_sigma_(1.0 / sigma_m) {
  if (!(sigma_m > 0.0) || !(radius_m > 0.0) || !std::isfinite(offset_m_)) {
    throw std::invalid_argument(
        "WaterSurfaceFactor: sigma and radius must be positive, heights finite");
  }
}

bool WaterSurfaceFactor::Evaluate(double const* const* parameters,
                                  double* residuals,
                                  double** jacobians) const {
  const double* p = parameters[0];
  residuals[0] = (offset_m_ + p[2] + (p[0] * p[0] + p[1] * p[1]) * inv_two_radius_) * inv_sigma_;
  if (jacobians != nullptr && jacobians[0] != nullptr) {
    jacobians[0][0] = 2.0 * p[0] * inv_two_radius_ * inv_sigma_;
    jacobians[0][1] = 2.0 * p[1] * inv_two_radius_ * inv_sigma_;
    jacobians[0][2] = inv_sigma_;
  }
  return true;
}

}  // namespace skerry
