// The solve-and-propagate pattern (solve_pattern.h): perturb, identify, recover. Residuals made
// the way sim/twin.h makes them (white noise, a fresh offset at each solution, a Gauss-Markov
// propagation velocity error integrated from it) at jittered ~7 Hz stamps on a UTC-like clock
// give back the period, the phase and each value within its stated sigma; a white noise with a
// slow drift, the same pattern logged once a second, and too few fixes are not taken for one.

#include "skerry/twin/solve_pattern.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

namespace skerry {
namespace {

struct Series {
  std::vector<TimeNs> t;
  std::vector<Eigen::Vector2d> e;
};

struct Truth {
  double rate_hz = 7.0;
  double period_s = 1.0, phase_s = 0.28;
  double white_m = 0.05, offset_m = 0.03, velocity_m_s = 0.35, tau_s = 5.0;
  double drift_m = 0.0, drift_tau_s = 30.0;  ///< a slow first-order drift besides
};

Series Make(const Truth& m, double duration_s, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal;
  auto n2 = [&] { return Eigen::Vector2d(normal(rng), normal(rng)); };
  const TimeNs start = SecondsToNs(1.7e9 + 0.613);  // a UTC stamp, not a whole second
  const TimeNs period = SecondsToNs(m.period_s), phase = SecondsToNs(m.phase_s);
  Series s;
  long solution = -1;
  Eigen::Vector2d v = m.velocity_m_s * n2(), offset = Eigen::Vector2d::Zero();
  Eigen::Vector2d drift = m.drift_m * n2();
  const double phi_v = std::exp(-m.period_s / m.tau_s);
  const double step_s = 1.0 / m.rate_hz;
  for (double t_s = 0.0; t_s < duration_s; t_s += step_s) {
    // Stamps jittered by 15 ms, as the Furuno's are.
    const TimeNs t = start + SecondsToNs(t_s + 0.015 * normal(rng));
    const long k = static_cast<long>((t - phase) / period);
    if (k != solution) {
      if (solution >= 0) v = phi_v * v + m.velocity_m_s * std::sqrt(1.0 - phi_v * phi_v) * n2();
      offset = m.offset_m * n2();
      solution = k;
    }
    const double phi_d = std::exp(-step_s / m.drift_tau_s);
    drift = phi_d * drift + m.drift_m * std::sqrt(1.0 - phi_d * phi_d) * n2();
    const double since = NsToSeconds(t - phase - k * period);
    s.t.push_back(t);
    s.e.push_back(m.white_m * n2() + offset + v * since + drift);
  }
  return s;
}

void ExpectWithin(const IdentifiedValue& v, double truth, const char* name) {
  EXPECT_TRUE(v.identified) << name;
  EXPECT_GT(v.sigma, 0.0) << name;
  EXPECT_LT(v.sigma, 0.25 * truth) << name;  // informative
  EXPECT_NEAR(v.value, truth, 3.0 * v.sigma) << name;
}

TEST(SolvePattern, ASawtoothIsFoundAndItsValuesRecovered) {
  const Truth m;
  const Series s = Make(m, 1800.0, 1);
  const SolvePattern p = IdentifySolvePattern(s.t, s.e);
  ASSERT_TRUE(p.detected) << p.jump_ratio << " " << p.jump_z;
  EXPECT_EQ(p.period_s, 1.0);
  // Any phase between the last fix before a solution and the first after it splits them alike:
  // within a fix interval (1/7 s) of the truth, on the circle.
  EXPECT_LT(std::abs(std::remainder(p.phase_s - m.phase_s, 1.0)), 1.0 / 7.0);
  EXPECT_GT(p.period_correlation, p.half_period_correlation);
  ExpectWithin(p.white_sigma_horizontal_m, m.white_m, "white");
  ExpectWithin(p.offset_sigma_m, m.offset_m, "offset");
  ExpectWithin(p.propagation_velocity_sigma_m_s, m.velocity_m_s, "velocity");
  ExpectWithin(p.propagation_velocity_tau_s, m.tau_s, "tau");
}

TEST(SolvePattern, AGrossFixIsLeftOut) {
  const Truth m;
  Series s = Make(m, 900.0, 2);
  std::vector<bool> gross(s.t.size(), false);
  for (size_t i = 100; i < s.t.size(); i += 500) {
    s.e[i] += Eigen::Vector2d(40.0, -25.0);
    gross[i] = true;
  }
  const SolvePattern p = IdentifySolvePattern(s.t, s.e, gross);
  ASSERT_TRUE(p.detected);
  ExpectWithin(p.propagation_velocity_sigma_m_s, m.velocity_m_s, "velocity");
  EXPECT_THROW(IdentifySolvePattern(s.t, s.e, std::vector<bool>(3, false)), std::invalid_argument);
}

TEST(SolvePattern, NoSawtoothNoDetection) {
  // White noise and a slow drift: first differences alike at every phase.
  Truth drift;
  drift.velocity_m_s = drift.offset_m = 0.0;
  drift.drift_m = 0.5;
  const SolvePattern none =
      IdentifySolvePattern(Make(drift, 1800.0, 3).t, Make(drift, 1800.0, 3).e);
  EXPECT_FALSE(none.detected) << none.jump_ratio << " " << none.jump_z;
  EXPECT_FALSE(none.offset_sigma_m.identified);
  // The sawtooth logged once a second: one fix per solution, nothing to see within one.
  Truth slow;
  slow.rate_hz = 1.0;
  const Series s = Make(slow, 1800.0, 4);
  EXPECT_FALSE(IdentifySolvePattern(s.t, s.e).detected);
  // Too few fixes.
  const Series shortened = Make(Truth(), 3.0, 5);
  EXPECT_FALSE(IdentifySolvePattern(shortened.t, shortened.e).detected);
}

TEST(SolvePattern, CorrelationAtALagPairsFixesByTime) {
  // A sine of period 2 s sampled at 10 Hz: +1 correlation 2 s apart, -1 one second apart.
  std::vector<TimeNs> t;
  std::vector<Eigen::Vector2d> e;
  for (int i = 0; i < 2000; ++i) {
    t.push_back(SecondsToNs(0.1 * i));
    e.emplace_back(std::sin(M_PI * 0.1 * i), 0.0);
  }
  EXPECT_NEAR(ResidualCorrelationAtLag(t, e, 2.0), 1.0, 0.02);
  EXPECT_NEAR(ResidualCorrelationAtLag(t, e, 1.0), -1.0, 0.02);
  EXPECT_EQ(ResidualCorrelationAtLag(t, e, 1000.0), 0.0);
}

}  // namespace
}  // namespace skerry
