// twin.yaml (twin_yaml.h): the model section written and read back exactly, and a hand-edited
// file with a missing, unknown, negative or non-numeric key refused with its file, line and key.

#include "skerry/twin/twin_yaml.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "skerry/core/input_error.h"

namespace skerry {
namespace {

std::string TmpDir() {
  const std::string d = std::string(SKERRY_TEST_TMP_DIR) + "/twin_yaml";
  std::filesystem::create_directories(d);
  return d;
}

std::string Read(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void Write(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

TEST(TwinYaml, TheModelComesBackAsWritten) {
  Dataset real;
  real.has_imu = true;
  TwinIdentification id;
  id.model.imu.gyro_noise_density_rad_s_sqrt_hz = 1.25e-4;
  id.model.imu.accel_noise_density_m_s2_sqrt_hz = 2.5e-3;
  id.model.gnss.white_sigma_horizontal_m = 0.375;
  id.model.gnss.drift_tau_s = 96.5;
  id.model.gnss.latency_s = 0.125;
  id.model.gnss.gross_rate_per_hour = 3.5;
  id.model.gnss.solve_period_s = 1.0;
  id.model.gnss.solve_phase_s = 0.28125;
  id.model.gnss.solve_offset_sigma_m = 0.03125;
  id.model.gnss.propagation_velocity_sigma_m_s = 0.3;
  id.model.gnss.propagation_velocity_tau_s = 4.75;
  id.imu.noise_source = "residuals";
  id.imu.gyro_noise_density = {1.25e-4, 3e-6, true};
  const std::string path = TmpDir() + "/twin.yaml";
  WriteTwinYaml(path, real, id, TwinProvenance(), nullptr);
  const sim::TwinModel m = ReadTwinModel(path);
  EXPECT_EQ(m.imu.gyro_noise_density_rad_s_sqrt_hz, 1.25e-4);
  EXPECT_EQ(m.imu.accel_noise_density_m_s2_sqrt_hz, 2.5e-3);
  EXPECT_EQ(m.gnss.white_sigma_horizontal_m, 0.375);
  EXPECT_EQ(m.gnss.drift_tau_s, 96.5);
  EXPECT_EQ(m.gnss.latency_s, 0.125);
  EXPECT_EQ(m.gnss.gross_rate_per_hour, 3.5);
  EXPECT_EQ(m.gnss.solve_period_s, 1.0);
  EXPECT_EQ(m.gnss.solve_phase_s, 0.28125);
  EXPECT_EQ(m.gnss.solve_offset_sigma_m, 0.03125);
  EXPECT_EQ(m.gnss.propagation_velocity_sigma_m_s, 0.3);
  EXPECT_EQ(m.gnss.propagation_velocity_tau_s, 4.75);
  const std::string text = Read(path);
  EXPECT_NE(text.find("gyro_noise_density_rad_s_sqrt_hz: {value: 0.000125, sigma: 3e-06, "
                      "identified: true}"),
            std::string::npos)
      << text;
}

TEST(TwinYaml, AnEditedModelWithABadKeyIsRefusedWithItsLine) {
  Dataset real;
  TwinIdentification id;
  const std::string path = TmpDir() + "/edited.yaml";
  WriteTwinYaml(path, real, id, TwinProvenance(), nullptr);
  const std::string good = Read(path);
  auto expect_error = [&](const std::string& from, const std::string& to, const std::string& key) {
    std::string text = good;
    const size_t at = text.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
    Write(path, text);
    try {
      ReadTwinModel(path);
      FAIL() << "accepted: " << to;
    } catch (const InputError& e) {
      EXPECT_EQ(e.file(), path);
      EXPECT_EQ(e.field(), key) << e.what();
      EXPECT_GT(e.line(), 0) << e.what();
    }
  };
  expect_error("    latency_s: 0", "    latency_s: -0.5", "model.gnss.latency_s");
  expect_error("    latency_s: 0", "    latency_s: soon", "model.gnss.latency_s");
  expect_error("    latency_s: 0", "    latency_s: 0\n    lateness_s: 1", "model.gnss.lateness_s");
  expect_error("    latency_s: 0\n", "", "model.gnss.latency_s");
  expect_error("    latency_s: 0", "    latency_s: 0\n    ? [a]\n    : 1", "model.gnss");
  expect_error("    solve_period_s: 0", "    solve_period_s: -1", "model.gnss.solve_period_s");
  expect_error("    propagation_velocity_tau_s: 5", "    propagation_velocity_tau_s: 0",
               "model.gnss.propagation_velocity_tau_s");
  Write(path, "twin: {}\n");
  EXPECT_THROW(ReadTwinModel(path), InputError);
  Write(path, "just a scalar\n");  // found by fuzzing: yaml-cpp threw on operator[]
  EXPECT_THROW(ReadTwinModel(path), InputError);
  Write(path, "- a\n- b\n");
  EXPECT_THROW(ReadTwinModel(path), InputError);
  EXPECT_THROW(ReadTwinModel(TmpDir() + "/absent.yaml"), InputError);
}

// A model: section as twin.yaml files were written before the solve-and-propagate keys: it
// still reads, with those keys off; the keys it always had stay required.
TEST(TwinYaml, AFileWrittenBeforeTheSolveKeysReadsWithThemOff) {
  const std::string old_model =
      "model:\n"
      "  imu:\n"
      "    gyro_noise_density_rad_s_sqrt_hz: 0.000125\n"
      "    accel_noise_density_m_s2_sqrt_hz: 0.0025\n"
      "    gyro_bias_random_walk_rad_s2_sqrt_hz: 0\n"
      "    accel_bias_random_walk_m_s3_sqrt_hz: 0\n"
      "  gnss:\n"
      "    white_sigma_horizontal_m: 0.375\n"
      "    white_sigma_vertical_m: 0.5\n"
      "    drift_sigma_horizontal_m: 0\n"
      "    drift_sigma_vertical_m: 0\n"
      "    drift_tau_s: 300\n"
      "    gross_rate_per_hour: 0\n"
      "    gross_mean_duration_s: 0\n"
      "    gross_offset_horizontal_m: 0\n"
      "    gross_offset_vertical_m: 0\n"
      "    latency_s: 0.125\n"
      "    heading_sigma_deg: 0\n";
  const std::string path = TmpDir() + "/old.yaml";
  Write(path, old_model);
  const sim::TwinModel m = ReadTwinModel(path);
  const sim::TwinModel off;
  EXPECT_EQ(m.gnss.white_sigma_horizontal_m, 0.375);
  EXPECT_EQ(m.gnss.latency_s, 0.125);
  EXPECT_EQ(m.gnss.solve_period_s, 0.0);
  EXPECT_EQ(m.gnss.solve_phase_s, off.gnss.solve_phase_s);
  EXPECT_EQ(m.gnss.solve_offset_sigma_m, off.gnss.solve_offset_sigma_m);
  EXPECT_EQ(m.gnss.propagation_velocity_sigma_m_s, off.gnss.propagation_velocity_sigma_m_s);
  EXPECT_EQ(m.gnss.propagation_velocity_tau_s, off.gnss.propagation_velocity_tau_s);
  std::string missing = old_model;
  missing.erase(missing.find("    latency_s: 0.125\n"),
                std::string("    latency_s: 0.125\n").size());
  Write(path, missing);
  EXPECT_THROW(ReadTwinModel(path), InputError);
}

}  // namespace
}  // namespace skerry
