#include "skerry/core/geodesy.h"

#include <gtest/gtest.h>

#include <cmath>

namespace skerry {
namespace {

TEST(GeodesyTest, OriginMapsToZero) {
  const LocalFrame frame({47.6, 9.4, 440.0});
  EXPECT_LT(frame.ToEnu(47.6, 9.4, 440.0).norm(), 1e-9);
}

TEST(GeodesyTest, RoundTrip) {
  const LocalFrame frame({47.6, 9.4, 440.0});
  const LocalFrame copy = frame;  // the pimpl must copy
  for (const Eigen::Vector3d& p :
       {Eigen::Vector3d(1234.5, -678.9, 12.3), Eigen::Vector3d(-25000.0, 40000.0, -300.0)}) {
    const Eigen::Vector3d llh = copy.ToGeodetic(p);
    EXPECT_LT((frame.ToEnu(llh.x(), llh.y(), llh.z()) - p).norm(), 1e-6);
  }
}

// Independent of GeographicLib: WGS84 meridian and prime-vertical radii of curvature give the
// metres per degree for a small offset, M = a(1-e^2)/W^3 and N cos(lat) = a cos(lat)/W.
TEST(GeodesyTest, SmallOffsetsMatchEllipsoidGeometry) {
  const double a = 6378137.0;
  const double f = 1.0 / 298.257223563;
  const double e2 = f * (2.0 - f);
  for (double lat : {0.0, 47.6, -33.9}) {
    const double lat_rad = lat * M_PI / 180.0;
    const double w = std::sqrt(1.0 - e2 * std::sin(lat_rad) * std::sin(lat_rad));
    const double m_per_deg_lat = a * (1.0 - e2) / (w * w * w) * M_PI / 180.0;
    const double m_per_deg_lon = a * std::cos(lat_rad) / w * M_PI / 180.0;
    const LocalFrame frame({lat, 9.4, 100.0});
    const double d = 1e-5;  // about 1 m
    const Eigen::Vector3d north = frame.ToEnu(lat + d, 9.4, 100.0);
    const Eigen::Vector3d east = frame.ToEnu(lat, 9.4 + d, 100.0);
    // Radii at height h: (M + h), (N + h) cos(lat); h = 100 m changes them by 1.6e-5.
    EXPECT_NEAR(north.y(), d * m_per_deg_lat * (1.0 + 100.0 / 6.37e6), 1e-5);
    EXPECT_NEAR(north.x(), 0.0, 1e-9);
    EXPECT_NEAR(east.x(), d * m_per_deg_lon * (1.0 + 100.0 / 6.37e6), 1e-5);
    EXPECT_NEAR(east.y(), 0.0, 1e-6);
    EXPECT_NEAR(frame.ToEnu(lat, 9.4, 101.0).z(), 1.0, 1e-9);
  }
  // The classic figure: at the equator 1 degree of latitude is 110574 m.
  const LocalFrame equator({0.0, 0.0, 0.0});
  EXPECT_NEAR(equator.ToEnu(1.0 / 110574.0, 0.0, 0.0).y(), 1.0, 1e-4);
}

}  // namespace
}  // namespace skerry
