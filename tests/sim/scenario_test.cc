// Scenario loading: the built-in scenarios, the search path, and errors that name file, line and
// key path.

#include "skerry/sim/scenario.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "sim/sim_test_util.h"
#include "skerry/core/input_error.h"
#include "skerry/sim/simulator.h"

namespace skerry::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;

const char* kMinimal = R"(name: tiny
duration_s: 10
origin: {lat_deg: 47.6, lon_deg: 9.45, height_m: 440}
)";

// Parses `text` and returns the InputError it must raise.
InputError ErrorOf(const std::string& text) {
  try {
    ParseScenario(text, "test.yaml");
  } catch (const InputError& e) {
    return e;
  }
  ADD_FAILURE() << "no InputError for:\n" << text;
  return InputError("", 0, "", "");
}

TEST(Scenario, HarbourHasTheBriefedContent) {
  const ScenarioConfig c = LoadScenario("harbour");
  EXPECT_EQ(c.name, "harbour");
  EXPECT_EQ(c.duration_s, 600.0);
  EXPECT_EQ(c.imu.grade, "tactical");
  EXPECT_EQ(c.imu.rate_hz, 200.0);
  EXPECT_EQ(c.gnss.rate_hz, 2.0);
  EXPECT_GT(c.gnss.drift_sigma_horizontal_m, 0.0);
  ASSERT_EQ(c.gnss.jumps.size(), 1u);
  EXPECT_EQ(c.gnss.jumps[0].offset_enu_m, Eigen::Vector3d(14.5, 0, 0));
  EXPECT_EQ(c.gnss.jumps[0].duration_s, 20.0);
  ASSERT_EQ(c.gnss.outages.size(), 1u);
  EXPECT_EQ(c.gnss.outages[0].duration_s, 120.0);
  EXPECT_NEAR(c.origin.lat_deg, 47.60, 1e-12);
  int turns = 0, u_turns = 0, speed_changes = 0;
  for (const Leg& leg : c.trajectory.legs) {
    turns += leg.type == Leg::Type::kTurn;
    u_turns += leg.type == Leg::Type::kTurn && std::abs(leg.angle_deg) == 180.0;
    speed_changes += leg.type == Leg::Type::kSpeedChange;
  }
  EXPECT_GE(turns, 4);
  EXPECT_EQ(u_turns, 1);
  EXPECT_GE(speed_changes, 2);
  ASSERT_FALSE(c.trajectory.legs.empty());
  EXPECT_EQ(c.trajectory.legs[0].type, Leg::Type::kStraight);
  EXPECT_GE(c.trajectory.legs[0].duration_s, 5.0);
  EXPECT_NEAR(c.imu.q_b_i.norm(), 1.0, 1e-15);
}

TEST(Scenario, OtherBuiltinsLoad) {
  const ScenarioConfig sea = LoadScenario("open-sea");
  EXPECT_EQ(sea.duration_s, 3600.0);
  EXPECT_EQ(sea.gnss.rate_hz, 1.0);
  EXPECT_TRUE(sea.gnss.outages.empty());
  EXPECT_TRUE(sea.gnss.dual_antenna_enabled);
  const ScenarioConfig consumer = LoadScenario("harbour-consumer");
  EXPECT_EQ(consumer.imu.grade, "consumer");
  EXPECT_EQ(consumer.imu.errors.noise.gyro_noise_density_rad_s_sqrt_hz,
            ImuGradePreset(ImuGrade::kConsumer).noise.gyro_noise_density_rad_s_sqrt_hz);
  const std::vector<std::string> names = ListBuiltinScenarios();
  for (const char* n :
       {"harbour", "harbour-consumer", "open-sea", "transit", "slow-survey", "at-anchor"}) {
    EXPECT_NE(std::find(names.begin(), names.end(), n), names.end()) << n;
  }
  // Every built-in scenario parses and simulates its first second (a broken key or value in
  // one of them is caught here, not by a user).
  for (const std::string& n : names) {
    SCOPED_TRACE(n);
    ScenarioConfig c = LoadScenario(n);
    EXPECT_EQ(c.earth.kind, EarthKind::kWgs84);
    c.duration_s = 1.0;
    const Dataset d = Simulate(c, 1);
    EXPECT_GT(d.imu_samples.size(), 1u);
  }
}

TEST(Scenario, GradePresetsAreOrderedAndMatchTheDocumentedFigures) {
  const ImuErrorModel consumer = ImuGradePreset(ImuGrade::kConsumer);
  const ImuErrorModel tactical = ImuGradePreset(ImuGrade::kTactical);
  const ImuErrorModel navigation = ImuGradePreset(ImuGrade::kNavigation);
  // Tactical (FOG, KVH 1750 class): ARW 0.012 deg/sqrt(h), VRW 0.05 m/s/sqrt(h), 0.2 mg.
  EXPECT_NEAR(tactical.noise.gyro_noise_density_rad_s_sqrt_hz, 0.012 * kPi / 180.0 / 60.0, 1e-12);
  EXPECT_NEAR(tactical.noise.accel_noise_density_m_s2_sqrt_hz, 0.05 / 60.0, 1e-12);
  EXPECT_NEAR(tactical.accel_bias_initial_sigma_m_s2, 0.2e-3 * 9.80665, 1e-12);
  EXPECT_GT(consumer.noise.gyro_noise_density_rad_s_sqrt_hz,
            tactical.noise.gyro_noise_density_rad_s_sqrt_hz);
  EXPECT_GT(tactical.noise.gyro_noise_density_rad_s_sqrt_hz,
            navigation.noise.gyro_noise_density_rad_s_sqrt_hz);
  EXPECT_GT(consumer.gyro_bias_initial_sigma_rad_s, tactical.gyro_bias_initial_sigma_rad_s);
  EXPECT_GT(tactical.gyro_bias_initial_sigma_rad_s, navigation.gyro_bias_initial_sigma_rad_s);
}

TEST(Scenario, OverridesReplaceThePresetAndDefaultsApply) {
  const ScenarioConfig c = ParseScenario(std::string(kMinimal) + R"(imu:
  grade: navigation
  gyro_noise_density_rad_s_sqrt_hz: 1.0e-3
)",
                                         "x.yaml");
  EXPECT_EQ(c.imu.errors.noise.gyro_noise_density_rad_s_sqrt_hz, 1.0e-3);
  EXPECT_EQ(c.imu.errors.noise.accel_noise_density_m_s2_sqrt_hz,
            ImuGradePreset(ImuGrade::kNavigation).noise.accel_noise_density_m_s2_sqrt_hz);
  EXPECT_EQ(c.imu.rate_hz, 200.0);
  EXPECT_EQ(c.gnss.rate_hz, 1.0);
  EXPECT_EQ(c.source_file, "x.yaml");
  EXPECT_TRUE(c.trajectory.legs.empty());
}

TEST(Scenario, FindsNamesInSkerryScenarioDirFirst) {
  const std::filesystem::path dir = std::filesystem::path(SKERRY_TEST_TMP_DIR) / "scenarios";
  std::filesystem::create_directories(dir);
  {
    std::ofstream out(dir / "harbour.yaml");
    out << kMinimal;  // shadows the built-in harbour
  }
  ASSERT_EQ(setenv("SKERRY_SCENARIO_DIR", dir.c_str(), 1), 0);
  const ScenarioConfig c = LoadScenario("harbour");
  unsetenv("SKERRY_SCENARIO_DIR");
  EXPECT_EQ(c.name, "tiny");
  EXPECT_EQ(LoadScenario("harbour").name, "harbour");
}

TEST(Scenario, UnknownNameAndMissingFileAreInputErrors) {
  try {
    LoadScenario("no-such-scenario");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "scenario");
    EXPECT_NE(std::string(e.what()).find("no-such-scenario"), std::string::npos);
  }
  EXPECT_THROW(LoadScenario("/nonexistent/dir/x.yaml"), InputError);
}

TEST(Scenario, ErrorsNameFileLineAndKeyPath) {
  struct Case {
    std::string text;
    int line;
    std::string field;
  };
  const std::string m = kMinimal;  // 3 lines
  const std::vector<Case> cases = {
      {"name: x\norigin: {lat_deg: 1, lon_deg: 2, height_m: 3}\n", 1, "duration_s"},
      {"name: x\nduration_s: ten\n", 2, "duration_s"},
      {m + "durration_s: 5\n", 4, "durration_s"},
      {m + "gnss:\n  rate_hz: -2\n", 5, "gnss.rate_hz"},
      {m + "gnss:\n  jumps:\n    - {start_s: 1, duration_s: 2, offset_enu_m: [1, 2]}\n", 6,
       "gnss.jumps[0].offset_enu_m"},
      {m + "gnss:\n  outages:\n    - {start_s: 1}\n", 6, "gnss.outages[0].duration_s"},
      {m + "imu:\n  grade: military\n", 5, "imu.grade"},
      {m + "imu:\n  T_b_i: {q_xyzw: [0, 0, 0, 2]}\n", 5, "imu.T_b_i.q_xyzw"},
      {m + "imu:\n  rate_hz: .nan\n", 5, "imu.rate_hz"},
      {m + "trajectory:\n  legs:\n    - {type: straight, duration_s: 5}\n"
           "    - {type: zigzag, angle_deg: 5}\n",
       7, "trajectory.legs[1].type"},
      {m + "trajectory:\n  legs:\n    - {type: turn, angle_deg: 90}\n", 6,
       "trajectory.legs[0].rate_deg_s"},
      {m + "trajectory:\n  legs:\n    - {type: turn, angle_deg: 90, rate_deg_s: 3, speed: 2}\n", 6,
       "trajectory.legs[0].speed"},
      {m + "waves:\n  roll:\n    - {amplitude_deg: 1, period_s: 0}\n", 6, "waves.roll[0].period_s"},
      {m + "seed: -3\n", 4, "seed"},
      {m + "gnss:\n  dual_antenna: {enabled: maybe}\n", 5, "gnss.dual_antenna.enabled"},
      {m + "gnss: [1, 2\n", 4, ""},  // YAML syntax error
      // The round Earth and the errors skerry does not model.
      {m + "earth: {model: disc}\n", 4, "earth.model"},
      {m + "earth:\n  model: wgs84\n  gravity_m_s2: 9.8\n", 6, "earth.gravity_m_s2"},
      {m + "earth: {model: flat, gravity_m_s2: 0}\n", 4, "earth.gravity_m_s2"},
      {m + "imu:\n  gravity_m_s2: 9.81\n", 5, "imu.gravity_m_s2"},
      {m + "imu:\n  scale_factor_ppm: {gyro: -5}\n", 5, "imu.scale_factor_ppm.gyro"},
      {m + "imu:\n  misalignment_mrad: {acel: 1}\n", 5, "imu.misalignment_mrad.acel"},
      {m + "imu:\n  bias_instability: {tau_s: .nan}\n", 5, "imu.bias_instability.tau_s"},
      {m + "imu:\n  bias_instability: {gyro_rad_s: 1.0e-5, tau_s: 0}\n", 5,
       "imu.bias_instability.tau_s"},
      {m + "gnss:\n  slow_drift: {tau_s: 0}\n", 5, "gnss.slow_drift.tau_s"},
      {m + "gnss:\n  multipath: {rate_per_hour: -1}\n", 5, "gnss.multipath.rate_per_hour"},
      {m + "gnss:\n  rate_hz: 2\n  timing: {stamp_jitter_s: 0.1}\n", 6,
       "gnss.timing.stamp_jitter_s"},
      {m + "gnss:\n  timing: {latency_s: -0.1}\n", 5, "gnss.timing.latency_s"},
      // The DEM's own error in the world.
      {m + "dem:\n  file: x.hgt\n  error: {sigma_m: -1}\n", 6, "dem.error.sigma_m"},
      {m + "dem:\n  file: x.hgt\n  error:\n    length_m: 0\n", 7, "dem.error.length_m"},
      {m + "dem:\n  file: x.hgt\n  error: {sigma_m: .nan}\n", 6, "dem.error.sigma_m"},
      {m + "dem:\n  file: x.hgt\n  error: {sigma: 4}\n", 6, "dem.error.sigma"},
      // Times and rates skerry can count: 1e300 s was cast to an integer sample count
      // (undefined behaviour) or a negative time; a rate past a megahertz, or so low that its
      // period is past 1e9 s, likewise.
      {"name: x\nduration_s: 1e300\norigin: {lat_deg: 1, lon_deg: 2, height_m: 3}\n", 2,
       "duration_s"},
      {m + "groundtruth_rate_hz: 1e-300\n", 4, "groundtruth_rate_hz"},
      {m + "imu:\n  rate_hz: 1e300\n", 5, "imu.rate_hz"},
      {m + "gnss:\n  rate_hz: 1.0e-10\n", 5, "gnss.rate_hz"},
      {m + "gnss:\n  drift: {tau_s: 1e300}\n", 5, "gnss.drift.tau_s"},
      {m + "gnss:\n  timing: {latency_s: 2.0e9}\n", 5, "gnss.timing.latency_s"},
      {m + "gnss:\n  outages:\n    - {start_s: -1.0e10, duration_s: 5}\n", 6,
       "gnss.outages[0].start_s"},
      {m + "trajectory:\n  legs:\n    - {type: straight, duration_s: 1e300}\n", 6,
       "trajectory.legs[0].duration_s"},
      {m + "harbour: {}\nlidar:\n  write_rate_hz: 1e300\n", 6, "lidar.write_rate_hz"},
  };
  for (const Case& c : cases) {
    const InputError e = ErrorOf(c.text);
    EXPECT_EQ(e.file(), "test.yaml") << c.text;
    EXPECT_EQ(e.field(), c.field) << c.text << " -> " << e.what();
    if (c.field.empty()) {
      EXPECT_GE(e.line(), 4) << c.text << " -> " << e.what();
    } else {
      EXPECT_EQ(e.line(), c.line) << c.text << " -> " << e.what();
    }
  }
}

// The simulator holds a stream's samples in memory: a scenario that would ask for more than 1e8
// of them is refused at its duration, with the rate that makes them, instead of running out of
// memory (std::bad_alloc, or "vector::reserve", was all a user saw).
TEST(Scenario, SampleCountsAreBounded) {
  const std::string origin = "origin: {lat_deg: 47.6, lon_deg: 9.45, height_m: 440}\n";
  const InputError e = ErrorOf("name: x\nduration_s: 1.0e7\n" + origin);  // 200 Hz IMU
  EXPECT_EQ(e.field(), "duration_s");
  EXPECT_EQ(e.line(), 2);
  EXPECT_NE(std::string(e.what()).find("imu.rate_hz 200"), std::string::npos) << e.what();
  const InputError g = ErrorOf("name: x\nduration_s: 1.0e5\ngroundtruth_rate_hz: 2000\n" + origin);
  EXPECT_NE(std::string(g.what()).find("groundtruth_rate_hz"), std::string::npos) << g.what();
  // A day at 200 Hz (1.7e7 samples) is a scenario like any other.
  EXPECT_EQ(ParseScenario("name: x\nduration_s: 86400\n" + origin, "day.yaml").duration_s, 86400.0);
}

TEST(Scenario, HarbourAndLidarErrorsNameFileLineAndKey) {
  struct Case {
    std::string text;
    int line;
    std::string field;
    std::string says;
  };
  const std::string m = kMinimal;  // 3 lines
  const std::vector<Case> cases = {
      {m + "lidar:\n  enabled: true\n", 5, "lidar", "needs a harbour"},
      {m + "harbour: {enabled: false}\nlidar: {}\n", 5, "lidar", "needs a harbour"},
      {m + "harbour:\n  basin_size: 250\n", 5, "harbour.basin_size", "unknown key"},
      {m + "harbour: {}\nlidar:\n  beamz: 32\n", 6, "lidar.beamz", "unknown key"},
      {m + "harbour: {}\nlidar:\n  write_rate_hz: -1\n", 6, "lidar.write_rate_hz", "> 0"},
      {m + "harbour: {}\nlidar:\n  rotation_rate_hz: 0\n", 6, "lidar.rotation_rate_hz", "> 0"},
      {m + "harbour: {}\nlidar: {write_rate_hz: 20, rotation_rate_hz: 10}\n", 5,
       "lidar.write_rate_hz", "rotation_rate_hz"},
      {m + "harbour: {}\nlidar:\n  dropout_at_max_range: 1.5\n", 6, "lidar.dropout_at_max_range",
       "<= 1"},
      {m + "harbour: {}\nlidar:\n  hull: {size_m: [15, 4.5]}\n", 6, "lidar.hull.size_m",
       "3 numbers"},
      {m + "harbour: {}\nlidar:\n  elevations_deg: [0, 95]\n", 6, "lidar.elevations_deg[1]", "90"},
      {m + "harbour: {}\nlidar:\n  max_range_m: .inf\n", 6, "lidar.max_range_m", "finite"},
      {m + "harbour: {piers: 2.5}\n", 4, "harbour.piers", "whole number"},
      {m + "harbour:\n  aerial_image: {resolution_m: 0}\n", 5, "harbour.aerial_image.resolution_m",
       "> 0"},
      {m + "harbour:\n  aerial_image:\n    sun_elevation_deg: 95\n", 6,
       "harbour.aerial_image.sun_elevation_deg", "<= 90"},
      {m + "harbour:\n  channel_width_m: 5\n", 5, "harbour.channel_width_m", "20 m"},
  };
  for (const Case& c : cases) {
    const InputError e = ErrorOf(c.text);
    EXPECT_EQ(e.file(), "test.yaml") << c.text;
    EXPECT_EQ(e.field(), c.field) << c.text << " -> " << e.what();
    EXPECT_EQ(e.line(), c.line) << c.text << " -> " << e.what();
    EXPECT_NE(std::string(e.what()).find(c.says), std::string::npos) << e.what();
  }
  // And the defaults when the sections are given empty.
  const ScenarioConfig c = ParseScenario(m + "harbour: {}\nlidar: {}\n", "test.yaml");
  EXPECT_TRUE(c.harbour.enabled);
  EXPECT_TRUE(c.harbour.aerial_image.enabled);
  EXPECT_DOUBLE_EQ(c.harbour.aerial_image.resolution_m, 0.16);
  EXPECT_TRUE(c.lidar.enabled);
  EXPECT_EQ(c.lidar.beams, 32);
  EXPECT_DOUBLE_EQ(c.lidar.rotation_rate_hz, 10.0);
  EXPECT_DOUBLE_EQ(c.lidar.write_rate_hz, 1.0);
  EXPECT_DOUBLE_EQ(c.lidar.max_range_m, 100.0);
  EXPECT_DOUBLE_EQ(c.lidar.range_noise_sigma_m, 0.03);
  EXPECT_EQ(c.lidar.T_b_l.p_b_s, Eigen::Vector3d(0, 0, 3));
  EXPECT_FALSE(ParseScenario(m, "test.yaml").lidar.enabled);
}

TEST(Scenario, ErrorsInAFileNameThatFile) {
  const std::filesystem::path path = std::filesystem::path(SKERRY_TEST_TMP_DIR) / "bad.yaml";
  std::filesystem::create_directories(path.parent_path());
  {
    std::ofstream out(path);
    out << kMinimal << "imu:\n  rate_hz: fast\n";
  }
  try {
    LoadScenario(path.string());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path.string());
    EXPECT_EQ(e.line(), 5);
    EXPECT_EQ(e.field(), "imu.rate_hz");
  }
}

}  // namespace
}  // namespace skerry::sim
