#include "skerry/skyline/frame_locator.h"

#include <gtest/gtest.h>

#include <random>

#include "skerry/sim/dem_error.h"
#include "skyline/skyline_test_scene.h"

namespace skerry::skyline {
namespace {

constexpr double kDeg = M_PI / 180.0;

Eigen::Matrix3d Level(double roll_deg, double pitch_deg) {
  // A forward camera on a body rolled and pitched, heading north... then with heading removed:
  // R_w_c = Rz(-heading) * Level.
  const Eigen::Quaterniond q_w_b(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(pitch_deg * kDeg, Eigen::Vector3d::UnitY()) *
                                 Eigen::AngleAxisd(roll_deg * kDeg, Eigen::Vector3d::UnitX()));
  return (q_w_b * LevelCameraRotation(0.0)).toRotationMatrix();
}

// From one frame, with the prior 600 m off and no heading: position and heading recovered.
TEST(FrameLocator, GlobalSearchFindsPositionAndHeadingFromOneFrame) {
  const auto horizon = std::make_shared<HorizonPredictor>(testing::MountainRing());
  CameraConfig config = PinholeFromFov("camera", 1920, 1080, 70.0);
  const CameraModel camera(config);
  const Eigen::Matrix3d level = Level(1.5, -1.0);
  const double heading = 217.0 * kDeg;
  const Eigen::Matrix3d r_w_c = Eigen::AngleAxisd(-heading, Eigen::Vector3d::UnitZ()) * level;
  const Eigen::Vector3d p_w_c(-350.0, 420.0, 5.0);
  const auto samples = testing::SyntheticSkyline(*horizon, camera, r_w_c, p_w_c, 8);
  FrameLocatorOptions o;
  o.search_radius_m = 1000.0;
  const Eigen::Vector3d prior(150.0, 800.0, 5.0);  // 630 m off
  const FrameLocation loc = LocateFrame(horizon, camera, samples, level, prior, o);
  ASSERT_TRUE(loc.ok) << loc.reason;
  EXPECT_LT((loc.p_w_c - p_w_c).head<2>().norm(), 1.0) << loc.p_w_c.transpose();
  EXPECT_LT(Eigen::Quaterniond(r_w_c).angularDistance(loc.q_w_c), 0.02 * kDeg);
  EXPECT_LT(loc.rms_px, 0.2);
  EXPECT_LT(loc.ambiguity, 0.5);
  EXPECT_TRUE(loc.covariance.allFinite());
  std::printf("located in %.2f s, %d candidates, ambiguity %.3g, sigma %.2f m\n", loc.seconds,
              loc.candidates_refined, loc.ambiguity, std::sqrt(loc.covariance(3, 3)));

  // On three threads (skyline.threads: the grid's nodes and the candidates' refinements shared
  // among them) the same location to the last bit.
  o.residual.threads = 3;
  const FrameLocation threaded = LocateFrame(horizon, camera, samples, level, prior, o);
  ASSERT_TRUE(threaded.ok) << threaded.reason;
  EXPECT_EQ(threaded.p_w_c, loc.p_w_c);
  EXPECT_EQ(threaded.q_w_c.coeffs(), loc.q_w_c.coeffs());
  EXPECT_EQ(threaded.covariance, loc.covariance);
  EXPECT_EQ(threaded.cost, loc.cost);
  EXPECT_EQ(threaded.ambiguity, loc.ambiguity);
  EXPECT_EQ(threaded.candidates_refined, loc.candidates_refined);
  std::printf("on three threads in %.2f s\n", threaded.seconds);
}

// With a heading window the coarse profiles are traced only where the sweep reads them (the
// samples' span widened by the window): the same lowest coarse score and the same location, to
// the last bit, as tracing them all round, for a truth near the window's edge and for views
// that straddle north and south (the azimuths wrap at +-180 deg), with a fraction of the traces.
TEST(FrameLocator, AHeadingWindowTracesOnlyTheAzimuthsItReads) {
  const auto horizon = std::make_shared<HorizonPredictor>(testing::MountainRing());
  const CameraModel camera(PinholeFromFov("camera", 1920, 1080, 70.0));
  const Eigen::Matrix3d level = Level(1.0, -0.5);
  for (const double heading_deg : {3.0, 180.0, 250.0, -185.0, -10.0}) {
    const Eigen::Matrix3d r_w_c =
        Eigen::AngleAxisd(-heading_deg * kDeg, Eigen::Vector3d::UnitZ()) * level;
    const Eigen::Vector3d p_w_c(-350.0, 420.0, 5.0);
    const auto samples = testing::SyntheticSkyline(*horizon, camera, r_w_c, p_w_c, 8);
    FrameLocatorOptions o;
    o.search_radius_m = 150.0;
    o.grid_step_m = 50.0;
    o.heading_window_deg = 15.0;
    // The truth 2 deg inside the window's upper edge, and for the headings written negative
    // inside its lower one.
    o.prior_heading_deg = heading_deg + (heading_deg < 0 ? 13.0 : -13.0);
    const Eigen::Vector3d prior = p_w_c + Eigen::Vector3d(60.0, -40.0, 0.0);
    const FrameLocation restricted = LocateFrame(horizon, camera, samples, level, prior, o);
    o.full_profiles = true;
    const FrameLocation full = LocateFrame(horizon, camera, samples, level, prior, o);
    SCOPED_TRACE(heading_deg);
    ASSERT_TRUE(full.ok) << full.reason;
    ASSERT_TRUE(restricted.ok) << restricted.reason;
    EXPECT_LT((full.p_w_c - p_w_c).head<2>().norm(), 1.0);
    EXPECT_EQ(restricted.coarse_score, full.coarse_score);
    EXPECT_EQ(restricted.p_w_c, full.p_w_c);
    EXPECT_EQ(restricted.q_w_c.coeffs(), full.q_w_c.coeffs());
    EXPECT_EQ(full.coarse_traces, 49 * 720);
    // 70 deg of view and 30 of window out of 360.
    EXPECT_LT(restricted.coarse_traces, 0.3 * full.coarse_traces);
    std::printf("heading %.0f deg: %ld of %ld traces, coarse %.3f s against %.3f s\n", heading_deg,
                restricted.coarse_traces, full.coarse_traces, restricted.coarse_seconds,
                full.coarse_seconds);
  }
}

TEST(FrameLocator, TooFewSamplesIsAReasonNotACrash) {
  const auto horizon = std::make_shared<HorizonPredictor>(testing::MountainRing(201, 100.0));
  const CameraModel camera(PinholeFromFov("camera", 1920, 1080, 70.0));
  const FrameLocation loc = LocateFrame(horizon, camera, {{Eigen::Vector2d(5, 5), 1.0}},
                                        Level(0, 0), Eigen::Vector3d(0, 0, 5), {});
  EXPECT_FALSE(loc.ok);
  EXPECT_FALSE(loc.reason.empty());
}

// A world whose terrain is the map plus a height error of 4 m correlated over a kilometre (the
// simulator's DEM error, a Gaussian field: not the locator's exponential model), seen from 5-8 km:
// refined from the true pose, the frame's horizontal position error against its covariance. Taking
// the map as exact, the covariance is the extraction noise's alone and the errors are 7 times
// it (ANEES ~110 for 2 expected); with the map's error in the samples' noise (dem_sigma_m) most of
// that is gone (~9). The rest is the world's field not being the model's: a Gaussian covariance
// puts more of the same variance at long wavelengths than an exponential one, and the long
// wavelengths along the skyline are what tell a frame's range to its ridges.
TEST(FrameLocator, TheMapsErrorInTheNoiseMakesOneFramesCovarianceHonest) {
  constexpr double kR = 6371000.0;
  const geo::EnuHeightGrid map = testing::MountainRing();
  const auto map_horizon = std::make_shared<const HorizonPredictor>(map);
  const CameraModel camera(PinholeFromFov("camera", 1920, 1080, 70.0));
  const Eigen::Matrix3d level = Level(0.0, 0.0);
  std::mt19937 rng(3);
  std::normal_distribution<double> normal;
  constexpr int kWorlds = 24;
  double nees_exact = 0.0, nees_map = 0.0;
  int n = 0;
  for (int world = 0; world < kWorlds; ++world) {
    geo::EnuHeightGrid terrain = map;
    sim::AddDemError({4.0, 1000.0}, 100 + world, kR, &terrain);
    const HorizonPredictor seen(terrain);
    const double heading = (15.0 * world) * kDeg;
    const Eigen::Matrix3d r_w_c = Eigen::AngleAxisd(-heading, Eigen::Vector3d::UnitZ()) * level;
    const Eigen::Vector3d p_w_c(-350.0 + 20.0 * world, 420.0 - 15.0 * world, 5.0);
    auto samples = testing::SyntheticSkyline(seen, camera, r_w_c, p_w_c, 8);
    for (SkylineSample& s : samples) s.pixel.y() += 0.3 * normal(rng);  // the extraction's
    FrameLocatorOptions o;
    o.residual.sigma_px = 0.3;
    double nees[2];
    for (int with_map = 0; with_map < 2; ++with_map) {
      o.dem_sigma_m = with_map ? 4.0 : 0.0;
      o.map_correlation_m = 1000.0;
      const FrameLocation loc = RefineFrame(map_horizon, camera, samples, Eigen::Quaterniond(r_w_c),
                                            p_w_c, level, p_w_c, o);
      ASSERT_TRUE(loc.ok) << loc.reason;
      const Eigen::Vector2d e = (loc.p_w_c - p_w_c).head<2>();
      nees[with_map] = e.dot(loc.covariance.block<2, 2>(3, 3).inverse() * e);
    }
    nees_exact += nees[0];
    nees_map += nees[1];
    ++n;
  }
  nees_exact /= n;
  nees_map /= n;
  std::printf("horizontal ANEES over %d worlds: map exact %.2f, map's error in the noise %.2f\n", n,
              nees_exact, nees_map);
  EXPECT_GT(nees_exact, 30.0);
  EXPECT_GT(nees_map, 0.5);
  EXPECT_LT(nees_map, 0.2 * nees_exact);
}

// A sea view of one ridge line 30 km off, located in the planar mode (tilt and height held by
// stiff priors) with a 170 m prior: one frame's range and its lateral position (traded against
// heading that far off) are weak but real information. The covariance is the inverse of the
// Gauss-Newton information built here from central differences of the residual over heading and
// the two horizontal axes; a pseudo-inverse that drops the weakest direction (Ceres'
// null_space_rank -1 did: it lies 1e-14 below the priors) reported it as known to nanometres.
// Within 10 % of a variance (5 % of a sigma): the differences straddle the DEM's cells.
TEST(FrameLocator, APlanarFramesWeakDirectionsStayInItsCovariance) {
  const auto horizon =
      std::make_shared<HorizonPredictor>(testing::Grid(801, 90.0, [](double x, double y) {
        const double ridge =
            std::exp(-std::pow((y - 30000.0) / 3000.0, 2)) *
            (600.0 + 200.0 * std::sin(x / 2500.0) + 90.0 * std::sin(x / 900.0 + 1));
        return (ridge > 0.5 ? ridge : 0.0) - (x * x + y * y) / (2 * 6371000.0);
      }));
  const CameraModel camera(PinholeFromFov("camera", 1920, 1080, 70.0));
  const Eigen::Matrix3d r_w_c = Level(0.0, 0.0);  // looking north
  const Eigen::Vector3d p(0.0, 0.0, 4.0);
  const auto samples = testing::SyntheticSkyline(*horizon, camera, r_w_c, p, 8);
  FrameLocatorOptions o;
  o.planar = true;
  o.horizontal_sigma_m = 170.0;
  const FrameLocation loc =
      RefineFrame(horizon, camera, samples, Eigen::Quaterniond(r_w_c), p, r_w_c, p, o);
  ASSERT_TRUE(loc.ok) << loc.reason;
  ASSERT_TRUE(loc.covariance.allFinite());

  // (heading about the world's up, east, north) by central differences of the model's residual.
  const SkylineResidualModel model(horizon, camera, samples, o.residual);
  const auto residual = [&](const Eigen::Vector3d& d) {
    Eigen::VectorXd r(model.size());
    model.Evaluate(Eigen::AngleAxisd(d[0], Eigen::Vector3d::UnitZ()) * r_w_c,
                   p + Eigen::Vector3d(d[1], d[2], 0.0), r.data());
    return r;
  };
  Eigen::MatrixXd j(model.size(), 3);
  const double steps[3] = {1e-6, 0.05, 0.05};
  for (int k = 0; k < 3; ++k) {
    Eigen::Vector3d d = Eigen::Vector3d::Zero();
    d[k] = steps[k];
    j.col(k) = (residual(d) - residual(-d)) / (2 * steps[k]);
  }
  Eigen::Matrix3d information = j.transpose() * j;
  information(1, 1) += 1.0 / (170.0 * 170.0);
  information(2, 2) += 1.0 / (170.0 * 170.0);
  const Eigen::Matrix2d want = information.inverse().block<2, 2>(1, 1);
  const Eigen::Matrix2d got = loc.covariance.block<2, 2>(3, 3);
  std::printf("horizontal sigma east %.1f north %.1f m (from differences %.1f, %.1f)\n",
              std::sqrt(got(0, 0)), std::sqrt(got(1, 1)), std::sqrt(want(0, 0)),
              std::sqrt(want(1, 1)));
  ASSERT_GT(want(1, 1), 100.0);  // the range is weak: sigma above 10 m
  for (int a = 0; a < 2; ++a) {
    for (int b = 0; b < 2; ++b) {
      EXPECT_NEAR(got(a, b), want(a, b), 0.1 * std::sqrt(want(a, a) * want(b, b)));
    }
  }
}

}  // namespace
}  // namespace skerry::skyline
