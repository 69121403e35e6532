#include "skerry/skyline/crest_correlation.h"

#include <gtest/gtest.h>

#include <cmath>

#include "skerry/skyline/camera_model.h"
#include "skerry/skyline/skyline_frontend.h"
#include "skyline/skyline_test_scene.h"

namespace skerry::skyline {
namespace {

using testing::Grid;

// Flat Earth and straight rays, so that the brute-force tangency below is the whole geometry.
HorizonOptions Flat() {
  HorizonOptions o;
  o.refraction_k = 0.0;
  o.earth_radius_m = 1e15;
  return o;
}

// Rays of a camera looking north, level, within +-1 degree of the axis (optical frame: z
// forward, x right, y down; world: x east, y north, z up).
std::vector<Eigen::Vector3d> RaysAhead() {
  std::vector<Eigen::Vector3d> rays;
  for (int i = -4; i <= 4; ++i) {
    rays.push_back(Eigen::Vector3d(std::tan(i * 0.25 * M_PI / 180.0), 0.0, 1.0).normalized());
  }
  return rays;
}
const Eigen::Matrix3d kLookNorth = (Eigen::Matrix3d() << 1, 0, 0, 0, 0, 1, 0, -1, 0).finished();

// The northing of the point where a ray from (y0, zc) grazes the profile z(y), by brute force
// over a 0.01 m grid (the largest elevation angle seen).
double Tangency(const std::function<double(double)>& z, double y0, double zc) {
  double best = -1e9, at = 0.0;
  for (double y = y0 + 100.0; y < 9000.0; y += 0.01) {
    const double e = (z(y) - zc) / (y - y0);
    if (e > best) best = e, at = y;
  }
  return at;
}

// A rounded ridge (a Gaussian cross-section, 1.5 km wide, lowered to meet the flat ground 3 km
// either side of its axis, 3 km north along the east axis): as the camera moves towards it the
// silhouette slides down its near slope. The shift measured on the DEM is the tangency's, and rho
// is exp(-shift / L).
TEST(CrestCorrelation, ARoundedRidgeSlidesAsTheTangencyDoes) {
  const auto ridge = [](double y) {
    const double u = (y - 3000.0) / 1500.0, base = std::exp(-2.0);
    return std::abs(u) >= 2.0 ? 0.0 : 300.0 * (std::exp(-0.5 * u * u) - base) / (1.0 - base);
  };
  const double spacing = 10.0, length = 100.0;
  const HorizonPredictor horizon(Grid(1601, spacing, [&](double, double y) { return ridge(y); }),
                                 Flat());
  const double zc = 3.0;
  for (const double step : {200.0, 500.0, 900.0}) {
    const Eigen::Vector3d before(0.0, -1000.0, zc), now(0.0, -1000.0 + step, zc);
    const double expected =
        std::abs(Tangency(ridge, now.y(), zc) - Tangency(ridge, before.y(), zc));
    ASSERT_GT(expected, 2.0 * spacing);
    const CrestMotion m = MeasureCrestMotion(horizon, RaysAhead(), kLookNorth, now, before, length);
    EXPECT_EQ(m.samples, 9);
    EXPECT_EQ(m.compared, 9);
    // The predictor's terrain point is found to a node of the grid.
    EXPECT_NEAR(m.median_shift_m, expected, spacing + 0.03 * expected) << "step " << step;
    EXPECT_NEAR(m.rho, std::exp(-expected / length), 0.1 * std::exp(-expected / length))
        << "step " << step;
  }
}

// A sharp ridge (a triangle in cross-section) is its own silhouette from anywhere below it: the
// same ground makes the skyline however far the camera moves along or towards it.
TEST(CrestCorrelation, ASharpRidgeKeepsItsGround) {
  const HorizonPredictor horizon(
      Grid(801, 10.0,
           [](double, double y) { return std::max(0.0, 300.0 - 0.6 * std::abs(y - 3000.0)); }),
      Flat());
  const Eigen::Vector3d before(0.0, -1000.0, 3.0);
  for (const Eigen::Vector3d& now :
       {Eigen::Vector3d(0.0, -400.0, 3.0), Eigen::Vector3d(250.0, -1000.0, 3.0)}) {
    const CrestMotion m = MeasureCrestMotion(horizon, RaysAhead(), kLookNorth, now, before, 20.0);
    EXPECT_EQ(m.compared, 9);
    EXPECT_LT(m.median_shift_m, 1.0);
    EXPECT_GT(m.rho, 0.95);
  }
}

// A near ridge that hid a far one: once the camera stands where the far ridge makes the skyline,
// the ground of the frame before (the near crest) is another, and the frame is a new one.
TEST(CrestCorrelation, NewGroundIsUncorrelated) {
  const auto terrain = [](double, double y) {
    const double near = std::max(0.0, 100.0 - 0.5 * std::abs(y - 1000.0));
    const double far = std::max(0.0, 400.0 - 0.5 * std::abs(y - 5000.0));
    return std::max(near, far);
  };
  const HorizonPredictor horizon(Grid(1601, 10.0, terrain), Flat());
  // From 700 m south of the near ridge it hides the far one (100 m at 0.3 km against 400 m at
  // 4.3 km); from above its crest, the far one is the skyline.
  const Eigen::Vector3d before(0.0, 300.0, 3.0), now(0.0, 1000.0, 110.0);
  const CrestMotion m = MeasureCrestMotion(horizon, RaysAhead(), kLookNorth, now, before, 90.0);
  EXPECT_EQ(m.samples, 9);
  EXPECT_EQ(m.compared, 9);
  EXPECT_GT(m.median_shift_m, 3000.0);
  EXPECT_LT(m.rho, 1e-6);
  EXPECT_THROW(MeasureCrestMotion(horizon, RaysAhead(), kLookNorth, now, before, 0.0),
               std::invalid_argument);
}

// The sea horizon of a camera 10 m up (a sphere in ENU): the grazing point is water wherever the
// camera is, so each frame's sea horizon is new; the same sea raised into a hill is not water.
TEST(CrestCorrelation, AHorizonMadeByWaterIsNewEveryFrame) {
  constexpr double kR = 6371000.0;
  const HorizonPredictor sea(
      Grid(801, 90.0, [](double x, double y) { return -(x * x + y * y) / (2 * kR); }));
  const CrestMotion m =
      MeasureCrestMotion(sea, RaysAhead(), kLookNorth, {0, 5, 10}, {0, 0, 10}, 90.0);
  EXPECT_EQ(m.samples, 9);
  EXPECT_EQ(m.water, 9);
  EXPECT_EQ(m.compared, 0);
  EXPECT_EQ(m.rho, 0.0);
  // A hill on the same sphere, 300 m high at 5 km: its crest is ground, and holds still.
  const HorizonPredictor hill(Grid(801, 90.0, [](double x, double y) {
    return 300.0 * std::exp(-0.5 * (x * x + std::pow(y - 5000.0, 2)) / (400.0 * 400.0)) -
           (x * x + y * y) / (2 * kR);
  }));
  const CrestMotion h =
      MeasureCrestMotion(hill, RaysAhead(), kLookNorth, {0, 5, 10}, {0, 0, 10}, 90.0);
  EXPECT_EQ(h.water, 0);
  EXPECT_EQ(h.compared, 9);
  EXPECT_GT(h.rho, 0.7);
}

// A wall seen from close by makes the horizon; from 3 km back, the terrain rising to the map's
// edge behind it does, truncated: the ground of the frame before is unknown, so the sample counts
// as new and is not compared.
TEST(CrestCorrelation, ATruncatedHorizonBeforeIsNoGroundToCompare) {
  const HorizonPredictor horizon(Grid(401, 25.0,
                                      [](double, double y) {
                                        const double wall =
                                            std::abs(y + 1000.0) < 50.0 ? 400.0 : 0.0;
                                        return std::max(wall, 0.3 * std::max(0.0, y));
                                      }),
                                 Flat());
  const Eigen::Vector3d before(0.0, -4500.0, 5.0), now(0.0, -1300.0, 5.0);
  ASSERT_TRUE(horizon.Trace(before, 0.0).truncated);
  ASSERT_FALSE(horizon.Trace(now, 0.0).truncated);
  const CrestMotion m = MeasureCrestMotion(horizon, RaysAhead(), kLookNorth, now, before, 90.0);
  EXPECT_EQ(m.samples, 9);
  EXPECT_EQ(m.compared, 0);
  EXPECT_EQ(m.rho, 0.0);
}

// Where the map ends on rising terrain the horizon is truncated: no sample, rho 0.
TEST(CrestCorrelation, TruncatedHorizonsCountAsNone) {
  const HorizonPredictor horizon(
      Grid(201, 50.0, [](double, double y) { return 0.2 * (y + 5000.0); }), Flat());
  const CrestMotion m =
      MeasureCrestMotion(horizon, RaysAhead(), kLookNorth, {0, -4900, 30}, {0, -4950, 30}, 90.0);
  EXPECT_EQ(m.samples, 0);
  EXPECT_EQ(m.rho, 0.0);
}

// A camera's frontend registered as the only sensor of an estimator.
SkylineFrontend Registered(const CameraConfig& camera,
                           std::shared_ptr<const HorizonPredictor> horizon,
                           const SkylineConfig& config) {
  SkylineFrontend frontend(camera, std::move(horizon), DefaultCameraSensorOptions(), config);
  struct OneSensor {
    SensorId RegisterSensor(const SensorSpec&) { return 0; }
  } estimator;
  frontend.Register(&estimator);
  return frontend;
}

// The frontend with skyline.frame_correlation_m: a frame's weight is made when a consumer reaches
// it, from the crest's motion since the frame before at that consumer's states, times the time
// term; the gate is told that weight. The window's and the batch's histories are their own.
TEST(CrestCorrelation, TheFrontendWeighsAFrameByItsCrestsMotionAtTheConsumersState) {
  auto horizon = std::make_shared<const HorizonPredictor>(testing::MountainRing());
  CameraConfig camera = PinholeFromFov("camera", 1920, 1080, 70.0);
  SkylineConfig config;
  config.frame_correlation_s = 10.0;
  config.frame_correlation_m = 90.0;
  SkylineFrontend frontend = Registered(camera, horizon, config);
  const CameraModel model(camera);
  // Body = camera (identity mount), looking north, level; the second frame a second and 40 m on.
  const Eigen::Quaterniond q(kLookNorth);
  const Eigen::Vector3d p0(0.0, 0.0, 5.0), p1(0.0, 40.0, 5.0);
  const auto a = frontend.Measurement(
      SecondsToNs(1.0), testing::SyntheticSkyline(*horizon, model, kLookNorth, p0, 8));
  const auto b = frontend.Measurement(
      SecondsToNs(2.0), testing::SyntheticSkyline(*horizon, model, kLookNorth, p1, 8));
  ASSERT_TRUE(a && b && a->prepare && b->prepare && !a->cost);
  NavState at0, at1;
  at0.q_w_b = at1.q_w_b = q;
  at0.p_w_b = p0;
  at1.p_w_b = p1;
  const SkylineResidualModel rays(
      horizon, model, testing::SyntheticSkyline(*horizon, model, kLookNorth, p1, 8), {});
  const CrestMotion motion =
      MeasureCrestMotion(*horizon, rays.rays_c(), kLookNorth, p1, p0, config.frame_correlation_m);
  ASSERT_GT(motion.compared, 100);
  const double rho = motion.rho * std::exp(-1.0 / config.frame_correlation_s);
  ASSERT_GT(rho, 0.05);
  ASSERT_LT(rho, 0.95);
  const double w = std::sqrt((1 - rho) / (1 + rho));

  const PreparedBlock window_a = a->prepare(at0, Eigen::Vector3d::Zero(), BlockConsumer::kWindow);
  const PreparedBlock window_b = b->prepare(at1, Eigen::Vector3d::Zero(), BlockConsumer::kWindow);
  ASSERT_TRUE(window_a && window_b);
  EXPECT_EQ(window_a.gate_scale, 1.0);
  EXPECT_NEAR(window_b.gate_scale, w, 1e-12);
  // The batch reaches the second frame without the first: nothing before it there (the window's
  // frames are not the batch's), a full frame.
  const PreparedBlock batch_b = b->prepare(at1, Eigen::Vector3d::Zero(), BlockConsumer::kBatch);
  ASSERT_TRUE(batch_b);
  EXPECT_EQ(batch_b.gate_scale, 1.0);
  // The cost carries the weight: its residual is w times the full frame's, at any state.
  NavState off = at1;
  off.p_w_b += Eigen::Vector3d(20.0, -15.0, 0.0);
  const auto residual = [&](const ceres::CostFunction& cost) {
    const Eigen::Quaterniond q_b_c = Eigen::Quaterniond::Identity();
    const Eigen::Vector3d p_b_c = Eigen::Vector3d::Zero();
    const double* blocks[] = {off.q_w_b.coeffs().data(), off.p_w_b.data(), q_b_c.coeffs().data(),
                              p_b_c.data()};
    Eigen::VectorXd r(cost.num_residuals());
    EXPECT_TRUE(cost.Evaluate(blocks, r.data(), nullptr));
    return r;
  };
  const Eigen::VectorXd full = residual(*batch_b.cost), weighted = residual(*window_b.cost);
  ASSERT_GT(full.norm(), 1.0);
  EXPECT_NEAR(weighted.norm() / full.norm(), w, 1e-9);
  EXPECT_EQ(frontend.stats().weighted_frames, 2);
  EXPECT_EQ(frontend.stats().crest_frames, 1);
}

// skyline.dem_sigma_m without the ground term: the frame is still prepared at the consumer's
// state, where its samples are weighted for the map's error (SkylineResidualModel::AddMapError)
// with the time term's frame weight; the window's frames count the mean map term.
TEST(CrestCorrelation, TheFrontendWeighsSamplesForTheMapsErrorAtTheConsumersState) {
  auto horizon = std::make_shared<const HorizonPredictor>(testing::MountainRing());
  CameraConfig camera = PinholeFromFov("camera", 1920, 1080, 70.0);
  SkylineConfig config;
  config.frame_correlation_s = 10.0;
  config.frame_correlation_m = 0.0;
  config.dem_sigma_m = 4.0;
  SkylineFrontend frontend = Registered(camera, horizon, config);
  const CameraModel model(camera);
  const Eigen::Vector3d p0(0.0, 0.0, 5.0), p1(0.0, 40.0, 5.0);
  const auto samples0 = testing::SyntheticSkyline(*horizon, model, kLookNorth, p0, 8);
  const auto samples1 = testing::SyntheticSkyline(*horizon, model, kLookNorth, p1, 8);
  const auto a = frontend.Measurement(SecondsToNs(1.0), samples0);
  const auto b = frontend.Measurement(SecondsToNs(2.0), samples1);
  ASSERT_TRUE(a && b && a->prepare && b->prepare && !b->cost);
  NavState at;
  at.q_w_b = Eigen::Quaterniond(kLookNorth);
  at.p_w_b = p1;
  const PreparedBlock block = b->prepare(at, Eigen::Vector3d::Zero(), BlockConsumer::kWindow);
  ASSERT_TRUE(block);
  const double rho = std::exp(-1.0 / config.frame_correlation_s);
  const double w = std::sqrt((1 - rho) / (1 + rho));
  EXPECT_NEAR(block.gate_scale, w, 1e-12);
  // The same residual as a model weighted by hand at that pose, at another pose.
  SkylineResidualOptions o = frontend.residual_options();
  o.frame_weight = w;
  SkylineResidualModel want(horizon, model, samples1, o);
  const double mean_px = want.AddMapError(kLookNorth, p1, config.dem_sigma_m);
  ASSERT_GT(mean_px, 0.01);
  const Eigen::Vector3d off(120.0, 150.0, 5.0);
  Eigen::VectorXd expected(want.size()), got(want.size());
  want.Evaluate(kLookNorth, off, expected.data());
  const Eigen::Quaterniond q_b_c = Eigen::Quaterniond::Identity();
  const Eigen::Vector3d p_b_c = Eigen::Vector3d::Zero();
  const double* blocks[] = {at.q_w_b.coeffs().data(), off.data(), q_b_c.coeffs().data(),
                            p_b_c.data()};
  ASSERT_TRUE(block.cost->Evaluate(blocks, got.data(), nullptr));
  ASSERT_GT(expected.norm(), 1.0);
  EXPECT_LT((got - expected).norm(), 1e-9 * expected.norm());
  // Without the map term the residual differs: the weighting is not a no-op here.
  SkylineResidualModel plain(horizon, model, samples1, o);
  Eigen::VectorXd unweighted(plain.size());
  plain.Evaluate(kLookNorth, off, unweighted.data());
  EXPECT_GT((unweighted - expected).norm(), 1e-3 * expected.norm());
  EXPECT_EQ(frontend.stats().weighted_frames, 1);
  EXPECT_NEAR(frontend.stats().map_sigma_px_sum, mean_px, 1e-12);
}

// With both terms on, a frame's prepare traces each sample's horizon once, at the consumer's
// state: the crest's motion and the map's error read the terrain points of one trace, and the
// consumer's first evaluation there (the gate's) re-uses it, with a camera mounted off the
// body's axes and origin. The block is the one built by hand from the rays' own traces.
TEST(CrestCorrelation, APreparedFrameTracesItsHorizonOnceAtTheConsumersState) {
  auto horizon = std::make_shared<const HorizonPredictor>(testing::MountainRing());
  CameraConfig camera = PinholeFromFov("camera", 1920, 1080, 70.0);
  camera.T_b_c.q_b_s =
      Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(0.2, 0.5, 1.0).normalized()));
  camera.T_b_c.p_b_s = Eigen::Vector3d(1.2, -0.4, 2.5);
  SkylineConfig config;
  config.frame_correlation_s = 10.0;
  config.frame_correlation_m = 90.0;
  config.dem_sigma_m = 4.0;
  SkylineFrontend frontend = Registered(camera, horizon, config);
  const CameraModel model(camera);
  const Eigen::Vector3d c0(0.0, 0.0, 5.0), c1(30.0, 40.0, 5.0);
  const auto a = frontend.Measurement(
      SecondsToNs(1.0), testing::SyntheticSkyline(*horizon, model, kLookNorth, c0, 8));
  const auto samples1 = testing::SyntheticSkyline(*horizon, model, kLookNorth, c1, 8);
  const auto b = frontend.Measurement(SecondsToNs(2.0), samples1);
  ASSERT_TRUE(a && b && a->prepare && b->prepare && !b->cost);
  // The body states that put the camera at c0, c1 looking north.
  const Eigen::Quaterniond q_w_b = Eigen::Quaterniond(kLookNorth) * camera.T_b_c.q_b_s.inverse();
  NavState at0, at1;
  at0.q_w_b = at1.q_w_b = q_w_b;
  at0.p_w_b = c0 - q_w_b * camera.T_b_c.p_b_s;
  at1.p_w_b = c1 - q_w_b * camera.T_b_c.p_b_s;
  ASSERT_TRUE(a->prepare(at0, Eigen::Vector3d::Zero(), BlockConsumer::kWindow));
  const PreparedBlock block = b->prepare(at1, Eigen::Vector3d::Zero(), BlockConsumer::kWindow);
  ASSERT_TRUE(block);
  const auto* cost = dynamic_cast<const SkylineCost*>(block.cost.get());
  ASSERT_NE(cost, nullptr);
  EXPECT_EQ(cost->model().traced_poses(), 1);

  const auto evaluate = [&](const NavState& at, bool with_jacobians) {
    const double* blocks[] = {at.q_w_b.coeffs().data(), at.p_w_b.data(),
                              camera.T_b_c.q_b_s.coeffs().data(), camera.T_b_c.p_b_s.data()};
    Eigen::VectorXd r(cost->num_residuals());
    std::vector<double> j0(r.size() * 4), j1(r.size() * 3), j2(r.size() * 4), j3(r.size() * 3);
    double* jacobians[] = {j0.data(), j1.data(), j2.data(), j3.data()};
    EXPECT_TRUE(cost->Evaluate(blocks, r.data(), with_jacobians ? jacobians : nullptr));
    return r;
  };
  const Eigen::VectorXd at_state = evaluate(at1, true);
  EXPECT_EQ(cost->model().traced_poses(), 1);  // the gate's evaluation re-used the trace

  // By hand, each term from its own trace.
  Eigen::Matrix3d r_w_c;
  Eigen::Vector3d p_w_c;
  SkylineCost::CameraPose(at1.q_w_b, at1.p_w_b, camera.T_b_c.q_b_s, camera.T_b_c.p_b_s, &r_w_c,
                          &p_w_c);
  SkylineResidualModel want(horizon, model, samples1, frontend.residual_options());
  Eigen::Vector3d p0_w_c;
  Eigen::Matrix3d unused;
  SkylineCost::CameraPose(at0.q_w_b, at0.p_w_b, camera.T_b_c.q_b_s, camera.T_b_c.p_b_s, &unused,
                          &p0_w_c);
  const CrestMotion motion =
      MeasureCrestMotion(*horizon, want.rays_c(), r_w_c, p_w_c, p0_w_c, config.frame_correlation_m);
  ASSERT_GT(motion.compared, 100);
  const double rho = std::min(motion.rho * std::exp(-1.0 / config.frame_correlation_s), 0.999);
  want.SetFrameWeight(std::sqrt((1 - rho) / (1 + rho)));
  ASSERT_GT(want.AddMapError(r_w_c, p_w_c, config.dem_sigma_m, config.frame_correlation_m), 0.01);
  EXPECT_NEAR(block.gate_scale, std::sqrt((1 - rho) / (1 + rho)), 1e-12);
  NavState off = at1;
  off.p_w_b += Eigen::Vector3d(25.0, -35.0, 0.0);
  for (const NavState* s : {&at1, &off}) {
    SkylineCost::CameraPose(s->q_w_b, s->p_w_b, camera.T_b_c.q_b_s, camera.T_b_c.p_b_s, &r_w_c,
                            &p_w_c);
    Eigen::VectorXd expected(want.size());
    want.Evaluate(r_w_c, p_w_c, expected.data());
    const Eigen::VectorXd got = s == &at1 ? at_state : evaluate(off, false);
    if (s == &off) {
      ASSERT_GT(expected.norm(), 0.5);  // at the state: the synthetic skyline's 0
    }
    EXPECT_LE((got - expected).norm(), 1e-9 * expected.norm() + 1e-12);
  }
  EXPECT_EQ(cost->model().traced_poses(), 2);  // a new pose is traced
}

// The frontend's global search (Locate: the start without GNSS; Relocate) weighs a frame as its
// blocks are weighed: with skyline.dem_sigma_m the located covariance carries the map's error, so
// it is wider than the same search's with the map taken as exact, on the same frame.
TEST(CrestCorrelation, TheFrontendLocatesAFrameWithTheMapsError) {
  auto horizon = std::make_shared<const HorizonPredictor>(testing::MountainRing());
  const CameraConfig camera = PinholeFromFov("camera", 1920, 1080, 70.0);
  const CameraModel model(camera);
  const Eigen::Vector3d p(-350.0, 420.0, 5.0);
  const auto samples = testing::SyntheticSkyline(*horizon, model, kLookNorth, p, 8);
  // Body = camera: the world's up in the optical frame of a level camera.
  const Eigen::Vector3d up_b = kLookNorth.transpose() * Eigen::Vector3d::UnitZ();
  // The estimate a relocation searches around: 30 m off, sigma 20 m per axis, heading 2 deg.
  NavState estimate;
  estimate.q_w_b = Eigen::Quaterniond(kLookNorth);
  estimate.p_w_b = p + Eigen::Vector3d(30.0, -20.0, 0.0);
  StateCovariance covariance = StateCovariance::Identity();
  covariance(kRot + 2, kRot + 2) = std::pow(2.0 * M_PI / 180.0, 2);
  covariance(kPos, kPos) = covariance(kPos + 1, kPos + 1) = 400.0;
  double located_variance[2] = {0.0, 0.0}, relocated_variance[2] = {0.0, 0.0};
  for (int with_map = 0; with_map < 2; ++with_map) {
    SkylineConfig config;
    config.dem_sigma_m = with_map ? 4.0 : 0.0;
    SkylineFrontend frontend = Registered(camera, horizon, config);
    const auto frame = frontend.Measurement(SecondsToNs(1.0), samples);
    ASSERT_TRUE(frame);
    const auto located = frontend.Locate(SecondsToNs(1.0), up_b, estimate.p_w_b, 100.0);
    const auto relocated = frontend.Relocate(*frame, estimate, covariance, false);
    ASSERT_TRUE(located && relocated);
    EXPECT_LT((located->p_w_b - p).head<2>().norm(), 1.0);
    EXPECT_LT((relocated->p_w_b - p).head<2>().norm(), 1.0);
    located_variance[with_map] =
        located->covariance(kPos, kPos) + located->covariance(kPos + 1, kPos + 1);
    relocated_variance[with_map] =
        relocated->covariance(kPos, kPos) + relocated->covariance(kPos + 1, kPos + 1);
  }
  std::printf(
      "horizontal sigma, map exact / map's error 4 m: located %.2f / %.2f m, relocated "
      "%.2f / %.2f m\n",
      std::sqrt(located_variance[0]), std::sqrt(located_variance[1]),
      std::sqrt(relocated_variance[0]), std::sqrt(relocated_variance[1]));
  EXPECT_GT(located_variance[1], 1.2 * located_variance[0]);
  EXPECT_GT(relocated_variance[1], 1.2 * relocated_variance[0]);
}

}  // namespace
}  // namespace skerry::skyline
