// The Earth model against numbers from outside GeographicLib: the WGS84 rotation rate and its
// components at a latitude, Somigliana's closed-form normal gravity (NIMA TR8350.2, eq. 4-1 and
// the height series 4-3), the free-air gradient, and the tilt of the vertical and the drop of
// the surface below the tangent plane away from the origin.

#include "skerry/core/earth_model.h"

#include <gtest/gtest.h>

#include <cmath>

namespace skerry {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr double kOmega = 7.292115e-5;  // WGS84 rotation rate, rad/s
constexpr double kA = 6378137.0;
constexpr double kF = 1.0 / 298.257223563;
constexpr double kE2 = kF * (2.0 - kF);

// Somigliana (TR8350.2 eq. 4-1) with the second-order height series (eq. 4-3).
double NormalGravityMagnitude(double lat_deg, double h) {
  const double s2 = std::pow(std::sin(lat_deg * kDeg), 2);
  const double gamma_e = 9.7803253359, k = 0.00193185265241, m = 0.00344978650684;
  const double gamma = gamma_e * (1.0 + k * s2) / std::sqrt(1.0 - kE2 * s2);
  return gamma * (1.0 - 2.0 / kA * (1.0 + kF + m - 2.0 * kF * s2) * h + 3.0 * h * h / (kA * kA));
}

TEST(EarthModel, RotationRateComponentsAtTheOrigin) {
  const EarthModel earth({47.0, 9.0, 0.0});
  const Eigen::Vector3d w = earth.omega_ie_w();
  EXPECT_NEAR(w.norm(), kOmega, 1e-12);
  EXPECT_NEAR(w.x(), 0.0, 1e-15);                             // no east component
  EXPECT_NEAR(w.y(), kOmega * std::cos(47.0 * kDeg), 1e-12);  // 10.3 deg/h north
  EXPECT_NEAR(w.z(), kOmega * std::sin(47.0 * kDeg), 1e-12);  // 11.0 deg/h up
  const double deg_h = 180.0 / M_PI * 3600.0;
  EXPECT_NEAR(w.y() * deg_h, 10.26, 0.01);
  EXPECT_NEAR(w.z() * deg_h, 11.00, 0.01);
}

TEST(EarthModel, NormalGravityAtTheOriginIsSomigliana) {
  for (const double lat : {0.0, 30.0, 47.6, 54.2, 89.0}) {
    for (const double h : {0.0, 440.0, 2000.0}) {
      const EarthModel earth({lat, 9.45, h});
      const Eigen::Vector3d g = earth.Gravity(Eigen::Vector3d::Zero());
      EXPECT_NEAR(g.norm(), NormalGravityMagnitude(lat, h), 2e-6) << lat << " " << h;
      // Along the ellipsoid normal up to the curvature of the normal plumb line, 0.17" per km
      // of height times sin(2 lat) (Heiskanen and Moritz 1967, "Physical Geodesy", eq. 5-34).
      const double curvature_rad = 0.17 / 3600.0 * kDeg * h / 1000.0 * std::sin(2.0 * lat * kDeg);
      EXPECT_NEAR(g.head<2>().norm() / g.norm(), std::abs(curvature_rad), 0.1e-6)
          << lat << " " << h;
      EXPECT_NEAR(g.x(), 0.0, 1e-12);
      EXPECT_LT(g.z(), 0.0);
    }
  }
}

TEST(EarthModel, TwentyKilometresAwayTheVerticalTiltsAndTheSurfaceDrops) {
  const GeoOrigin origin{47.6, 9.45, 0.0};
  const EarthModel earth(origin);
  const LocalFrame frame(origin);
  // A point on the ellipsoid 20 km east along the parallel.
  const double n_radius = kA / std::sqrt(1.0 - kE2 * std::pow(std::sin(47.6 * kDeg), 2));
  const double dlon_deg = 20000.0 / (n_radius * std::cos(47.6 * kDeg)) / kDeg;
  const Eigen::Vector3d p = frame.ToEnu(47.6, 9.45 + dlon_deg, 0.0);
  EXPECT_NEAR(p.x(), 20000.0, 5.0);
  EXPECT_NEAR(p.z(), -20000.0 * 20000.0 / (2.0 * n_radius), 0.5);  // 31 m below the plane
  const Eigen::Vector3d g = earth.Gravity(p);
  // Tilted towards the origin by the angle subtended at the centre of the parallel's curvature.
  const double tilt = 20000.0 / n_radius;  // 3.13 mrad
  EXPECT_NEAR(-g.x() / g.norm(), tilt, 2e-5);
  EXPECT_NEAR(g.x(), -0.0307, 2e-4);  // the 30 mm/s^2
  EXPECT_NEAR(g.norm(), NormalGravityMagnitude(47.6, 0.0), 1e-6);
  // The local level frame there: its up is the ellipsoid normal, i.e. along -g.
  const Eigen::Matrix3d R_w_n = earth.LocalLevel(p);
  EXPECT_LT((R_w_n.transpose() * R_w_n - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  EXPECT_LT((R_w_n.col(2) + g.normalized()).norm(), 1e-6);
  // and its north has turned by the meridian convergence dlon sin(lat) (0.19 deg).
  const double convergence = std::atan2(-R_w_n(0, 1), R_w_n(1, 1));
  EXPECT_NEAR(convergence, dlon_deg * kDeg * std::sin(47.6 * kDeg), 1e-5);
  EXPECT_TRUE(earth.LocalLevel(Eigen::Vector3d::Zero()).isIdentity(1e-12));
}

TEST(EarthModel, GravityGradientIsTheFreeAirGradient) {
  const EarthModel earth({47.6, 9.45, 400.0});
  const LocalGravity lg = earth.GravityNear(Eigen::Vector3d(100.0, -200.0, 0.0));
  // d g_up / d up = +2 g / R (less pull higher up): 3.08e-6 1/s^2 at mid latitudes.
  EXPECT_NEAR(lg.dg_dp(2, 2), 3.08e-6, 0.03e-6);
  // Horizontally g turns towards the centre: d g_e / d e = -g / N, d g_n / d n = -g / M.
  EXPECT_NEAR(lg.dg_dp(0, 0), -9.81 / 6.389e6, 0.02e-6);
  EXPECT_NEAR(lg.dg_dp(1, 1), -9.81 / 6.370e6, 0.02e-6);
  // The tensor is symmetric (gravity has a potential) and its trace is 2 omega^2 (Poisson's
  // equation outside the masses, with the centrifugal potential's Laplacian).
  EXPECT_LT((lg.dg_dp - lg.dg_dp.transpose()).cwiseAbs().maxCoeff(), 1e-11);
  EXPECT_NEAR(lg.dg_dp.trace(), 2.0 * kOmega * kOmega, 1e-10);
  // The first-order model against the model itself 3 km away: error ~ g d^2 / R^2.
  const Eigen::Vector3d q(2000.0, 2000.0, 500.0);
  EXPECT_LT((lg.At<double>(q) - earth.Gravity(q)).norm(), 5e-6);
  EXPECT_GT((lg.g_ref_w - earth.Gravity(q)).norm(), 4e-3);  // a constant would be far off
}

TEST(EarthModel, FlatIsConstantAndStill) {
  const EarthModel flat = EarthModel::Flat(9.81);
  EXPECT_EQ(flat.kind(), EarthKind::kFlat);
  EXPECT_EQ(flat.omega_ie_w(), Eigen::Vector3d::Zero());
  EXPECT_EQ(flat.Gravity(Eigen::Vector3d(3e4, -2e4, 100.0)), Eigen::Vector3d(0.0, 0.0, -9.81));
  EXPECT_TRUE(flat.GravityNear(Eigen::Vector3d(1e4, 0, 0)).dg_dp.isZero());
  EXPECT_TRUE(flat.LocalLevel(Eigen::Vector3d(1e4, 0, 0)).isIdentity());
  EarthKind k;
  EXPECT_TRUE(ParseEarthKind("flat", &k));
  EXPECT_EQ(k, EarthKind::kFlat);
  EXPECT_TRUE(ParseEarthKind("wgs84", &k));
  EXPECT_EQ(k, EarthKind::kWgs84);
  EXPECT_FALSE(ParseEarthKind("round", &k));
  EXPECT_EQ(EarthKindName(EarthKind::kFlat), "flat");
}

}  // namespace
}  // namespace skerry
