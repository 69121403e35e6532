// The twin's calibration search (twin_calibration.h) on objectives whose minimum is known: it
// finds a noise level the identification got wrong by 2x, switches on a drift the
// identification did not see, leaves a parameter that does not matter alone, and refuses a
// search it cannot run.

#include "skerry/twin/twin_calibration.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

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

}  // namespace
}  // namespace skerry
