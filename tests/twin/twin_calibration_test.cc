// The twin's calibration search (twin_calibration.h) on objectives whose minimum is known: it
// finds a noise level the identification got wrong by 2x, switches on a drift the
// identification did not see, leaves a parameter that does not matter alone, and refuses a
// search it cannot run.

#include "skerry/twin/twin_calibration.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "skerry/twin/gnss_statistics.h"

namespace skerry {
namespace {

Dataset GnssOnly() {
  Dataset d;
  d.has_imu = false;
  d.has_gnss = true;
  return d;
}

TEST(TwinCalibration, FindsTheMinimumOfASmoothObjective) {
  const std::vector<TwinParameter> params = CalibratableParameters(GnssOnly(), 0.5);
  sim::TwinModel start;
  start.gnss.white_sigma_horizontal_m = 0.8;  // the truth is 0.4
  start.gnss.white_sigma_vertical_m = 1.0;    // does not matter
  start.gnss.drift_tau_s = 300.0;
  // log-quadratic in the white sigma, a drift wanted at 0.5 m; vertical irrelevant.
  auto objective = [](const sim::TwinModel& m) {
    const double a = std::log(m.gnss.white_sigma_horizontal_m / 0.4);
    const double d = m.gnss.drift_sigma_horizontal_m - 0.5;
    return 0.3 + a * a + d * d;
  };
  const TwinCalibration c = CalibrateTwin(start, params, objective);
  EXPECT_NEAR(c.model.gnss.white_sigma_horizontal_m, 0.4, 0.4 * 0.1);
  EXPECT_NEAR(c.model.gnss.drift_sigma_horizontal_m, 0.5, 0.1);
  EXPECT_EQ(c.model.gnss.white_sigma_vertical_m, 1.0);
  EXPECT_LT(c.objective_after, 0.32);
  EXPECT_NEAR(c.objective_before, 0.3 + std::log(2.0) * std::log(2.0) + 0.25, 1e-12);
  EXPECT_EQ(c.evaluations, static_cast<int>(c.steps.size()) + 1);
  int kept = 0;
  for (const TwinCalibrationStep& s : c.steps) kept += s.kept ? 1 : 0;
  EXPECT_GE(kept, 2);
}

// An IMU density the residuals overstate twentyfold (their truth misses a drone's fastest
// motion): a few halvings cannot get back to the sheet, trying the sheet's value can.
TEST(TwinCalibration, ReachesASheetValueFarBelowTheIdentifiedOne) {
  Dataset d;
  d.has_imu = true;
  d.has_gnss = true;
  d.imu.noise.gyro_noise_density_rad_s_sqrt_hz = 1.7e-4;
  d.imu.noise.accel_noise_density_m_s2_sqrt_hz = 2e-3;
  sim::TwinModel start;
  start.gnss.white_sigma_horizontal_m = start.gnss.white_sigma_vertical_m = 0.5;
  start.gnss.drift_tau_s = 300.0;
  start.imu.gyro_noise_density_rad_s_sqrt_hz = 3.4e-3;
  start.imu.accel_noise_density_m_s2_sqrt_hz = 2e-3;
  auto objective = [](const sim::TwinModel& m) {
    const double a = std::log(m.imu.gyro_noise_density_rad_s_sqrt_hz / 1.9e-4);
    return 0.1 + a * a;
  };
  const TwinCalibration c = CalibrateTwin(start, CalibratableParameters(d, 0.5), objective);
  EXPECT_NEAR(c.model.imu.gyro_noise_density_rad_s_sqrt_hz, 1.9e-4, 0.15 * 1.9e-4);
  EXPECT_EQ(c.model.imu.accel_noise_density_m_s2_sqrt_hz, 2e-3);
  EXPECT_LT(c.objective_after, 0.12);
}

TEST(TwinCalibration, KeepsTheStartWhenNothingIsBetter) {
  sim::TwinModel start;
  start.gnss.white_sigma_horizontal_m = 0.4;
  start.gnss.white_sigma_vertical_m = 0.4;
  const TwinCalibration c = CalibrateTwin(start, CalibratableParameters(GnssOnly(), 0.4),
                                          [](const sim::TwinModel&) { return 1.0; });
  EXPECT_EQ(c.model.gnss.white_sigma_horizontal_m, 0.4);
  EXPECT_EQ(c.model.gnss.drift_sigma_horizontal_m, 0.0);
  EXPECT_EQ(c.objective_after, c.objective_before);
}

TEST(TwinCalibration, ParametersFollowTheRecordingsSensors) {
  Dataset d = GnssOnly();
  EXPECT_EQ(CalibratableParameters(d, 0.5).size(), 7u);
  d.has_imu = true;
  EXPECT_EQ(CalibratableParameters(d, 0.5).size(), 11u);
  GnssFix f;
  f.has_heading = true;
  d.gnss_fixes.push_back(f);
  EXPECT_EQ(CalibratableParameters(d, 0.5).back().name, "gnss.heading_sigma_deg");
}

TEST(TwinCalibration, RefusesASearchItCannotRun) {
  auto objective = [](const sim::TwinModel&) { return 0.0; };
  EXPECT_THROW(CalibrateTwin({}, {}, objective), std::invalid_argument);
  TwinCalibrationOptions bad;
  bad.rounds = 0;
  EXPECT_THROW(CalibrateTwin({}, CalibratableParameters(GnssOnly(), 1), objective, bad),
               std::invalid_argument);
  bad = TwinCalibrationOptions();
  bad.factors = {0.5, -1.0};
  EXPECT_THROW(CalibrateTwin({}, CalibratableParameters(GnssOnly(), 1), objective, bad),
               std::invalid_argument);
}

// A short clean log: none of a few twins has a gross fix, the recording has one. The share's
// scale is its binomial sampling sd, so the distance stays finite and calibratable; the other
// statistics keep their twins' sd.
TEST(GnssStatistics, GrossShareScaleHasABinomialFloor) {
  const size_t n = 400;
  GnssStatistics real;
  real.white_sigma_horizontal_m = 0.1;
  real.gross_share = 1.0 / n;
  std::vector<GnssStatistics> twins(8);
  for (size_t k = 0; k < twins.size(); ++k) {
    twins[k].white_sigma_horizontal_m = 0.09 + 0.005 * static_cast<double>(k % 3);
  }
  const std::vector<StatisticComparison> c = CompareGnssStatistics(real, twins);
  const std::vector<double> scales = StatisticsScales(c, n);
  ASSERT_EQ(scales.size(), c.size());
  for (size_t i = 0; i < c.size(); ++i) {
    if (c[i].name == "share of gross fixes") {
      EXPECT_EQ(c[i].twins_sd, 0.0);
      const double p = 1.0 / n;
      EXPECT_NEAR(scales[i], std::sqrt(p * (1.0 - p) / n), 1e-15);
    } else {
      EXPECT_EQ(scales[i], c[i].twins_sd) << c[i].name;
    }
  }
  // One gross fix more than the twins is one binomial sd: a term of about 1, not 1e6.
  const double d = StatisticsDistance(c, scales);
  EXPECT_LT(d, 1e3);
  EXPECT_THROW(StatisticsScales(c, 0), std::invalid_argument);
}

// With a solve period identified, its offset, propagation velocity error and correlation time
// are calibrated too (and not otherwise): a known minimum in the velocity error is found from 0.
TEST(TwinCalibration, CalibratesTheSolvePatternWhenIdentified) {
  Dataset d;
  d.has_gnss = true;
  auto names = [](const std::vector<TwinParameter>& ps) {
    std::vector<std::string> n;
    for (const TwinParameter& p : ps) n.push_back(p.name);
    return n;
  };
  const std::vector<std::string> off = names(CalibratableParameters(d, 0.5));
  EXPECT_EQ(std::count(off.begin(), off.end(), "gnss.propagation_velocity_sigma_m_s"), 0);
  const std::vector<TwinParameter> on = CalibratableParameters(d, 0.15, true);
  const std::vector<std::string> on_names = names(on);
  for (const char* n : {"gnss.solve_offset_sigma_m", "gnss.propagation_velocity_sigma_m_s",
                        "gnss.propagation_velocity_tau_s"}) {
    EXPECT_EQ(std::count(on_names.begin(), on_names.end(), n), 1) << n;
  }
  sim::TwinModel start;
  start.gnss.white_sigma_horizontal_m = 0.15;
  start.gnss.solve_period_s = 1.0;
  auto objective = [](const sim::TwinModel& m) {
    const double a = std::log((m.gnss.propagation_velocity_sigma_m_s + 1e-3) / 0.35);
    return 0.1 + a * a;
  };
  const TwinCalibration c = CalibrateTwin(start, on, objective, {3});
  EXPECT_NEAR(c.model.gnss.propagation_velocity_sigma_m_s, 0.35, 0.05);
  EXPECT_EQ(c.model.gnss.solve_period_s, 1.0);
}

}  // namespace
}  // namespace skerry
