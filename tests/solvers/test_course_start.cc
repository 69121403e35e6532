// The heading at the first fix from the course over ground with the gyro's turns taken out,
// against exact arcs: the chord is half the turn off, the straightened course is not.

#include <gtest/gtest.h>

#include <cmath>

#include "skerry/solvers/course_start.h"

namespace skerry {
namespace {

constexpr double kDeg = M_PI / 180.0;

// A vehicle at `speed` starting on heading h0 (clockwise from north) turning counter-clockwise
// at `rate`: fixes at 2 Hz for `duration_s`, yaw rates at 100 Hz.
void Arc(double h0,
         double rate,
         double speed,
         double duration_s,
         std::vector<CourseFix>* fixes,
         std::vector<YawRate>* rates) {
  Eigen::Vector2d p = Eigen::Vector2d::Zero();
  const double dt = 0.001;
  const int steps = static_cast<int>(std::lround(duration_s / dt));
  for (int k = 0; k <= steps; ++k) {
    const double t = k * dt;
    if (k % 500 == 0) fixes->push_back({SecondsToNs(t), p});
    if (k % 10 == 0) rates->push_back({SecondsToNs(t), rate});
    const double h = h0 - rate * (t + 0.5 * dt);  // midpoint heading over the step
    p += speed * dt * Eigen::Vector2d(std::sin(h), std::cos(h));
  }
}

TEST(CourseStart, StraightStretchIsTheChord) {
  std::vector<CourseFix> fixes;
  std::vector<YawRate> rates;
  Arc(-35.0 * kDeg, 0.0, 1.0, 15.0, &fixes, &rates);
  const CourseStart c = CourseAtFirstFix(fixes, rates, 0.3, 0.0);
  EXPECT_NEAR(c.heading_rad, -35.0 * kDeg, 1e-9);
  EXPECT_NEAR(c.speed_m_s, 1.0, 1e-9);
  EXPECT_NEAR(c.turned_rad, 0.0, 1e-12);
  EXPECT_NEAR(c.sigma_rad, std::sqrt(2.0) * 0.3 / 15.0, 1e-9);  // no gyro bias prior
}

// 40 deg turned over 15 m: the chord points 20 deg along the turn, the straightened course at the
// start (to the arc's discretisation: fixes 0.5 s apart); the speed is the arc length's.
TEST(CourseStart, TurnAlongTheStretchIsTakenOut) {
  for (double rate_deg : {40.0 / 15.0, -40.0 / 15.0, 10.0}) {
    SCOPED_TRACE(rate_deg);
    std::vector<CourseFix> fixes;
    std::vector<YawRate> rates;
    Arc(170.0 * kDeg, rate_deg * kDeg, 1.0, 15.0, &fixes, &rates);
    const Eigen::Vector2d chord = fixes.back().en_m - fixes.front().en_m;
    const double chord_heading = std::atan2(chord.x(), chord.y());
    const double turned = rate_deg * 15.0 * kDeg;
    EXPECT_NEAR(std::remainder(chord_heading - 170.0 * kDeg, 2 * M_PI), -0.5 * turned, 0.01);
    const CourseStart c = CourseAtFirstFix(fixes, rates, 0.3, 1e-3);
    EXPECT_NEAR(std::remainder(c.heading_rad - 170.0 * kDeg, 2 * M_PI), 0.0, 1e-3);
    EXPECT_NEAR(c.turned_rad, turned, 1e-9);
    EXPECT_NEAR(c.speed_m_s, 1.0, 2e-3);
    // Sigma: end-fix noise across ~15 m and the bias prior over half the stretch.
    EXPECT_NEAR(c.sigma_rad, std::hypot(std::sqrt(2.0) * 0.3 / (15.0 * c.speed_m_s), 7.5e-3), 1e-4);
  }
}

// A gyro bias b turns each displacement k by b t_k: the heading is off by about b T/2, which the
// sigma admits.
TEST(CourseStart, GyroBiasShiftsTheHeadingByWhatTheSigmaSays) {
  std::vector<CourseFix> fixes;
  std::vector<YawRate> rates;
  Arc(10.0 * kDeg, 2.0 * kDeg, 1.0, 20.0, &fixes, &rates);
  const double bias = 0.005;
  for (YawRate& r : rates) r.rad_s += bias;
  const CourseStart c = CourseAtFirstFix(fixes, rates, 0.0, bias);
  const double err = std::remainder(c.heading_rad - 10.0 * kDeg, 2 * M_PI);
  EXPECT_NEAR(err, bias * 10.0, 0.1 * bias * 10.0);
  EXPECT_NEAR(c.sigma_rad, bias * 10.0, 1e-12);
}

TEST(CourseStart, NeedsTwoFixes) {
  EXPECT_THROW(CourseAtFirstFix({{0, Eigen::Vector2d::Zero()}}, {}, 0.3, 0.0),
               std::invalid_argument);
}

}  // namespace
}  // namespace skerry
