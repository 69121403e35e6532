// The skyline frontend in the sliding window and the batch, with GNSS denied: a vessel on the
// harbour scenario (tactical IMU, afloat) among a ring of mountains 5-8 km away, one forward
// camera at 1 Hz. The frames' skylines come from the horizon model itself at the true camera
// pose plus pixel noise (the simulator's independent renderer is tested in bench/ and sim/): this
// checks the plumbing and the estimator, not the model.

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "skerry/eval/evaluation.h"
#include "skerry/frontends/dataset_sensors.h"
#include "skerry/sim/scenario.h"
#include "skerry/sim/simulator.h"
#include "skerry/skyline/skyline_frontend.h"
#include "skerry/skyline/skyline_start.h"
#include "skerry/solvers/pipeline.h"
#include "skyline/skyline_test_scene.h"

namespace skerry {
namespace {

constexpr double kDuration = 150.0;
constexpr double kDenied = 40.0;

struct Errors {
  double nees_horizontal = 0.0;
  double horizontal_rmse_m = 0.0;
  double horizontal_max_m = 0.0;
  double heading_rmse_deg = 0.0;
};

Errors DeniedErrors(const std::vector<EstimateRecord>& records, const Dataset& data) {
  const EvaluationResult ev = Evaluate(records, data.groundtruth);
  Errors out;
  double h2 = 0.0, psi2 = 0.0;
  int n = 0;
  for (const EpochError& e : ev.epochs) {
    if (e.t_ns < SecondsToNs(kDenied)) continue;
    const double h = e.p_err_w.head<2>().norm();
    h2 += h * h;
    out.horizontal_max_m = std::max(out.horizontal_max_m, h);
    psi2 += e.heading_err_deg * e.heading_err_deg;
    out.nees_horizontal += e.nees_horizontal;
    ++n;
  }
  EXPECT_GT(n, 100);
  out.nees_horizontal /= std::max(n, 1);
  out.horizontal_rmse_m = std::sqrt(h2 / n);
  out.heading_rmse_deg = std::sqrt(psi2 / n);
  return out;
}

class SkylineWindow : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    sim::ScenarioConfig sc = sim::LoadScenario(std::string(SKERRY_SOURCE_DIR) +
                                               "/bench/figures/harbour-pose-fixes-afloat.yaml");
    sc.duration_s = kDuration;
    sc.gnss.outages = {{kDenied, kDuration}};
    sc.pose_fixes.enabled = false;
    data_ = new Dataset(sim::Simulate(sc, 11));
    config_ = new EstimatorConfig(LoadPreset("default"));
    horizon_ = new std::shared_ptr<const skyline::HorizonPredictor>(
        std::make_shared<skyline::HorizonPredictor>(skyline::testing::MountainRing(801, 25.0)));
  }
  static void TearDownTestSuite() {
    delete horizon_;
    delete config_;
    delete data_;
  }

  // The water surface from the dataset plus, when `with_camera`, the camera's frames.
  // `map_offset`: the frames are seen from the truth moved by this (a DEM misregistered by it).
  // `horizon` / `world`: the estimator's map and the terrain the frames are made from (both the
  // fixture's mountain ring when null).
  static SensorLog Sensors(bool with_camera,
                           skyline::SkylineFrameStats* stats = nullptr,
                           const EstimatorConfig* config = nullptr,
                           const Eigen::Vector3d& map_offset = Eigen::Vector3d::Zero(),
                           std::shared_ptr<const skyline::HorizonPredictor> horizon = nullptr,
                           std::shared_ptr<const skyline::HorizonPredictor> world = nullptr) {
    if (config == nullptr) config = config_;
    if (!horizon) horizon = *horizon_;
    if (!world) world = horizon;
    SensorLog log = DatasetSensors(*data_, *config);
    if (!with_camera) return log;
    CameraConfig camera = skyline::PinholeFromFov("camera", 1920, 1080, 70.0);
    camera.distortion = {-0.05, 0.01, 0.0, 0.0};
    camera.T_b_c.q_b_s = skyline::LevelCameraRotation(0.0);
    camera.T_b_c.p_b_s = Eigen::Vector3d(2.0, 0.0, 4.0);
    skyline::SkylineFrontend frontend(camera, horizon, skyline::DefaultCameraSensorOptions(),
                                      config->skyline);
    frontend.Register(&log);
    std::mt19937 rng(5);
    std::normal_distribution<double> noise(0.0, 0.5);
    const auto& truth = data_->truth_states;
    for (double t = 0.23; t < kDuration - 1.0; t += 1.0) {
      const TimeNs t_ns = SecondsToNs(t);
      const auto it = std::lower_bound(truth.begin(), truth.end(), t_ns,
                                       [](const NavState& s, TimeNs v) { return s.t_ns < v; });
      // The frame's pose: the truth state at or just after t (50 Hz), moved back to t.
      const NavState& s = *it;
      const Eigen::Vector3d p_w_b = s.p_w_b - s.v_w * NsToSeconds(s.t_ns - t_ns);
      const Eigen::Quaterniond q_w_c = s.q_w_b * camera.T_b_c.q_b_s;
      const Eigen::Vector3d p_w_c = p_w_b + s.q_w_b * camera.T_b_c.p_b_s + map_offset;
      auto samples =
          skyline::testing::SyntheticSkyline(*world, frontend.camera(), q_w_c.toRotationMatrix(),
                                             p_w_c, config_->skyline.column_stride_px);
      for (auto& x : samples) x.pixel.y() += noise(rng);
      if (auto m = frontend.Measurement(t_ns, samples)) log.measurements.push_back(*m);
    }
    if (stats) stats_ = std::make_shared<skyline::SkylineFrontend>(frontend);
    if (stats) *stats = frontend.stats();
    return log;
  }
  static inline std::shared_ptr<skyline::SkylineFrontend> stats_;

  static Dataset* data_;
  static EstimatorConfig* config_;
  static std::shared_ptr<const skyline::HorizonPredictor>* horizon_;
};
Dataset* SkylineWindow::data_ = nullptr;
EstimatorConfig* SkylineWindow::config_ = nullptr;
std::shared_ptr<const skyline::HorizonPredictor>* SkylineWindow::horizon_ = nullptr;

TEST_F(SkylineWindow, CameraHoldsPositionAndHeadingWithoutGnss) {
  skyline::SkylineFrameStats stats;
  const WindowRun with = RunWindow(*data_, *config_, {}, nullptr, Sensors(true, &stats));
  const WindowRun without = RunWindow(*data_, *config_, {}, nullptr, Sensors(false));
  ASSERT_FALSE(with.records.empty());
  EXPECT_EQ(stats.measurements, stats.frames);
  const Errors cam = DeniedErrors(with.records, *data_);
  const Errors imu = DeniedErrors(without.records, *data_);
  const SensorStats& s = with.sensor_stats.back();
  std::printf(
      "camera: %.2f m RMS (max %.2f, NEES %.2f), heading %.3f deg; IMU alone: %.1f m, %.3f deg; "
      "frames accepted %d rejected %d dropped %d, NIS/dof %.2f\n",
      cam.horizontal_rmse_m, cam.horizontal_max_m, cam.nees_horizontal, cam.heading_rmse_deg,
      imu.horizontal_rmse_m, imu.heading_rmse_deg, s.accepted, s.rejected, s.dropped,
      s.accepted > 0 ? s.nis_per_dof_sum_accepted / s.accepted : 0.0);
  // One 70 deg frame of peaks 6 km away says little about range (tens of metres): the IMU's
  // motion between frames triangulates it.
  EXPECT_LT(cam.horizontal_rmse_m, 3.0);
  EXPECT_LT(cam.horizontal_rmse_m, 0.5 * imu.horizontal_rmse_m);
  EXPECT_LT(cam.heading_rmse_deg, 0.1);
  EXPECT_GE(s.accepted, 0.95 * stats.measurements);
  // The gate judges a frame by its own pixels (SensorMeasurement::gate_scale), not by the 5 % of
  // its information a frame keeps a second after the last: white 0.5 px noise whitened as errors
  // correlated along the skyline (rho = 0.67 at 8 px) is (0.5 / 1)^2 (1 + rho^2) / (1 - rho^2) =
  // 0.66 px^2 per sample at the truth. Judged weighted, it was 0.03: a gate 20 times too loose.
  const double nis_per_dof = s.nis_per_dof_sum_accepted / std::max(s.accepted, 1);
  EXPECT_GT(nis_per_dof, 0.3);
  EXPECT_LT(nis_per_dof, 1.5);

  const BatchResult batch = SmoothUntil(*data_, *config_, with, data_->imu_samples.back().t_ns);
  const Errors b = DeniedErrors(batch.records, *data_);
  std::printf("batch: %.2f m RMS, heading %.3f deg\n", b.horizontal_rmse_m, b.heading_rmse_deg);
  EXPECT_LT(b.horizontal_rmse_m, cam.horizontal_rmse_m);
}

// A window started 350 m and 8 deg off with a covariance that claims 2 m and 0.3 deg, no GNSS at
// all: the camera's frames do not fit; the window re-acquires, relocated by the global search
// around its estimate (here as soon as the heading sigma passes 0.3 deg; with a tighter claim,
// after the streak of rejected frames), and from then on navigates on the camera.
TEST_F(SkylineWindow, RelocatesAfterAStreakOfRejectedFrames) {
  EstimatorConfig config = *config_;
  config.init.mode = "given";
  Dataset data = *data_;
  data.gnss_fixes.clear();
  const NavState& t0 = data.truth_states.front();
  EstimateRecord initial;
  initial.state = t0;
  initial.state.p_w_b += Eigen::Vector3d(350.0, -60.0, 0.0);
  initial.state.q_w_b = Eigen::AngleAxisd(8.0 * M_PI / 180.0, Eigen::Vector3d::UnitZ()) * t0.q_w_b;
  initial.has_covariance = true;
  initial.covariance.setIdentity();
  initial.covariance.block<3, 3>(kRot, kRot) *= std::pow(0.3 * M_PI / 180.0, 2);
  initial.covariance.block<3, 3>(kPos, kPos) *= 4.0;
  initial.covariance.block<3, 3>(kVel, kVel) *= 0.04;
  initial.covariance.block<3, 3>(kBg, kBg) *= std::pow(data.imu.gyro_bias_prior_sigma_rad_s, 2);
  initial.covariance.block<3, 3>(kBa, kBa) *= std::pow(data.imu.accel_bias_prior_sigma_m_s2, 2);
  skyline::SkylineFrameStats unused;
  const SensorLog sensors = Sensors(true, &unused, &config);
  const WindowRun run = RunWindow(data, config, {}, &initial, sensors);
  ASSERT_FALSE(run.records.empty());
  const SensorStats& s = run.sensor_stats.back();
  const skyline::SkylineFrameStats& fs = stats_->stats();
  EXPECT_GE(s.reacquired, 1);
  EXPECT_GE(fs.relocations_found, 1);
  // The last minute: back on the camera's accuracy.
  const EvaluationResult ev = Evaluate(run.records, data.groundtruth);
  double h2 = 0.0;
  int n = 0;
  for (const EpochError& e : ev.epochs) {
    if (e.t_ns < SecondsToNs(kDuration - 60.0)) continue;
    h2 += e.p_err_w.head<2>().squaredNorm();
    ++n;
  }
  ASSERT_GT(n, 100);
  std::printf("reacquired %d, searches %d (found %d), last minute %.2f m RMS, accepted %d of %d\n",
              s.reacquired, fs.relocations_tried, fs.relocations_found, std::sqrt(h2 / n),
              s.accepted, fs.measurements);
  // Without any GNSS the velocity and biases come from the camera alone: a few metres, not the
  // 2 m of a window that had GNSS first.
  EXPECT_LT(std::sqrt(h2 / n), 10.0);
}

// GNSS accepted and a camera whose map is 150 m off: its frames are rejected, the streak
// re-acquires, and the relocation may turn the estimate but never move it away from a receiver
// that is being accepted (a wrong single-frame range once overrode GNSS by 60 m on the ring).
TEST_F(SkylineWindow, ARelocationDoesNotMoveAPositionThatGnssHolds) {
  skyline::SkylineFrameStats unused;
  const SensorLog sensors = Sensors(true, &unused, config_, Eigen::Vector3d(120.0, -90.0, 0.0));
  const WindowRun run = RunWindow(*data_, *config_, {}, nullptr, sensors);
  ASSERT_FALSE(run.records.empty());
  const SensorStats& s = run.sensor_stats.back();
  const EvaluationResult ev = Evaluate(run.records, data_->groundtruth);
  double worst = 0.0;
  for (const EpochError& e : ev.epochs) {
    if (e.t_ns < SecondsToNs(kDenied)) worst = std::max(worst, e.p_err_w.head<2>().norm());
  }
  std::printf("camera 150 m off: reacquired %d, rejected %d, worst error with GNSS %.2f m\n",
              s.reacquired, s.rejected, worst);
  EXPECT_GE(s.reacquired, 1);  // the relocation was tried while GNSS held the position
  EXPECT_LT(worst, 3.0);
}

// No GNSS at all and a prior 500 m off: the window starts from the global search on the first
// frames (init.mode skyline), heading unknown, and navigates on the camera.
TEST_F(SkylineWindow, StartsWithoutGnssFromTheGlobalSearch) {
  EstimatorConfig config = *config_;
  config.init.mode = "given";
  Dataset data = *data_;
  data.gnss_fixes.clear();
  skyline::SkylineFrameStats unused;
  const SensorLog sensors = Sensors(true, &unused, &config);
  const Eigen::Vector3d prior = data.truth_states.front().p_w_b + Eigen::Vector3d(-300, 400, 0);
  const auto start = skyline::SkylineStartState(*stats_, data.imu_samples, data.imu, prior, {});
  ASSERT_TRUE(start.has_value());
  const auto truth =
      std::lower_bound(data.truth_states.begin(), data.truth_states.end(), start->state.t_ns,
                       [](const NavState& s, TimeNs v) { return s.t_ns < v; });
  const double start_error = (start->state.p_w_b - truth->p_w_b).head<2>().norm();
  const double heading_error = start->state.q_w_b.angularDistance(truth->q_w_b) * 180.0 / M_PI;
  // Inside the search's own covariance (chi-square, 2 DOF, 99.9 %): one 70 deg frame of peaks
  // 6 km away fixes bearing well and range poorly.
  const Eigen::Vector2d dp = (start->state.p_w_b - truth->p_w_b).head<2>();
  const Eigen::Matrix2d pc = start->covariance.block<2, 2>(kPos, kPos);
  EXPECT_LT(dp.dot(pc.ldlt().solve(dp)), 13.8) << dp.transpose();
  EXPECT_LT(heading_error, 0.5);
  const WindowRun run = RunWindow(data, config, {}, &*start, sensors);
  ASSERT_FALSE(run.records.empty());
  const EvaluationResult ev = Evaluate(run.records, data.groundtruth);
  double h2 = 0.0, nees = 0.0;
  int n = 0;
  for (const EpochError& e : ev.epochs) {
    if (e.t_ns < SecondsToNs(kDuration - 60.0)) continue;
    h2 += e.p_err_w.head<2>().squaredNorm();
    nees += e.nees_horizontal;
    ++n;
  }
  ASSERT_GT(n, 100);
  std::printf(
      "start at %.1f s: %.1f m and %.2f deg off; last minute %.2f m RMS, horizontal "
      "NEES %.2f\n",
      NsToSeconds(start->state.t_ns), start_error, heading_error, std::sqrt(h2 / n), nees / n);
  EXPECT_LT(std::sqrt(h2 / n), 20.0);
  // Known and open (docs/results.md): after a start 45 m off along the line of sight the window
  // is overconfident about range (NEES ~27 where 2 is consistent); a window that had GNSS first
  // reads ~3. This bound catches it getting worse.
  EXPECT_LT(nees / n, 40.0);
}

// The refraction coefficient estimated with the states (skyline.refraction_k_sigma): ranges
// 12-32 km off, the world bending rays with k = 0.13, the estimator's map assuming 0.0 (a sea
// horizon's or a ridge's apparent height off by 0.13 s / (2 R): 0.12 to 0.33 mrad, 0.17 to 0.45
// px). Estimated, k comes back to within three sigmas of the world's, in the window and the batch,
// and the position is better than with k held wrong.
TEST_F(SkylineWindow, TheRefractionIsEstimatedWithTheStates) {
  const auto far = skyline::testing::Grid(801, 100.0, [](double x, double y) {
    const double d = std::hypot(x, y), a = std::atan2(x, y);
    const double ridge_m = 22000.0 + 10000.0 * std::sin(2 * a + 0.5);
    const double peaks = 700.0 + 250.0 * std::sin(5 * a) + 120.0 * std::sin(11 * a + 1.0);
    return peaks * std::exp(-std::pow((d - ridge_m) / 2500.0, 2)) - d * d / (2 * 6371000.0);
  });
  skyline::HorizonOptions world_options, map_options;
  world_options.refraction_k = 0.13;
  map_options.refraction_k = 0.0;
  const auto world = std::make_shared<skyline::HorizonPredictor>(far, world_options);
  const auto map = std::make_shared<skyline::HorizonPredictor>(far, map_options);
  EstimatorConfig fixed = *config_;
  fixed.skyline.refraction_k = 0.0;
  // k alone: with the gyro's calibration estimated too (the default), E takes up what k held
  // wrong costs this run's position (k held at 0: 3.83 -> 1.50 m RMS; k estimated: 1.67 ->
  // 1.54 m), and the two runs' positions tie.
  fixed.estimate_gyro_calibration = false;
  EstimatorConfig estimated = fixed;
  estimated.skyline.refraction_k_sigma = 0.2;
  skyline::SkylineFrameStats unused;
  const WindowRun held =
      RunWindow(*data_, fixed, {}, nullptr,
                Sensors(true, &unused, &fixed, Eigen::Vector3d::Zero(), map, world));
  const WindowRun run =
      RunWindow(*data_, estimated, {}, nullptr,
                Sensors(true, &unused, &estimated, Eigen::Vector3d::Zero(), map, world));
  ASSERT_EQ(held.parameters.size(), 0u);
  ASSERT_EQ(run.parameters.size(), 1u);
  const BatchResult batch = SmoothUntil(*data_, estimated, run, data_->imu_samples.back().t_ns);
  ASSERT_EQ(batch.parameters.size(), 1u);
  const Errors e_held = DeniedErrors(held.records, *data_);
  const Errors e_run = DeniedErrors(run.records, *data_);
  for (const SensorParameterEstimate& k : {run.parameters[0], batch.parameters[0]}) {
    ASSERT_TRUE(k.has_variance);
    const double sigma = std::sqrt(k.variance);
    std::printf("k %.3f +- %.3f (world 0.13, start 0.0, prior sigma 0.2)\n", k.value, sigma);
    EXPECT_LT(std::abs(k.value - 0.13), 3.0 * sigma);
    EXPECT_LT(sigma, 0.1);  // learnt from the frames, not the prior's 0.2
  }
  std::printf(
      "window: k held at 0: %.2f m RMS (max %.2f, NEES %.2f); estimated: %.2f m (max "
      "%.2f, NEES %.2f)\n",
      e_held.horizontal_rmse_m, e_held.horizontal_max_m, e_held.nees_horizontal,
      e_run.horizontal_rmse_m, e_run.horizontal_max_m, e_run.nees_horizontal);
  EXPECT_LT(e_run.horizontal_rmse_m, e_held.horizontal_rmse_m);
}

// The crest offset estimated with the states (skyline.crest_offset_sigma_m): the world's land
// stands 8 m above the map's, as real crests stand above a raster's (a ring 5-8 km off: 1.0 to
// 1.6 mrad, 1.4 to 2.2 px). The water surface holds the camera's height; what tells the offset
// from the range to the crests ahead (raising a crest h high d away by c reads as coming c d / h
// closer) is the vessel turning. The batch brings the offset back to within three sigmas of 8 m;
// the window learns most of it but, as on range itself, is overconfident (5.6 +- 0.5 m at the
// end: docs/skyline.md); the window's position error is less than half that of the map taken as
// it is (31 m RMS, NEES 84, without one frame rejected: the bias is inside the gate).
TEST_F(SkylineWindow, TheCrestOffsetIsEstimatedWithTheStates) {
  const auto world = std::make_shared<skyline::HorizonPredictor>(
      skyline::testing::RaisedMountainRing(8.0, 801, 25.0));
  EstimatorConfig estimated = *config_;
  estimated.skyline.crest_offset_sigma_m = 10.0;
  skyline::SkylineFrameStats unused;
  const WindowRun held =
      RunWindow(*data_, *config_, {}, nullptr,
                Sensors(true, &unused, config_, Eigen::Vector3d::Zero(), *horizon_, world));
  const WindowRun run =
      RunWindow(*data_, estimated, {}, nullptr,
                Sensors(true, &unused, &estimated, Eigen::Vector3d::Zero(), *horizon_, world));
  ASSERT_EQ(held.parameters.size(), 0u);
  ASSERT_EQ(run.parameters.size(), 1u);
  EXPECT_EQ(run.sensors.sensors[run.parameters[0].sensor].parameter_name, "crest_offset_m");
  const BatchResult batch = SmoothUntil(*data_, estimated, run, data_->imu_samples.back().t_ns);
  ASSERT_EQ(batch.parameters.size(), 1u);
  const Errors e_held = DeniedErrors(held.records, *data_);
  const Errors e_run = DeniedErrors(run.records, *data_);
  for (const SensorParameterEstimate& c : {run.parameters[0], batch.parameters[0]}) {
    ASSERT_TRUE(c.has_variance);
    const double sigma = std::sqrt(c.variance);
    std::printf("crest offset %.2f +- %.2f m (world 8, start 0, prior sigma 10)\n", c.value, sigma);
    EXPECT_GT(c.value, 4.0);  // more than half the offset learnt
    EXPECT_LT(c.value, 12.0);
    EXPECT_LT(sigma, 4.0);  // learnt from the frames, not the prior's 10 m
  }
  EXPECT_LT(std::abs(batch.parameters[0].value - 8.0),
            3.0 * std::sqrt(batch.parameters[0].variance));
  std::printf(
      "window: map as it is: %.2f m RMS (max %.2f, NEES %.2f, frames accepted %d rejected %d); "
      "offset estimated: %.2f m (max %.2f, NEES %.2f, accepted %d rejected %d)\n",
      e_held.horizontal_rmse_m, e_held.horizontal_max_m, e_held.nees_horizontal,
      held.sensor_stats.back().accepted, held.sensor_stats.back().rejected, e_run.horizontal_rmse_m,
      e_run.horizontal_max_m, e_run.nees_horizontal, run.sensor_stats.back().accepted,
      run.sensor_stats.back().rejected);
  EXPECT_LT(e_run.horizontal_rmse_m, 0.5 * e_held.horizontal_rmse_m);
}

}  // namespace
}  // namespace skerry
