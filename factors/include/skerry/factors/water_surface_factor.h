#pragma once
/// \file
/// Water-surface factor: a vessel floats. The ellipsoidal height of its body origin stays at the
/// height it has afloat, `height_m` (the water surface's ellipsoidal height plus the origin's
/// height above the waterline), up to the waves: sigma_m covers heave, and the roll and pitch of a
/// body origin off the centre of motion. In the local ENU frame at the dataset origin the
/// ellipsoidal height of a point p = (x, y, z) a few kilometres away is
///   h(p) = h_0 + z + (x^2 + y^2) / (2 R) + O(d^4 / R^3)
/// (h_0 the origin's, R the Gaussian mean radius of curvature sqrt(M N) at the origin: the
/// tangent plane rises above the ellipsoid by d^2 / 2R, 7.8 m at 10 km; the next term is 1e-5 m
/// there, the difference between the meridian and prime-vertical radii 2 cm), and
///   r = (h(p_w_b) - height_m) / sigma_m.
/// Prior work's planar EKF assumed the same implicitly; here it is a measurement, gated, so that
/// a tide or a lock can be seen. Parameter block: p_w_b[3].

#include <ceres/sized_cost_function.h>

#include <memory>

namespace skerry {

class WaterSurfaceFactor : public ceres::SizedCostFunction<1, 3> {
 public:
  /// `origin_height_m`: h_0; `radius_m`: R; `height_m`, `sigma_m` as above (sigma > 0).
  WaterSurfaceFactor(double origin_height_m, double radius_m, double height_m, double sigma_m);

  bool Evaluate(double const* const* parameters,
                double* residuals,
                double** jacobians) const override;

 private:
  double offset_m_;  ///< h_0 - height_m
  double inv_two_radius_;
  double inv_sigma_;
};

}  // namespace skerry
