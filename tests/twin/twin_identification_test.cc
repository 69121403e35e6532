// Identification against a simulator whose models are known (twin_identification.h): a
// recording simulated with a given IMU and GNSS model, identified against its own true states,
// gives those models back within the uncertainty it states.

#include "skerry/twin/twin_identification.h"

#include <gtest/gtest.h>

#include <cmath>

#include "skerry/core/input_error.h"
#include "skerry/sim/scenario.h"
#include "skerry/sim/simulator.h"

namespace skerry {
namespace {

sim::ScenarioConfig KnownModels(double duration_s) {
  sim::ScenarioConfig c =
      sim::LoadScenario(std::string(SKERRY_SOURCE_DIR) + "/config/scenarios/open-sea.yaml");
  c.duration_s = duration_s;
  sim::ImuErrorModel& e = c.imu.errors;
  e.gyro_scale_factor_ppm = e.accel_scale_factor_ppm = 0.0;
  e.gyro_misalignment_mrad = e.accel_misalignment_mrad = 0.0;
  e.noise.gyro_noise_density_rad_s_sqrt_hz = 2e-4;
  e.noise.accel_noise_density_m_s2_sqrt_hz = 2e-3;
  sim::GnssModel& g = c.gnss;
  g = sim::GnssModel();
  g.rate_hz = 5.0;
  g.noise_sigma_horizontal_m = 0.4;
  g.noise_sigma_vertical_m = 0.8;
  g.drift_sigma_horizontal_m = 1.2;
  g.drift_sigma_vertical_m = 1.2;
  g.drift_tau_s = 60.0;
  return c;
}

void ExpectWithin(const IdentifiedValue& v, double truth, double sigmas, const char* what) {
  EXPECT_TRUE(v.identified) << what;
  EXPECT_GT(v.sigma, 0.0) << what;
  EXPECT_LT(std::abs(v.value - truth), sigmas * v.sigma)
      << what << ": " << v.value << " +- " << v.sigma << ", truth " << truth;
}

TEST(TwinIdentification, RecoversTheSimulatorsModelsAgainstItsTruth) {
  const sim::ScenarioConfig c = KnownModels(1800.0);
  const Dataset real = sim::Simulate(c, 4);
  const sim::SplineMotion truth(real.truth_states);
  const TwinIdentification id = IdentifyTwin(real, truth);
  // IMU: the residuals against the exact truth are the white noise alone.
  ExpectWithin(id.imu.residual_gyro_density, 2e-4, 4.0, "gyro density");
  ExpectWithin(id.imu.residual_accel_density, 2e-3, 4.0, "accel density");
  EXPECT_NEAR(id.imu.residual_gyro_density.value, 2e-4, 0.05 * 2e-4);
  EXPECT_EQ(id.imu.noise_source, "residuals");  // a vessel at sea is never at rest
  EXPECT_FALSE(id.imu.allan.has_value());
  // GNSS: white noise, drift and its correlation time; no latency, no gross errors.
  ASSERT_TRUE(id.gnss.has_value());
  ExpectWithin(id.gnss->white_sigma_horizontal_m, 0.4, 3.5, "white h");
  ExpectWithin(id.gnss->white_sigma_vertical_m, 0.8, 3.5, "white v");
  ExpectWithin(id.gnss->drift_sigma_horizontal_m, 1.2, 3.5, "drift h");
  ExpectWithin(id.gnss->drift_tau_s, 60.0, 3.5, "drift tau");
  EXPECT_EQ(id.gross.episodes, 0);
  EXPECT_EQ(id.model.gnss.gross_rate_per_hour, 0.0);
  // No latency: zero within what the fit says it can tell (a drift that happens to follow the
  // course leans on the regression).
  EXPECT_LT(std::abs(id.gnss->latency_s.value), 3.5 * id.gnss->latency_s.sigma)
      << id.gnss->latency_s.value << " +- " << id.gnss->latency_s.sigma;
  // Timing from the stamps.
  ASSERT_TRUE(id.gnss_timing.has_value());
  EXPECT_NEAR(id.gnss_timing->rate_hz, 5.0, 1e-6);
  EXPECT_EQ(id.gnss_timing->gaps, 0);
  ASSERT_TRUE(id.imu_timing.has_value());
  EXPECT_NEAR(id.imu_timing->rate_hz, c.imu.rate_hz, 1e-6);
  // The model the twin is simulated with.
  EXPECT_DOUBLE_EQ(id.model.imu.gyro_noise_density_rad_s_sqrt_hz, id.imu.gyro_noise_density.value);
  EXPECT_DOUBLE_EQ(id.model.gnss.drift_tau_s, id.gnss->drift_tau_s.value);
}

TEST(TwinIdentification, LatencyAndTheTwinsOwnModelComeBack) {
  // A twin simulated with a latency and gross errors, identified against the same truth.
  sim::ScenarioConfig c = KnownModels(900.0);
  const Dataset base = sim::Simulate(c, 5);
  const sim::SplineMotion truth(base.truth_states);
  sim::TwinModel m;
  m.imu.gyro_noise_density_rad_s_sqrt_hz = 5e-4;
  m.imu.accel_noise_density_m_s2_sqrt_hz = 4e-3;
  m.gnss.white_sigma_horizontal_m = 0.3;
  m.gnss.white_sigma_vertical_m = 0.6;
  m.gnss.latency_s = 0.2;
  m.gnss.gross_rate_per_hour = 60.0;  // ~15 episodes in 900 s, 4 s each, 25 m off
  m.gnss.gross_mean_duration_s = 4.0;
  m.gnss.gross_offset_horizontal_m = 25.0;
  const Dataset twin = sim::SimulateTwin(base, truth, m, 9);
  const TwinIdentification id = IdentifyTwin(twin, truth);
  ExpectWithin(id.imu.residual_gyro_density, 5e-4, 4.0, "gyro density");
  ExpectWithin(id.gnss->latency_s, 0.2, 3.5, "latency");
  ExpectWithin(id.gnss->white_sigma_horizontal_m, 0.3, 3.5, "white h");
  ExpectWithin(id.gross.rate_per_hour, 60.0, 3.5, "gross rate");
  ExpectWithin(id.gross.mean_duration_s, 4.0, 3.5, "gross duration");
  ExpectWithin(id.gross.offset_horizontal_m, 25.0, 3.5, "gross offset");
  EXPECT_NEAR(id.model.gnss.latency_s, 0.2, 0.05);
}

TEST(TwinIdentification, ATruthThatMissesTheRecordingIsAnError) {
  const Dataset real = sim::Simulate(KnownModels(30.0), 1);
  std::vector<NavState> later = real.truth_states;
  for (NavState& s : later) s.t_ns += SecondsToNs(1000.0);
  EXPECT_THROW(IdentifyTwin(real, sim::SplineMotion(later)), InputError);
  // Covering 2 s: too few fixes for a GNSS model, and the message says how many.
  std::vector<NavState> short_truth(real.truth_states.begin(), real.truth_states.begin() + 100);
  try {
    IdentifyTwin(real, sim::SplineMotion(short_truth));
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("needs at least 30"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace skerry
