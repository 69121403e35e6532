// Estimator configuration: every shipped preset loads, ToYaml round-trips every field, and bad
// input raises InputError naming the file, the 1-based line and the key path.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <limits>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/test_util.h"
#include "skerry/core/input_error.h"
#include "skerry/io/dataset.h"
#include "skerry/solvers/batch_smoother.h"
#include "skerry/solvers/estimator_config.h"
#include "skerry/solvers/keyframe_policy.h"
#include "skerry/solvers/navigation_estimator.h"
#include "skerry/solvers/sliding_window_estimator.h"
#include "skerry/solvers/yaw_hypothesis_bank.h"

namespace skerry {
namespace {

using testing::ExpectInputError;
using testing::FreshDir;
using testing::WriteText;

const std::string kPresetDir = std::string(SKERRY_SOURCE_DIR) + "/config/presets";

void ExpectCeresEq(const CeresConfig& a, const CeresConfig& b) {
  EXPECT_EQ(a.trust_region, b.trust_region);
  EXPECT_EQ(a.dogleg_type, b.dogleg_type);
  EXPECT_EQ(a.linear_solver, b.linear_solver);
  EXPECT_EQ(a.max_iterations, b.max_iterations);
  EXPECT_EQ(a.initial_trust_region_radius, b.initial_trust_region_radius);
  EXPECT_EQ(a.max_time_s, b.max_time_s);
  EXPECT_EQ(a.num_threads, b.num_threads);
  EXPECT_EQ(a.function_tolerance, b.function_tolerance);
  EXPECT_EQ(a.gradient_tolerance, b.gradient_tolerance);
  EXPECT_EQ(a.parameter_tolerance, b.parameter_tolerance);
  EXPECT_EQ(a.chain_gains, b.chain_gains);
}

void ExpectConfigEq(const EstimatorConfig& a, const EstimatorConfig& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.keyframe_rate_hz, b.keyframe_rate_hz);
  EXPECT_EQ(a.window_keyframes, b.window_keyframes);
  EXPECT_EQ(a.window_s, b.window_s);
  EXPECT_EQ(a.first_estimate_jacobians, b.first_estimate_jacobians);
  EXPECT_EQ(a.gnss_loss.type, b.gnss_loss.type);
  EXPECT_EQ(a.gnss_loss.scale, b.gnss_loss.scale);
  EXPECT_EQ(a.heading_loss.type, b.heading_loss.type);
  EXPECT_EQ(a.heading_loss.scale, b.heading_loss.scale);
  EXPECT_EQ(a.gnss_gate_probability, b.gnss_gate_probability);
  EXPECT_EQ(a.gnss_gate_max_reject_s, b.gnss_gate_max_reject_s);
  EXPECT_EQ(a.gnss_sigma_scale, b.gnss_sigma_scale);
  EXPECT_EQ(a.use_gnss_heading, b.use_gnss_heading);
  EXPECT_EQ(a.gnss_jump_test, b.gnss_jump_test);
  EXPECT_EQ(a.gnss_jump_as_drift_step, b.gnss_jump_as_drift_step);
  EXPECT_EQ(a.gnss_jump_step_after_s, b.gnss_jump_step_after_s);
  {
    SCOPED_TRACE("solver");
    ExpectCeresEq(a.ceres, b.ceres);
  }
  {
    SCOPED_TRACE("batch_solver");
    ExpectCeresEq(a.batch_ceres, b.batch_ceres);
  }
  EXPECT_EQ(a.compute_covariance, b.compute_covariance);
  EXPECT_EQ(a.init.mode, b.init.mode);
  EXPECT_EQ(a.init.min_cog_distance_m, b.init.min_cog_distance_m);
  EXPECT_EQ(a.init.max_cog_time_s, b.init.max_cog_time_s);
  EXPECT_EQ(a.init.attitude_window_s, b.init.attitude_window_s);
  EXPECT_EQ(a.init.roll_pitch_sigma_deg, b.init.roll_pitch_sigma_deg);
  EXPECT_EQ(a.init.yaw_sigma_deg, b.init.yaw_sigma_deg);
  EXPECT_EQ(a.init.velocity_sigma_m_s, b.init.velocity_sigma_m_s);
  EXPECT_EQ(a.init.position_sigma_scale, b.init.position_sigma_scale);
  EXPECT_EQ(a.init.static_s, b.init.static_s);
  EXPECT_EQ(a.init.align_hypotheses, b.init.align_hypotheses);
  EXPECT_EQ(a.init.align_min_s, b.init.align_min_s);
  EXPECT_EQ(a.init.align_max_s, b.init.align_max_s);
  EXPECT_EQ(a.init.align_decide_mass, b.init.align_decide_mass);
}

std::string WriteConfig(const std::string& text, const std::string& name = "config.yaml") {
  const std::string path = FreshDir("cfg") + "/" + name;
  WriteText(path, text);
  return path;
}

TEST(EstimatorConfigTest, EveryShippedPresetLoadsWithItsOwnName) {
  std::set<std::string> names;
  for (const auto& entry : std::filesystem::directory_iterator(kPresetDir)) {
    if (entry.path().extension() != ".yaml") continue;
    const std::string stem = entry.path().stem().string();
    names.insert(stem);
    SCOPED_TRACE(entry.path().string());
    EstimatorConfig c;
    ASSERT_NO_THROW(c = LoadEstimatorConfig(entry.path().string()));
    EXPECT_EQ(c.name, stem);
    // Also through the preset search path (the source tree is on it), and by path.
    EstimatorConfig by_path = LoadPreset(entry.path().string());
    ExpectConfigEq(by_path, c);
  }
  // The presets the docs and the CLI defaults refer to.
  for (const char* expected : {"default", "batch-lm", "dogleg-sparse", "lm-dense-qr",
                               "lm-dense-schur", "short-window-no-gate"}) {
    EXPECT_TRUE(names.count(expected)) << expected;
  }
}

TEST(EstimatorConfigTest, PresetValuesAreWhatTheFilesSay) {
  const EstimatorConfig d = LoadEstimatorConfig(kPresetDir + "/default.yaml");
  EXPECT_EQ(d.keyframe_rate_hz, 10.0);
  EXPECT_EQ(d.window_keyframes, 10);
  EXPECT_EQ(d.ceres.function_tolerance, 1e-6);
  EXPECT_TRUE(d.first_estimate_jacobians);
  EXPECT_EQ(d.gnss_loss.type, LossType::kHuber);
  EXPECT_EQ(d.gnss_loss.scale, 3.0);
  EXPECT_EQ(d.gnss_gate_probability, 0.999);
  EXPECT_EQ(d.gnss_gate_max_reject_s, 30.0);
  EXPECT_EQ(d.ceres.max_iterations, 10);
  EXPECT_EQ(d.ceres.max_time_s, 0.2);
  EXPECT_EQ(d.batch_ceres.max_iterations, 50);

  const EstimatorConfig poor = LoadEstimatorConfig(kPresetDir + "/short-window-no-gate.yaml");
  EXPECT_EQ(poor.window_keyframes, 3);
  EXPECT_FALSE(poor.first_estimate_jacobians);
  EXPECT_EQ(poor.gnss_loss.type, LossType::kNone);
  EXPECT_EQ(poor.gnss_gate_probability, 0.0);

  const EstimatorConfig dogleg = LoadEstimatorConfig(kPresetDir + "/dogleg-sparse.yaml");
  EXPECT_EQ(dogleg.ceres.trust_region, "dogleg");
  EXPECT_EQ(dogleg.batch_ceres.trust_region, "dogleg");

  const EstimatorConfig batch = LoadEstimatorConfig(kPresetDir + "/batch-lm.yaml");
  EXPECT_EQ(batch.batch_ceres.max_iterations, 100);
  EXPECT_EQ(batch.batch_ceres.function_tolerance, 1e-12);
  // Keys not given keep their defaults.
  EXPECT_EQ(batch.window_keyframes, EstimatorConfig().window_keyframes);
}

TEST(EstimatorConfigTest, LoadPresetByName) {
  const EstimatorConfig c = LoadPreset("lm-dense-qr");
  EXPECT_EQ(c.name, "lm-dense-qr");
  EXPECT_EQ(c.ceres.linear_solver, "dense_qr");
}

TEST(EstimatorConfigTest, RoundTripThroughYamlKeepsEveryField) {
  // Every field away from its default, with doubles that need all 17 digits.
  EstimatorConfig c;
  c.name = "round-trip";
  c.keyframe_rate_hz = 1.0 / 0.07;
  c.window_keyframes = 7;
  c.window_s = 2.0 / 3.0;
  c.first_estimate_jacobians = false;
  c.gnss_loss = {LossType::kCauchy, 2.0 / 7.0};
  c.heading_loss = {LossType::kTukey, 4.1};
  c.gnss_gate_probability = 0.9973;
  c.gnss_gate_max_reject_s = 12.345678901234567;
  c.gnss_sigma_scale = 1.0 / 3.0;
  c.use_gnss_heading = false;
  c.gnss_jump_as_drift_step = true;
  c.gnss_jump_step_after_s = 4.0 / 3.0;
  c.ceres = {"dogleg", "subspace", "dense_schur", 17, 3.3e7, 0.05, 2, 1e-9, 3e-11, 7e-9};
  c.batch_ceres = {"levenberg_marquardt", "traditional", "dense_qr", 77, 1e4, 0.0, 3,
                   1.0 / 3.0 * 1e-10,     1e-13,         2e-11};
  c.compute_covariance = false;
  c.init.mode = "cog";
  c.init.min_cog_distance_m = 9.5;
  c.init.max_cog_time_s = 31.0 / 3.0;
  c.init.attitude_window_s = 1.25;
  c.init.roll_pitch_sigma_deg = 2.5;
  c.init.yaw_sigma_deg = 7.0 / 3.0;
  c.init.velocity_sigma_m_s = 0.3;
  c.init.position_sigma_scale = 1.5;
  c.init.static_s = 4.0 / 3.0;
  c.init.align_hypotheses = 7;
  c.init.align_min_s = 12.5;
  c.init.align_max_s = 200.0 / 3.0;
  c.init.align_decide_mass = 0.95;

  const std::string path = WriteConfig(ToYaml(c), "round_trip.yaml");
  const EstimatorConfig back = LoadEstimatorConfig(path);
  ExpectConfigEq(back, c);

  // And the defaults round-trip too (the text that goes into summary.json).
  const std::string path2 = FreshDir("defaults") + "/defaults.yaml";
  WriteText(path2, ToYaml(EstimatorConfig()));
  EstimatorConfig defaults;
  defaults.name = "default";
  ExpectConfigEq(LoadEstimatorConfig(path2), defaults);
}

TEST(EstimatorConfigTest, NameDefaultsToTheFileStem) {
  const std::string path = WriteConfig("window_keyframes: 5\n", "my-tuning.yaml");
  const EstimatorConfig c = LoadEstimatorConfig(path);
  EXPECT_EQ(c.name, "my-tuning");
  EXPECT_EQ(c.window_keyframes, 5);
}

TEST(EstimatorConfigTest, UnknownTopLevelKey) {
  const std::string path = WriteConfig(
      "name: x\n"
      "window_keyframes: 10\n"
      "window_keyframs: 12\n");
  ExpectInputError([&] { LoadEstimatorConfig(path); }, path, 3, "window_keyframs");
}

TEST(EstimatorConfigTest, UnknownNestedKey) {
  const std::string path = WriteConfig(
      "name: x\n"
      "solver:\n"
      "  trust_region: dogleg\n"
      "  max_iteration: 4\n");
  ExpectInputError([&] { LoadEstimatorConfig(path); }, path, 4, "solver.max_iteration");
  const std::string path2 = WriteConfig(
      "gnss:\n"
      "  loss: huber\n"
      "  gate_prob: 0.99\n",
      "gnss.yaml");
  ExpectInputError([&] { LoadEstimatorConfig(path2); }, path2, 3, "gnss.gate_prob");
  const std::string path3 = WriteConfig(
      "init:\n"
      "  mode: cog\n"
      "\n"
      "  min_cog_distance: 3\n",
      "init.yaml");
  ExpectInputError([&] { LoadEstimatorConfig(path3); }, path3, 4, "init.min_cog_distance");
}

// lidar_aerial: every key round-trips through the text summary.json carries, and bad values name
// their key and line.
TEST(EstimatorConfigTest, LidarAerialKeysRoundTripAndAreChecked) {
  EstimatorConfig c;
  LidarAerialConfig& l = c.lidar_aerial;
  l.resolution_m = 0.2;
  l.max_distance_m = 4.0 / 3.0;
  l.sigma_m = 0.3;
  l.map_blur_m = 0.5;
  l.canny_high_quantile = 0.9;
  l.canny_low_quantile = 0.75;
  l.loss = "geman_mcclure";
  l.batch_loss = "huber";
  l.loss_sigmas = 0.0;
  l.window_trim_sigmas = 0.0;
  l.effective_points = 50.0;
  l.scan_correlation_s = 0.0;
  l.min_height_m = -0.2;
  l.max_range_m = 80.0;
  l.hull_min_b_m = {-7.5, -2.25, -1.0};
  l.hull_max_b_m = {7.5, 2.25, 4.0};
  l.cell_m = 0.4;
  l.front_sector_deg = 0.0;
  l.wall_gap_per_m = 0.02;
  l.max_edge_height_m = 0.0;
  l.max_points = 1000;
  l.min_points = 10;
  l.map_margin_m = 250.0;
  l.map_tile_above_mcells = 0.0;
  l.map_tile_m = 120.0;
  l.relocate_above_position_sigma_m = 0.0;
  l.reacquire_after_rejections = 7;
  l.relocate_above_heading_sigma_deg = 0.5;
  const LidarAerialConfig b =
      LoadEstimatorConfig(WriteConfig(ToYaml(c), "lidar.yaml")).lidar_aerial;
  EXPECT_EQ(b.resolution_m, l.resolution_m);
  EXPECT_EQ(b.max_distance_m, l.max_distance_m);
  EXPECT_EQ(b.sigma_m, l.sigma_m);
  EXPECT_EQ(b.map_blur_m, l.map_blur_m);
  EXPECT_EQ(b.canny_high_quantile, l.canny_high_quantile);
  EXPECT_EQ(b.canny_low_quantile, l.canny_low_quantile);
  EXPECT_EQ(b.loss, l.loss);
  EXPECT_EQ(b.batch_loss, l.batch_loss);
  EXPECT_EQ(b.loss_sigmas, l.loss_sigmas);
  EXPECT_EQ(b.window_trim_sigmas, l.window_trim_sigmas);
  EXPECT_EQ(b.effective_points, l.effective_points);
  EXPECT_EQ(b.scan_correlation_s, l.scan_correlation_s);
  EXPECT_EQ(b.min_height_m, l.min_height_m);
  EXPECT_EQ(b.max_range_m, l.max_range_m);
  EXPECT_EQ(b.hull_min_b_m, l.hull_min_b_m);
  EXPECT_EQ(b.hull_max_b_m, l.hull_max_b_m);
  EXPECT_EQ(b.cell_m, l.cell_m);
  EXPECT_EQ(b.front_sector_deg, l.front_sector_deg);
  EXPECT_EQ(b.wall_gap_per_m, l.wall_gap_per_m);
  EXPECT_EQ(b.max_edge_height_m, l.max_edge_height_m);
  EXPECT_EQ(b.max_points, l.max_points);
  EXPECT_EQ(b.min_points, l.min_points);
  EXPECT_EQ(b.map_margin_m, l.map_margin_m);
  EXPECT_EQ(b.map_tile_above_mcells, l.map_tile_above_mcells);
  EXPECT_EQ(b.map_tile_m, l.map_tile_m);
  EXPECT_EQ(b.relocate_above_position_sigma_m, l.relocate_above_position_sigma_m);
  EXPECT_EQ(b.reacquire_after_rejections, l.reacquire_after_rejections);
  EXPECT_EQ(b.relocate_above_heading_sigma_deg, l.relocate_above_heading_sigma_deg);

  const std::string hull = WriteConfig("lidar_aerial:\n  hull_min_b_m: [1, 2]\n", "hull.yaml");
  ExpectInputError([&] { LoadEstimatorConfig(hull); }, hull, 2, "lidar_aerial.hull_min_b_m");
  const std::string order = WriteConfig(
      "lidar_aerial:\n  hull_min_b_m: [1, 0, 0]\n  hull_max_b_m: [0, 1, 1]\n", "order.yaml");
  ExpectInputError([&] { LoadEstimatorConfig(order); }, order, 3, "lidar_aerial.hull_max_b_m");
  const std::string sigma = WriteConfig("lidar_aerial:\n  sigma_m: 0\n", "sigma.yaml");
  ExpectInputError([&] { LoadEstimatorConfig(sigma); }, sigma, 2, "lidar_aerial.sigma_m");
  const std::string loss = WriteConfig("lidar_aerial:\n  batch_loss: cauchy\n", "loss.yaml");
  ExpectInputError([&] { LoadEstimatorConfig(loss); }, loss, 2, "lidar_aerial.batch_loss");
  const std::string typo = WriteConfig("lidar_aerial:\n  sigma: 1\n", "typo.yaml");
  ExpectInputError([&] { LoadEstimatorConfig(typo); }, typo, 2, "lidar_aerial.sigma");
}

TEST(EstimatorConfigTest, AlignKeysAreChecked) {
  const std::string ok = WriteConfig("init:\n  mode: align\n  static_s: 4\n", "align.yaml");
  EXPECT_EQ(LoadEstimatorConfig(ok).init.mode, "align");
  EXPECT_EQ(LoadEstimatorConfig(ok).init.static_s, 4.0);
  const std::string none = WriteConfig("init:\n  mode: align\n  align_hypotheses: 0\n", "k0.yaml");
  ExpectInputError([&] { LoadEstimatorConfig(none); }, none, 3, "init.align_hypotheses");
  const std::string mass =
      WriteConfig("init:\n  align_decide_mass: 1.5\n  mode: align\n", "mass.yaml");
  ExpectInputError([&] { LoadEstimatorConfig(mass); }, mass, 2, "init.align_decide_mass");
  const std::string neg = WriteConfig("init:\n  static_s: -1\n", "neg.yaml");
  ExpectInputError([&] { LoadEstimatorConfig(neg); }, neg, 2, "init.static_s");
  const std::string mode = WriteConfig("init:\n  mode: alignn\n", "mode.yaml");
  ExpectInputError([&] { LoadEstimatorConfig(mode); }, mode, 2, "init.mode");
  const std::string order =
      WriteConfig("init:\n  align_min_s: 30\n  align_max_s: 20\n", "order.yaml");
  ExpectInputError([&] { LoadEstimatorConfig(order); }, order, 3, "init.align_max_s");
  const std::string min_only = WriteConfig("init:\n  align_min_s: 500\n", "min.yaml");
  ExpectInputError([&] { LoadEstimatorConfig(min_only); }, min_only, 2, "init.align_min_s");
}

// A jump taken into the drift needs the drift and the jump test; said with the key's line.
TEST(EstimatorConfigTest, JumpAsDriftStepNeedsTheDriftAndTheJumpTest) {
  const std::string ok =
      WriteConfig("gnss:\n  jump_as_drift_step: true\n  jump_step_after_s: 2\n", "step_ok.yaml");
  EXPECT_TRUE(LoadEstimatorConfig(ok).gnss_jump_as_drift_step);
  EXPECT_EQ(LoadEstimatorConfig(ok).gnss_jump_step_after_s, 2.0);
  const std::string no_drift = WriteConfig(
      "gnss:\n  drift_sigma_horizontal_m: 0\n  jump_as_drift_step: true\n"
      "  drift_sigma_vertical_m: 0\n",
      "step_no_drift.yaml");
  ExpectInputError([&] { LoadEstimatorConfig(no_drift); }, no_drift, 3, "gnss.jump_as_drift_step");
  const std::string no_test =
      WriteConfig("gnss:\n  jump_test: false\n  jump_as_drift_step: true\n", "step_no_test.yaml");
  ExpectInputError([&] { LoadEstimatorConfig(no_test); }, no_test, 3, "gnss.jump_as_drift_step");
  const std::string negative =
      WriteConfig("gnss:\n  jump_step_after_s: -1\n", "step_negative.yaml");
  ExpectInputError([&] { LoadEstimatorConfig(negative); }, negative, 2, "gnss.jump_step_after_s");
}

TEST(EstimatorConfigTest, SkylineFrameCorrelationKeysRoundTripAndAreChecked) {
  const std::string ok = WriteConfig(
      "skyline:\n  frame_correlation_s: 0\n  frame_correlation_m: 45.5\n", "crest_ok.yaml");
  const EstimatorConfig c = LoadEstimatorConfig(ok);
  EXPECT_EQ(c.skyline.frame_correlation_s, 0.0);
  EXPECT_EQ(c.skyline.frame_correlation_m, 45.5);
  EXPECT_EQ(
      LoadEstimatorConfig(WriteConfig(ToYaml(c), "crest_back.yaml")).skyline.frame_correlation_m,
      45.5);
  const std::string negative =
      WriteConfig("skyline:\n  frame_correlation_m: -1\n", "crest_negative.yaml");
  ExpectInputError([&] { LoadEstimatorConfig(negative); }, negative, 2,
                   "skyline.frame_correlation_m");
  const std::string nan = WriteConfig("skyline:\n  frame_correlation_m: .nan\n", "crest_nan.yaml");
  ExpectInputError([&] { LoadEstimatorConfig(nan); }, nan, 2, "skyline.frame_correlation_m");
}

TEST(EstimatorConfigTest, SkylineSigmasRoundTripAndAreChecked) {
  struct Key {
    const char* name;
    double SkylineConfig::*member;
    double default_value, value;
  };
  for (const Key& k : {Key{"dem_sigma_m", &SkylineConfig::dem_sigma_m, 4.0, 4.5},
                       Key{"refraction_k_sigma", &SkylineConfig::refraction_k_sigma, 0.0, 0.1}}) {
    EXPECT_EQ(EstimatorConfig{}.skyline.*k.member, k.default_value) << k.name;
    const std::string ok = WriteConfig(
        std::string("skyline:\n  ") + k.name + ": " + std::to_string(k.value) + "\n", "ok.yaml");
    const EstimatorConfig c = LoadEstimatorConfig(ok);
    EXPECT_EQ(c.skyline.*k.member, k.value) << k.name;
    EXPECT_EQ(LoadEstimatorConfig(WriteConfig(ToYaml(c), "back.yaml")).skyline.*k.member, k.value)
        << k.name;
    for (const char* bad : {"-1", ".nan", ".inf", "four"}) {
      const std::string path =
          WriteConfig(std::string("\nskyline:\n  ") + k.name + ": " + bad + "\n", "bad.yaml");
      ExpectInputError([&] { LoadEstimatorConfig(path); }, path, 3,
                       std::string("skyline.") + k.name);
    }
  }
}

// The map's oversampling of the DEM's cell: an integer of at least 1, 2 by default.
TEST(EstimatorConfigTest, SkylineDemOversamplingRoundTripsAndIsChecked) {
  EXPECT_EQ(EstimatorConfig{}.skyline.dem_oversampling, 2);
  const EstimatorConfig c =
      LoadEstimatorConfig(WriteConfig("skyline:\n  dem_oversampling: 3\n", "over_ok.yaml"));
  EXPECT_EQ(c.skyline.dem_oversampling, 3);
  EXPECT_EQ(LoadEstimatorConfig(WriteConfig(ToYaml(c), "over_back.yaml")).skyline.dem_oversampling,
            3);
  for (const char* bad : {"0", "-2", "1.5", ".nan", "twice"}) {
    const std::string path =
        WriteConfig(std::string("\nskyline:\n  dem_oversampling: ") + bad + "\n", "over_bad.yaml");
    ExpectInputError([&] { LoadEstimatorConfig(path); }, path, 3, "skyline.dem_oversampling");
  }
}

// The map's sharpening: off by default, a gain >= 0 and a footprint > 0, both round-tripped.
TEST(EstimatorConfigTest, SkylineDemSharpeningRoundTripsAndIsChecked) {
  EXPECT_EQ(EstimatorConfig{}.skyline.dem_sharpening, 0.0);
  EXPECT_EQ(EstimatorConfig{}.skyline.dem_footprint_cells, 0.75);
  const EstimatorConfig c = LoadEstimatorConfig(
      WriteConfig("skyline:\n  dem_sharpening: 2\n  dem_footprint_cells: 0.6\n", "sharp_ok.yaml"));
  EXPECT_EQ(c.skyline.dem_sharpening, 2.0);
  EXPECT_EQ(c.skyline.dem_footprint_cells, 0.6);
  const EstimatorConfig back = LoadEstimatorConfig(WriteConfig(ToYaml(c), "sharp_back.yaml"));
  EXPECT_EQ(back.skyline.dem_sharpening, 2.0);
  EXPECT_EQ(back.skyline.dem_footprint_cells, 0.6);
  for (const char* bad : {"-1", ".nan", ".inf", "much"}) {
    const std::string path =
        WriteConfig(std::string("\nskyline:\n  dem_sharpening: ") + bad + "\n", "sharp_bad.yaml");
    ExpectInputError([&] { LoadEstimatorConfig(path); }, path, 3, "skyline.dem_sharpening");
  }
  for (const char* bad : {"0", "-0.5", ".nan", "wide", "45"}) {
    const std::string path = WriteConfig(
        std::string("\nskyline:\n  dem_footprint_cells: ") + bad + "\n", "foot_bad.yaml");
    ExpectInputError([&] { LoadEstimatorConfig(path); }, path, 3, "skyline.dem_footprint_cells");
  }
}

// The crest offset: off by default, signed, bounded, round-trips; estimated alone, never with
// the refraction coefficient (the camera's sensor parameter is one number).
TEST(EstimatorConfigTest, SkylineCrestOffsetRoundTripsAndIsChecked) {
  EXPECT_EQ(EstimatorConfig{}.skyline.crest_offset_m, 0.0);
  EXPECT_EQ(EstimatorConfig{}.skyline.crest_offset_sigma_m, 0.0);
  const EstimatorConfig c = LoadEstimatorConfig(WriteConfig(
      "skyline:\n  crest_offset_m: -2.5\n  crest_offset_sigma_m: 4\n", "crest_ok.yaml"));
  EXPECT_EQ(c.skyline.crest_offset_m, -2.5);
  EXPECT_EQ(c.skyline.crest_offset_sigma_m, 4.0);
  const EstimatorConfig back =
      LoadEstimatorConfig(WriteConfig(ToYaml(c), "crest_offset_back.yaml"));
  EXPECT_EQ(back.skyline.crest_offset_m, -2.5);
  EXPECT_EQ(back.skyline.crest_offset_sigma_m, 4.0);
  for (const char* bad : {".nan", ".inf", "-1e4", "high"}) {
    const std::string path =
        WriteConfig(std::string("\nskyline:\n  crest_offset_m: ") + bad + "\n", "crest_bad.yaml");
    ExpectInputError([&] { LoadEstimatorConfig(path); }, path, 3, "skyline.crest_offset_m");
  }
  for (const char* bad : {"-1", ".nan", ".inf", "wide"}) {
    const std::string path = WriteConfig(
        std::string("\nskyline:\n  crest_offset_sigma_m: ") + bad + "\n", "crest_sbad.yaml");
    ExpectInputError([&] { LoadEstimatorConfig(path); }, path, 3, "skyline.crest_offset_sigma_m");
  }
  const std::string both = WriteConfig(
      "skyline:\n  refraction_k_sigma: 0.1\n  crest_offset_sigma_m: 4\n", "crest_both.yaml");
  ExpectInputError([&] { LoadEstimatorConfig(both); }, both, 3, "skyline.crest_offset_sigma_m");
}

// The sharpening gain estimated: off by default, round-trips, >= 0, and the camera's only
// estimated parameter.
TEST(EstimatorConfigTest, SkylineDemSharpeningSigmaRoundTripsAndIsChecked) {
  EXPECT_EQ(EstimatorConfig{}.skyline.dem_sharpening_sigma, 0.0);
  const EstimatorConfig c =
      LoadEstimatorConfig(WriteConfig("skyline:\n  dem_sharpening_sigma: 1.5\n", "gain_ok.yaml"));
  EXPECT_EQ(c.skyline.dem_sharpening_sigma, 1.5);
  EXPECT_EQ(
      LoadEstimatorConfig(WriteConfig(ToYaml(c), "gain_back.yaml")).skyline.dem_sharpening_sigma,
      1.5);
  for (const char* bad : {"-1", ".nan", ".inf", "some"}) {
    const std::string path = WriteConfig(
        std::string("\nskyline:\n  dem_sharpening_sigma: ") + bad + "\n", "gain_bad.yaml");
    ExpectInputError([&] { LoadEstimatorConfig(path); }, path, 3, "skyline.dem_sharpening_sigma");
  }
  for (const char* other : {"refraction_k_sigma: 0.1", "crest_offset_sigma_m: 4"}) {
    const std::string path = WriteConfig(
        std::string("skyline:\n  ") + other + "\n  dem_sharpening_sigma: 1\n", "gain_two.yaml");
    ExpectInputError([&] { LoadEstimatorConfig(path); }, path, 3, "skyline.dem_sharpening_sigma");
  }
}

// The refraction coefficient may be negative (over cold water), never 1 or beyond.
TEST(EstimatorConfigTest, SkylineRefractionIsInItsRange) {
  EXPECT_EQ(LoadEstimatorConfig(WriteConfig("skyline:\n  refraction_k: -0.2\n", "k_ok.yaml"))
                .skyline.refraction_k,
            -0.2);
  for (const char* bad : {"1", "-1", "1.5", ".nan", ".inf", "cold"}) {
    const std::string path =
        WriteConfig(std::string("\nskyline:\n  refraction_k: ") + bad + "\n", "k_bad.yaml");
    ExpectInputError([&] { LoadEstimatorConfig(path); }, path, 3, "skyline.refraction_k");
  }
}

TEST(EstimatorConfigTest, WrongType) {
  const std::string path = WriteConfig(
      "name: x\n"
      "solver:\n"
      "  max_iterations: ten\n");
  ExpectInputError([&] { LoadEstimatorConfig(path); }, path, 3, "solver.max_iterations");
  const std::string path2 = WriteConfig("first_estimate_jacobians: maybe\n", "bool.yaml");
  ExpectInputError([&] { LoadEstimatorConfig(path2); }, path2, 1, "first_estimate_jacobians");
  const std::string path3 = WriteConfig("keyframe_rate_hz: [10, 20]\n", "seq.yaml");
  ExpectInputError([&] { LoadEstimatorConfig(path3); }, path3, 1, "keyframe_rate_hz");
  // A section that is not a mapping.
  const std::string path4 = WriteConfig("name: x\ngnss: 3\n", "notmap.yaml");
  ExpectInputError([&] { LoadEstimatorConfig(path4); }, path4, 2, "gnss");
}

TEST(EstimatorConfigTest, NegativeMaxIterations) {
  const std::string path = WriteConfig(
      "batch_solver:\n"
      "  linear_solver: dense_qr\n"
      "  max_iterations: -5\n");
  ExpectInputError([&] { LoadEstimatorConfig(path); }, path, 3, "batch_solver.max_iterations");
}

TEST(EstimatorConfigTest, OutOfRangeNumbers) {
  const std::string path = WriteConfig("name: x\nkeyframe_rate_hz: 0\n");
  ExpectInputError([&] { LoadEstimatorConfig(path); }, path, 2, "keyframe_rate_hz");
  const std::string path2 = WriteConfig("window_keyframes: 1\n", "window.yaml");
  ExpectInputError([&] { LoadEstimatorConfig(path2); }, path2, 1, "window_keyframes");
  const std::string path3 = WriteConfig("solver:\n  num_threads: 0\n", "threads.yaml");
  ExpectInputError([&] { LoadEstimatorConfig(path3); }, path3, 2, "solver.num_threads");
  const std::string path4 = WriteConfig("init:\n  yaw_sigma_deg: .nan\n", "nan.yaml");
  ExpectInputError([&] { LoadEstimatorConfig(path4); }, path4, 2, "init.yaw_sigma_deg");
}

// Every duration in seconds becomes int64 nanoseconds: 1e300 s made a negative time (with
// init.attitude_window_s no sample averaged and the run aborted on a NaN attitude), so a duration
// past kMaxDurationS is refused where it is written, and the longest one allowed is taken.
TEST(EstimatorConfigTest, DurationsAreBounded) {
  const std::vector<std::pair<std::string, std::string>> keys = {
      {"", "window_s"},
      {"solver", "max_time_s"},
      {"batch_solver", "max_time_s"},
      {"gnss", "gate_max_reject_s"},
      {"gnss", "gate_streak_max_gap_s"},
      {"gnss", "jump_step_after_s"},
      {"gnss", "drift_tau_s"},
      {"skyline", "frame_correlation_s"},
      {"lidar_aerial", "scan_correlation_s"},
      {"init", "max_cog_time_s"},
      {"init", "attitude_window_s"},
      {"init", "static_s"},
      {"init", "align_min_s"},
      {"init", "align_max_s"},
      {"watchdog", "window_s"},
  };
  for (const auto& entry : keys) {
    // Named copies, not structured bindings: a C++17 lambda may not capture a binding (clang).
    const std::string section = entry.first;
    const std::string key = entry.second;
    const std::string path_name = section.empty() ? key : section + "." + key;
    SCOPED_TRACE(path_name);
    auto yaml = [&](const std::string& value) {
      if (section.empty()) return "name: x\n" + key + ": " + value + "\n";
      return "name: x\n" + section + ":\n  " + key + ": " + value + "\n";
    };
    const int line = section.empty() ? 2 : 3;
    for (const char* bad : {"1e300", "1.0e10", ".inf"}) {
      const std::string path = WriteConfig(yaml(bad), "duration_bad.yaml");
      ExpectInputError([&] { LoadEstimatorConfig(path); }, path, line, path_name);
    }
    // The bound itself is a duration like any other (align_min_s must stay below align_max_s).
    const std::string value = key == "align_min_s" ? "1" : "1e9";
    const std::string path = WriteConfig(yaml(value), "duration_max.yaml");
    EXPECT_NO_THROW(LoadEstimatorConfig(path));
  }
  EXPECT_EQ(LoadEstimatorConfig(WriteConfig("init:\n  attitude_window_s: 1e9\n", "aw.yaml"))
                .init.attitude_window_s,
            1e9);
}

// The keyframe period 1 / keyframe_rate_hz must be a duration (at most 1e9 s) and at least a
// microsecond: 1e-12 Hz gave a keyframe at every IMU sample and no solve at all, reported as a
// run; 1e308 Hz a period of 0 ns.
TEST(EstimatorConfigTest, KeyframeRateIsBounded) {
  for (const char* bad : {"1e-12", "9.9e-10", "1.1e6", "1e308"}) {
    SCOPED_TRACE(bad);
    const std::string path = WriteConfig(std::string("name: x\nkeyframe_rate_hz: ") + bad + "\n");
    ExpectInputError([&] { LoadEstimatorConfig(path); }, path, 2, "keyframe_rate_hz");
  }
  for (const double good : {1e-9, 0.5, 1e6}) {
    std::ostringstream yaml;
    yaml.precision(17);
    yaml << "keyframe_rate_hz: " << good << "\n";
    EXPECT_EQ(LoadEstimatorConfig(WriteConfig(yaml.str(), "rate.yaml")).keyframe_rate_hz, good);
  }
  // The same bound where a program sets the rate itself (the estimator's policy).
  EXPECT_THROW(KeyframePolicy(1e-12), std::invalid_argument);
  EXPECT_THROW(KeyframePolicy(1e308), std::invalid_argument);
  EXPECT_THROW(KeyframePolicy(std::nan("")), std::invalid_argument);
  EXPECT_NEAR(static_cast<double>(KeyframePolicy(1e-9).period_ns()), 1e18, 1e3);  // 1e9 s
}

// A program that embeds skerry builds its EstimatorConfig in code: the estimators check it as
// the reader checks a file, naming the key path, where before a NaN sigma or a 1e300 s window
// went into the solve (the file's checks, DurationsAreBounded above, stood only in the reader).
TEST(EstimatorConfigTest, AProgramsConfigurationIsCheckedAsAFileIs) {
  EXPECT_NO_THROW(ValidateEstimatorConfig(EstimatorConfig()));
  for (const auto& entry : std::filesystem::directory_iterator(kPresetDir)) {
    SCOPED_TRACE(entry.path().string());
    EXPECT_NO_THROW(ValidateEstimatorConfig(LoadEstimatorConfig(entry.path().string())));
  }
  // Values at a bound survive the trip through the YAML text to the last bit.
  EstimatorConfig edge;
  edge.gnss_gate_probability = std::nextafter(1.0, 0.0);
  edge.keyframe_rate_hz = 1e-9;
  edge.init.attitude_window_s = kMaxDurationS;
  edge.init.static_s = 0.0;
  EXPECT_NO_THROW(ValidateEstimatorConfig(edge));

  struct Case {
    const char* key;
    void (*wrong)(EstimatorConfig*);
  };
  const Case cases[] = {
      {"skyline.sigma_px", [](EstimatorConfig* c) { c->skyline.sigma_px = std::nan(""); }},
      {"init.attitude_window_s", [](EstimatorConfig* c) { c->init.attitude_window_s = 1e300; }},
      {"gnss.gate_probability", [](EstimatorConfig* c) { c->gnss_gate_probability = 1.0; }},
      {"gnss.drift_tau_s",
       [](EstimatorConfig* c) { c->gnss_drift.tau_s = std::numeric_limits<double>::infinity(); }},
      {"solver.linear_solver", [](EstimatorConfig* c) { c->ceres.linear_solver = "bogus"; }},
      {"batch_solver.chain_gains", [](EstimatorConfig* c) { c->batch_ceres.chain_gains = "half"; }},
      {"batch_solver.max_iterations",
       [](EstimatorConfig* c) { c->batch_ceres.max_iterations = 0; }},
      {"window_keyframes", [](EstimatorConfig* c) { c->window_keyframes = 1; }},
      {"keyframe_rate_hz", [](EstimatorConfig* c) { c->keyframe_rate_hz = -10.0; }},
      {"skyline.refraction_k", [](EstimatorConfig* c) { c->skyline.refraction_k = 1.0; }},
      {"lidar_aerial.hull_min_b_m", [](EstimatorConfig* c) { c->lidar_aerial.hull_min_b_m = {0}; }},
      {"lidar_aerial.loss", [](EstimatorConfig* c) { c->lidar_aerial.loss = "cauchy"; }},
      {"sensors.camera.gate_probability",
       [](EstimatorConfig* c) { c->sensors["camera"].gate_probability = -0.5; }},
      {"init.mode", [](EstimatorConfig* c) { c->init.mode = "guess"; }},
      {"init.align_max_s", [](EstimatorConfig* c) { c->init.align_max_s = 1.0; }},
      {"gnss.jump_as_drift_step",
       [](EstimatorConfig* c) {
         c->gnss_jump_as_drift_step = true;
         c->gnss_jump_test = false;
       }},
      {"watchdog.rejected_share", [](EstimatorConfig* c) { c->watchdog.rejected_share = 2.0; }},
  };
  for (const Case& k : cases) {
    SCOPED_TRACE(k.key);
    EstimatorConfig config;
    k.wrong(&config);
    const std::string expected = std::string("EstimatorConfig ") + k.key + ": ";
    try {
      ValidateEstimatorConfig(config);
      ADD_FAILURE() << "no error";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()).rfind(expected, 0), 0u) << e.what();
    }
    // The window and the batch refuse it before they use it.
    try {
      SlidingWindowEstimator window(config, ImuConfig(), GnssConfig(), EarthModel::Flat());
      ADD_FAILURE() << "the window took it";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()).rfind(expected, 0), 0u) << e.what();
    }
    try {
      SmoothFrom(Dataset(), config, EstimateRecord(), 0);
      ADD_FAILURE() << "the batch took it";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()).rfind(expected, 0), 0u) << e.what();
    }
    // So do the estimator a program embeds and the alignment's bank, each checking it once.
    try {
      NavigationEstimator estimator(config, ImuConfig(), GnssConfig(), EarthModel::Flat());
      ADD_FAILURE() << "the navigation estimator took it";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()).rfind(expected, 0), 0u) << e.what();
    }
    try {
      YawHypothesisBank bank(config, ImuConfig(), GnssConfig(), EarthModel::Flat());
      ADD_FAILURE() << "the alignment's bank took it";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()).rfind(expected, 0), 0u) << e.what();
    }
  }
  // An owner that checked its configuration builds windows from it unchecked (a restart, each of
  // an alignment's hypotheses): the tag skips the check, which the owner made once.
  EstimatorConfig wrong;
  wrong.skyline.sigma_px = std::nan("");
  EXPECT_NO_THROW(SlidingWindowEstimator(wrong, ImuConfig(), GnssConfig(), EarthModel::Flat(),
                                         ConfigValidated()));
  EXPECT_NO_THROW(
      YawHypothesisBank(wrong, ImuConfig(), GnssConfig(), EarthModel::Flat(), ConfigValidated()));
}

TEST(EstimatorConfigTest, BadLossName) {
  const std::string path = WriteConfig(
      "name: x\n"
      "gnss:\n"
      "  loss_scale: 2.0\n"
      "  loss: hubber\n");
  ExpectInputError([&] { LoadEstimatorConfig(path); }, path, 4, "gnss.loss");
  const std::string path2 = WriteConfig("gnss:\n  heading_loss: l2\n", "heading.yaml");
  ExpectInputError([&] { LoadEstimatorConfig(path2); }, path2, 2, "gnss.heading_loss");
}

// The Ceres option names are validated into enums at load: the error must point at the key that
// is wrong, on its line, like every other configuration error.
TEST(EstimatorConfigTest, BadLinearSolver) {
  const std::string path = WriteConfig(
      "name: x\n"
      "solver:\n"
      "  trust_region: levenberg_marquardt\n"
      "  linear_solver: sparse_cholesky\n");
  ExpectInputError([&] { LoadEstimatorConfig(path); }, path, 4, "solver.linear_solver");
}

TEST(EstimatorConfigTest, BadChainGains) {
  const std::string path = WriteConfig(
      "batch_solver:\n"
      "  linear_solver: chain\n"
      "  chain_gains: float\n");
  ExpectInputError([&] { LoadEstimatorConfig(path); }, path, 3, "batch_solver.chain_gains");
}

TEST(EstimatorConfigTest, BadTrustRegion) {
  const std::string path = WriteConfig(
      "batch_solver:\n"
      "  trust_region: gauss_newton\n");
  ExpectInputError([&] { LoadEstimatorConfig(path); }, path, 2, "batch_solver.trust_region");
}

TEST(EstimatorConfigTest, GateProbabilityMustBeBelowOne) {
  for (const char* value : {"1", "1.0", "1.5"}) {
    SCOPED_TRACE(value);
    const std::string path = WriteConfig(std::string("name: x\n"
                                                     "gnss:\n"
                                                     "  loss: huber\n"
                                                     "  gate_probability: ") +
                                         value + "\n");
    ExpectInputError([&] { LoadEstimatorConfig(path); }, path, 4, "gnss.gate_probability");
  }
  const std::string negative = WriteConfig("gnss:\n  gate_probability: -0.1\n", "neg.yaml");
  ExpectInputError([&] { LoadEstimatorConfig(negative); }, negative, 2, "gnss.gate_probability");
  // 0 switches the gate off and is accepted.
  const std::string off = WriteConfig("gnss:\n  gate_probability: 0\n", "off.yaml");
  EXPECT_EQ(LoadEstimatorConfig(off).gnss_gate_probability, 0.0);
}

TEST(EstimatorConfigTest, UnknownInitMode) {
  const std::string path = WriteConfig(
      "name: x\n"
      "init:\n"
      "  min_cog_distance_m: 10\n"
      "  mode: compass\n");
  ExpectInputError([&] { LoadEstimatorConfig(path); }, path, 4, "init.mode");
}

TEST(EstimatorConfigTest, MissingFile) {
  const std::string path = FreshDir("missing") + "/no_such_config.yaml";
  try {
    LoadEstimatorConfig(path);
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path);
    EXPECT_EQ(e.line(), 0);
    EXPECT_NE(std::string(e.what()).find("no_such_config.yaml"), std::string::npos);
  }
}

TEST(EstimatorConfigTest, YamlSyntaxError) {
  const std::string path = WriteConfig(
      "name: x\n"
      "solver:\n"
      "  max_iterations: [1, 2\n"
      "window_keyframes: 3\n");
  try {
    LoadEstimatorConfig(path);
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path);
    // The unclosed flow sequence opens on line 3; yaml-cpp reports where it notices, 3 or 4.
    EXPECT_GE(e.line(), 3) << e.what();
    EXPECT_LE(e.line(), 4) << e.what();
  }
  const std::string tabs = WriteConfig("name: x\nsolver:\n  a: 1\n b: 2\n", "indent.yaml");
  try {
    LoadEstimatorConfig(tabs);
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), tabs);
    EXPECT_EQ(e.line(), 4) << e.what();
  }
}

// `--set KEY=VALUE` on a preset: the key changes, every other key keeps the preset's value (a
// YAML file alone would start from the code's defaults), sections are made where missing, and
// each override is checked as a file's key is, its errors naming the command line's option.
TEST(EstimatorConfigTest, SetOverridesOneKeyOfAPreset) {
  const EstimatorConfig preset = LoadPreset("default");
  const EstimatorConfig c =
      LoadPreset("default", {"skyline.dem_spacing_m=63", "solver.max_iterations=4",
                             "gnss.loss=cauchy", "skyline.dem_spacing_m=62.5"});
  EXPECT_EQ(c.skyline.dem_spacing_m, 62.5);  // the last of a key wins
  EXPECT_EQ(c.ceres.max_iterations, 4);
  EXPECT_EQ(c.gnss_loss.type, LossType::kCauchy);
  EXPECT_EQ(c.name, preset.name);
  // Everything else is the preset's, not the code's defaults (they differ in the tolerances).
  EXPECT_EQ(c.ceres.function_tolerance, preset.ceres.function_tolerance);
  EXPECT_NE(preset.ceres.function_tolerance, EstimatorConfig().ceres.function_tolerance);
  EXPECT_EQ(c.window_keyframes, preset.window_keyframes);
  EXPECT_EQ(c.skyline.sigma_px, preset.skyline.sigma_px);
  EXPECT_EQ(ToYaml(LoadPreset("default", {})), ToYaml(preset));
  // A section the file does not have, and an empty file.
  const std::string empty = WriteConfig("", "empty.yaml");
  const EstimatorConfig e = LoadEstimatorConfig(empty, {"skyline.threads=3", "window_keyframes=7"});
  EXPECT_EQ(e.skyline.threads, 3);
  EXPECT_EQ(e.window_keyframes, 7);
}

TEST(EstimatorConfigTest, SetErrorsNameTheOverride) {
  auto expect = [](const std::vector<std::string>& set, const std::string& field,
                   const std::string& message) {
    try {
      LoadPreset("default", set);
      ADD_FAILURE() << "no InputError for " << set.back();
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), "(command line)") << set.back();
      EXPECT_EQ(e.line(), 0) << set.back();
      EXPECT_EQ(e.field(), field) << set.back();
      EXPECT_NE(e.message().find(message), std::string::npos) << e.message();
    }
  };
  expect({"skyline.dem_spacing_m"}, "--set", "expected KEY=VALUE");
  expect({"=3"}, "--set", "expected KEY=VALUE");
  expect({"skyline..threads=3"}, "--set skyline..threads", "empty key name");
  expect({"skyline.threads="}, "--set skyline.threads", "no value");
  expect({"skyline.threads=[1, 2"}, "--set skyline.threads", "not a YAML value");
  expect({"skyline.no_such_key=1"}, "--set skyline.no_such_key", "unknown key");
  expect({"skyline.dem_spacing_m=-5"}, "--set skyline.dem_spacing_m", "must be >= 0");
  expect({"skyline.threads=many"}, "--set skyline.threads", "wrong type");
  expect({"name.x=1"}, "--set name.x", "not a section");
  expect({"skyline=5"}, "--set skyline", "expected a mapping");
  // An error in the file itself still names the file and its line.
  const std::string path = WriteConfig("solver:\n  max_iteration: 4\n", "typo.yaml");
  ExpectInputError([&] { LoadEstimatorConfig(path, {"solver.max_iterations=3"}); }, path, 2,
                   "solver.max_iteration");
}

TEST(EstimatorConfigTest, UnknownPresetName) {
  try {
    LoadPreset("no-such-preset");
    ADD_FAILURE() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "no-such-preset");
    EXPECT_NE(std::string(e.what()).find("no-such-preset"), std::string::npos);
  }
}

TEST(EstimatorConfigTest, PresetDirFromEnvironmentWins) {
  const std::string dir = FreshDir("presets");
  WriteText(dir + "/default.yaml", "name: overridden\nwindow_keyframes: 4\n");
  ASSERT_EQ(setenv("SKERRY_PRESET_DIR", dir.c_str(), 1), 0);
  EstimatorConfig c;
  try {
    c = LoadPreset("default");
  } catch (...) {
    unsetenv("SKERRY_PRESET_DIR");
    throw;
  }
  unsetenv("SKERRY_PRESET_DIR");
  EXPECT_EQ(c.name, "overridden");
  EXPECT_EQ(c.window_keyframes, 4);
}

}  // namespace
}  // namespace skerry
