// IMU noise identification by Allan deviation (allan_deviation.h) against numbers: synthetic
// noise of known white density, rate random walk and Gauss-Markov bias against the analytic Allan
// variance of each (IEEE Std 952-1997 Annex C), the exact cluster averaging of a sine, rest found
// in a synthetic recording, and the EuRoC V1_01 ADIS16448 at rest before take-off against its
// datasheet densities (skipped when ../shared/data/euroc_v1_01 is missing).

#include "skerry/eval/allan_deviation.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <sstream>
#include <string>

#include "skerry/io/importers.h"

namespace skerry {
namespace {

constexpr double kPi = 3.14159265358979323846;

/// White rate noise of density `n_density` (units/sqrt(Hz)) at `rate_hz`: per-sample sigma
/// n_density sqrt(rate_hz), so that sigma^2(tau0) = N^2 / tau0.
std::vector<double> WhiteNoise(size_t count, double rate_hz, double n_density, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01;
  std::vector<double> x(count);
  for (double& v : x) v = n_density * std::sqrt(rate_hz) * n01(rng);
  return x;
}

/// Adds a rate random walk of density `k_density` (units/s/sqrt(Hz)): increments of variance
/// K^2 tau0, so that sigma^2(tau) = K^2 tau / 3 (IEEE 952 C.1.4).
void AddRandomWalk(double rate_hz, double k_density, uint64_t seed, std::vector<double>* x) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01;
  double b = 0.0;
  for (double& v : *x) {
    v += b;
    b += k_density * std::sqrt(1.0 / rate_hz) * n01(rng);
  }
}

/// Adds a stationary first-order Gauss-Markov bias of standard deviation `s` and correlation time
/// `t_corr_s` (autocovariance s^2 exp(-|u| / T)), exactly discretised.
void AddGaussMarkov(
    double rate_hz, double s, double t_corr_s, uint64_t seed, std::vector<double>* x) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01;
  const double phi = std::exp(-1.0 / (rate_hz * t_corr_s));
  double b = s * n01(rng);
  for (double& v : *x) {
    v += b;
    b = phi * b + s * std::sqrt(1.0 - phi * phi) * n01(rng);
  }
}

/// The Allan variance of a stationary process from its autocovariance R(u) = s^2 exp(-u / T):
/// the variance of a tau-average is V(tau) = (2 / tau^2) int_0^tau (tau - u) R(u) du
/// = (2 s^2 / tau^2) (T tau - T^2 (1 - exp(-tau / T))); two adjacent averages have
/// Var(ybar1 + ybar2) = 4 V(2 tau), so Cov = 2 V(2 tau) - V(tau) and
/// sigma^2(tau) = (Var - Cov) = 2 V(tau) - 2 V(2 tau)
/// (= (2 s^2 T / tau) (1 - T / (2 tau) (3 - 4 exp(-tau/T) + exp(-2 tau/T))), El-Sheimy 2008).
double GaussMarkovAvar(double tau, double s, double t_corr) {
  const auto v = [&](double t) {
    return 2.0 * s * s / (t * t) * (t_corr * t - t_corr * t_corr * -std::expm1(-t / t_corr));
  };
  return 2.0 * v(tau) - 2.0 * v(2.0 * tau);
}

double Z(const AllanPoint& p, double expected) { return (p.adev - expected) / p.adev_sigma; }

TEST(OverlappingAllanDeviation, GridIsLogarithmicFromOneSampleToANinthOfTheData) {
  const std::vector<double> x = WhiteNoise(10000, 100.0, 0.01, 1);
  const std::vector<AllanPoint> c = OverlappingAllanDeviation(x, 100.0, 10);
  ASSERT_FALSE(c.empty());
  EXPECT_DOUBLE_EQ(c.front().tau_s, 0.01);
  EXPECT_LE(c.back().tau_s, 10000 / 9 / 100.0 + 1e-12);
  EXPECT_GT(c.back().tau_s, 10000 / 9 / 100.0 / std::pow(10.0, 0.1) - 1e-12);
  for (size_t i = 1; i < c.size(); ++i) {
    EXPECT_GT(c[i].tau_s, c[i - 1].tau_s);  // no duplicate m
    EXPECT_LE(c[i].tau_s / c[i - 1].tau_s, 2.0 + 1e-12);
  }
  // m = 1..10 at 10 per decade: 1, 2, 3, 4, 5, 6, 8, 10 (1, 1, 2, 2, 3, 3, ... once each).
  EXPECT_NEAR(c[7].tau_s, 0.10, 1e-12);
  EXPECT_EQ(c[0].clusters, 10000);
  EXPECT_EQ(c[7].clusters, 1000);
  EXPECT_DOUBLE_EQ(c[7].adev_sigma, c[7].adev / std::sqrt(2.0 * (1000.0 - 1.0)));
}

// +1, -1, +1, ...: single samples differ by 2 (sigma^2 = 4/2), pairs average to 0.
TEST(OverlappingAllanDeviation, AlternatingSignByHand) {
  std::vector<double> x(20);
  for (size_t i = 0; i < x.size(); ++i) x[i] = 5.0 + (i % 2 ? -1.0 : 1.0);
  const std::vector<AllanPoint> c = OverlappingAllanDeviation(x, 1.0);
  ASSERT_EQ(c.size(), 2u);  // m = 1, 2 (20 / 9 = 2)
  EXPECT_NEAR(c[0].adev, std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(c[1].adev, 0.0, 1e-12);
}

// x = c + A sin(2 pi t / P) sampled at tau0: a cluster of m samples averages the sine to
// A D sin(2 pi t / P + phase) with D = sin(pi m tau0 / P) / (m sin(pi tau0 / P)), and two adjacent
// clusters differ by 2 A D sin(pi tau / P) times a sine, so sigma^2 = A^2 D^2 sin^2(pi tau / P)
// (the continuous limit is IEEE 952's A^2 sin^4(pi tau/P) / (pi tau/P)^2): 0 at tau = P, 2P.
TEST(OverlappingAllanDeviation, SineClosedForm) {
  const double rate = 100.0, period = 0.5, amplitude = 0.3;
  std::vector<double> x(20000);
  for (size_t i = 0; i < x.size(); ++i) {
    x[i] = 7.0 + amplitude * std::sin(2.0 * kPi * (i / rate) / period + 0.4);
  }
  const std::vector<AllanPoint> c = OverlappingAllanDeviation(x, rate);
  int at_period = 0;
  for (const AllanPoint& p : c) {
    const double m = std::round(p.tau_s * rate);
    const double d = std::sin(kPi * m / (rate * period)) / (m * std::sin(kPi / (rate * period)));
    const double expected = amplitude * std::abs(d * std::sin(kPi * p.tau_s / period));
    EXPECT_NEAR(p.adev, expected, 2e-3 * expected + 1e-4 * amplitude) << "tau " << p.tau_s;
    if (std::abs(std::remainder(p.tau_s, period)) < 1e-9) {
      EXPECT_LT(p.adev, 1e-9 * amplitude) << "tau " << p.tau_s;
      ++at_period;
    }
  }
  EXPECT_EQ(at_period, 4);  // 0.5, 1, 2, 5 s (m = 50, 100, 200, 500)
}

TEST(AllanFit, WhiteNoiseDensity) {
  const double rate = 200.0, n_density = 0.01;
  for (uint64_t seed : {11u, 12u, 13u}) {
    const std::vector<double> x = WhiteNoise(120000, rate, n_density, seed);
    const std::vector<AllanPoint> c = OverlappingAllanDeviation(x, rate);
    for (const AllanPoint& p : c) {
      EXPECT_LT(std::abs(Z(p, n_density / std::sqrt(p.tau_s))), 4.0) << "tau " << p.tau_s;
    }
    const AllanFit fit = FitAllan(c);
    EXPECT_TRUE(fit.white_density.identified);
    EXPECT_GT(fit.white_density.sigma, 0.0);
    EXPECT_LT(std::abs(fit.white_density.value - n_density), 3.0 * fit.white_density.sigma);
    EXPECT_LT(std::abs(fit.white_density.value / n_density - 1.0), 0.05);
    EXPECT_FALSE(fit.random_walk.identified) << "seed " << seed;
    EXPECT_EQ(fit.random_walk.value, 0.0);
  }
}

TEST(AllanFit, RandomWalkDensity) {
  const double rate = 200.0, n_density = 0.01, k_density = 0.01;
  for (uint64_t seed : {21u, 22u, 23u}) {
    std::vector<double> x = WhiteNoise(120000, rate, n_density, seed);
    AddRandomWalk(rate, k_density, seed + 100, &x);
    const std::vector<AllanPoint> c = OverlappingAllanDeviation(x, rate);
    const AllanFit fit = FitAllan(c);
    ASSERT_TRUE(fit.random_walk.identified) << "seed " << seed;
    EXPECT_LT(std::abs(fit.random_walk.value / k_density - 1.0), 0.25) << "seed " << seed;
    EXPECT_LT(std::abs(fit.random_walk.value - k_density), 3.0 * fit.random_walk.sigma);
    EXPECT_LT(std::abs(fit.white_density.value / n_density - 1.0), 0.05);
    // The minimum lies near where N^2 / tau = K^2 tau / 3: tau = sqrt(3) N / K = 1.7 s.
    EXPECT_GT(fit.min_tau_s, 0.5);
    EXPECT_LT(fit.min_tau_s, 6.0);
  }
}

// The Allan deviation of a first-order Gauss-Markov process rises as K sqrt(tau/3) (K^2 = 2 s^2 /
// T) well below T, peaks at 0.62 s near tau = 1.89 T and falls as s sqrt(2 T / tau) beyond. With
// white noise under it, the curve has a floor before the peak: that is what the bias instability
// reads, and what it is compared with here, from the analytic variance at the curve's taus.
TEST(AllanFit, GaussMarkovBiasInstability) {
  const double rate = 200.0, n_density = 0.002, s = 0.01, t_corr = 10.0;
  // The analytic GM curve itself: the peak.
  double peak = 0.0, peak_tau = 0.0;
  for (double tau = 0.1; tau < 100.0; tau *= 1.001) {
    const double a = std::sqrt(GaussMarkovAvar(tau, s, t_corr));
    if (a > peak) {
      peak = a;
      peak_tau = tau;
    }
  }
  EXPECT_NEAR(peak / s, 0.62, 0.01);
  EXPECT_NEAR(peak_tau / t_corr, 1.89, 0.02);

  for (uint64_t seed : {31u, 32u, 33u}) {
    std::vector<double> x = WhiteNoise(72000, rate, n_density, seed);
    AddGaussMarkov(rate, s, t_corr, seed + 100, &x);
    const std::vector<AllanPoint> c = OverlappingAllanDeviation(x, rate);
    double expected_min = HUGE_VAL;
    for (const AllanPoint& p : c) {
      const double expected =
          std::sqrt(n_density * n_density / p.tau_s + GaussMarkovAvar(p.tau_s, s, t_corr));
      EXPECT_LT(std::abs(Z(p, expected)), 4.0) << "tau " << p.tau_s << " seed " << seed;
      expected_min = std::min(expected_min, expected);
    }
    const AllanFit fit = FitAllan(c);
    const double expected_b = expected_min / 0.664;
    EXPECT_TRUE(fit.bias_instability.identified) << "seed " << seed;
    EXPECT_GT(fit.bias_instability.value, expected_b / 2.0) << "seed " << seed;
    EXPECT_LT(fit.bias_instability.value, expected_b * 2.0) << "seed " << seed;
    std::printf("GM seed %d: B %.4g (expected %.4g, floor at %.3g s), peak %.4g\n",
                static_cast<int>(seed), fit.bias_instability.value, expected_b, fit.min_tau_s,
                peak);
  }
}

/// 200 Hz at rest with a gyro bias and gravity along z, noisy; `yaw_rate` adds a turn.
std::vector<ImuSample> Recording(double duration_s,
                                 const std::function<double(double)>& yaw_rate,
                                 uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01;
  std::vector<ImuSample> imu;
  for (size_t i = 0; i < duration_s * 200.0; ++i) {
    const double t = i / 200.0;
    ImuSample s;
    s.t_ns = 1'000'000'000'000 + SecondsToNs(t);
    s.gyro_rad_s = Eigen::Vector3d(0.001, -0.002, 0.0015 + yaw_rate(t)) +
                   1e-3 * Eigen::Vector3d(n01(rng), n01(rng), n01(rng));
    s.accel_m_s2 =
        Eigen::Vector3d(0.05, -0.03, 9.81) + 0.02 * Eigen::Vector3d(n01(rng), n01(rng), n01(rng));
    imu.push_back(s);
  }
  return imu;
}

double SecondsFromStart(const std::vector<ImuSample>& imu, size_t i) {
  return i < imu.size() ? NsToSeconds(imu[i].t_ns - imu[0].t_ns)
                        : NsToSeconds(imu.back().t_ns - imu[0].t_ns) + 0.005;
}

TEST(FindRestSegments, RestTurnRest) {
  // At rest 30 s, a 10 s turn (yaw rate 0.5 sin(pi t / 10) rad/s), at rest 40 s.
  const auto yaw = [](double t) {
    return t > 30.0 && t < 40.0 ? 0.5 * std::sin(kPi * (t - 30.0) / 10.0) : 0.0;
  };
  const std::vector<ImuSample> imu = Recording(80.0, yaw, 41);
  const std::vector<RestSegment> rest = FindRestSegments(imu, 5.0);
  ASSERT_EQ(rest.size(), 2u);
  EXPECT_NEAR(SecondsFromStart(imu, rest[0].begin), 40.0, 0.5);
  EXPECT_NEAR(SecondsFromStart(imu, rest[0].end), 80.0, 0.5);
  EXPECT_NEAR(rest[0].duration_s, 40.0, 0.5);
  EXPECT_NEAR(SecondsFromStart(imu, rest[1].begin), 0.0, 0.5);
  EXPECT_NEAR(SecondsFromStart(imu, rest[1].end), 30.0, 0.5);
  EXPECT_NEAR(rest[1].duration_s, 30.0, 0.5);
  EXPECT_EQ(rest[0].end, imu.size());
  EXPECT_EQ(rest[1].begin, 0u);

  const std::vector<RestSegment> long_only = FindRestSegments(imu, 35.0);
  ASSERT_EQ(long_only.size(), 1u);
  EXPECT_EQ(long_only[0].begin, rest[0].begin);
}

TEST(FindRestSegments, TimeGapSplitsASegment) {
  std::vector<ImuSample> imu = Recording(
      20.0, [](double) { return 0.0; }, 42);
  ASSERT_EQ(FindRestSegments(imu, 5.0).size(), 1u);
  // Drop the samples in [8, 8.5) s: a 0.5 s gap.
  const size_t gap_begin = 8 * 200, gap_end = 8 * 200 + 100;
  imu.erase(imu.begin() + gap_begin, imu.begin() + gap_end);
  const std::vector<RestSegment> rest = FindRestSegments(imu, 5.0);
  ASSERT_EQ(rest.size(), 2u);
  EXPECT_EQ(rest[0].begin, gap_begin);  // the 11.5 s after the gap first
  EXPECT_EQ(rest[0].end, imu.size());
  EXPECT_NEAR(rest[0].duration_s, 11.5, 1e-6);
  EXPECT_EQ(rest[1].begin, 0u);
  EXPECT_EQ(rest[1].end, gap_begin);
  EXPECT_NEAR(rest[1].duration_s, 8.0, 1e-6);
}

TEST(FindRestSegments, EmptyAndShortInput) {
  EXPECT_TRUE(FindRestSegments({}, 1.0).empty());
  const std::vector<ImuSample> imu = Recording(
      3.0, [](double) { return 0.0; }, 43);
  EXPECT_TRUE(FindRestSegments(imu, 5.0).empty());
  const std::vector<RestSegment> rest = FindRestSegments(imu, 2.0);
  ASSERT_EQ(rest.size(), 1u);
  EXPECT_TRUE(std::isfinite(rest[0].duration_s));
}

TEST(AnalyseImuAtRest, SyntheticDensitiesAndReportFiles) {
  std::vector<ImuSample> imu = Recording(
      300.0, [](double) { return 0.0; }, 44);
  const ImuAllanReport r = AnalyseImuAtRest(imu, FindRestSegments(imu, 5.0).at(0));
  EXPECT_NEAR(r.rate_hz, 200.0, 1e-6);
  // Per-sample sigma 1e-3 rad/s and 0.02 m/s^2 at 200 Hz: N = sigma / sqrt(200).
  const double gyro_n = 1e-3 / std::sqrt(200.0), accel_n = 0.02 / std::sqrt(200.0);
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(r.gyro_fit[a].white_density.value, gyro_n, 0.05 * gyro_n) << a;
    EXPECT_NEAR(r.accel_fit[a].white_density.value, accel_n, 0.05 * accel_n) << a;
  }
  EXPECT_NEAR(r.gyro_combined.white_density.value, gyro_n, 0.05 * gyro_n);
  EXPECT_TRUE(r.gyro_combined.white_density.identified);
  EXPECT_GT(r.gyro_combined.white_density.sigma, 0.0);
  EXPECT_LT(r.gyro_combined.white_density.sigma, r.gyro_fit[0].white_density.sigma);

  const std::filesystem::path dir = std::filesystem::path(SKERRY_TEST_TMP_DIR) / "allan";
  std::filesystem::create_directories(dir);
  WriteAllanCsv((dir / "allan.csv").string(), r);
  std::ifstream csv(dir / "allan.csv");
  std::string header, line;
  std::getline(csv, header);
  EXPECT_EQ(header.rfind("tau_s,gyro_x_adev,gyro_y_adev,gyro_z_adev,accel_x_adev,", 0), 0u);
  EXPECT_NE(header.find(",accel_z_sigma"), std::string::npos);
  size_t rows = 0;
  while (std::getline(csv, line)) {
    ++rows;
    EXPECT_EQ(std::count(line.begin(), line.end(), ','), 12);
  }
  EXPECT_EQ(rows, r.gyro[0].size());

  WriteAllanSvg((dir / "allan.svg").string(), r, "synthetic <rest> & noise");
  std::ifstream svg_file(dir / "allan.svg");
  std::stringstream svg;
  svg << svg_file.rdbuf();
  EXPECT_NE(svg.str().find("<svg"), std::string::npos);
  EXPECT_NE(svg.str().find("synthetic &lt;rest&gt; &amp; noise"), std::string::npos);
  EXPECT_NE(svg.str().find("</svg>"), std::string::npos);
  size_t polylines = 0;
  for (size_t at = svg.str().find("<polyline"); at != std::string::npos;
       at = svg.str().find("<polyline", at + 1)) {
    ++polylines;
  }
  EXPECT_EQ(polylines, 6u);

  EXPECT_THROW(WriteAllanCsv("/nonexistent-dir/allan.csv", r), std::runtime_error);
  try {
    WriteAllanSvg("/nonexistent-dir/allan.svg", r, "x");
    ADD_FAILURE() << "no throw";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent-dir/allan.svg"), std::string::npos);
  }
}

TEST(AllanDeviation, BadInputThrows) {
  EXPECT_THROW(OverlappingAllanDeviation(std::vector<double>(19, 1.0), 100.0),
               std::invalid_argument);
  EXPECT_NO_THROW(OverlappingAllanDeviation(std::vector<double>(20, 1.0), 100.0));
  std::vector<double> x = WhiteNoise(100, 100.0, 0.01, 5);
  EXPECT_THROW(OverlappingAllanDeviation(x, 0.0), std::invalid_argument);
  EXPECT_THROW(OverlappingAllanDeviation(x, -1.0), std::invalid_argument);
  EXPECT_THROW(OverlappingAllanDeviation(x, std::numeric_limits<double>::quiet_NaN()),
               std::invalid_argument);
  EXPECT_THROW(OverlappingAllanDeviation(x, HUGE_VAL), std::invalid_argument);
  x[50] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(OverlappingAllanDeviation(x, 100.0), std::invalid_argument);
  x[50] = HUGE_VAL;
  EXPECT_THROW(OverlappingAllanDeviation(x, 100.0), std::invalid_argument);
  EXPECT_THROW(FitAllan({}), std::invalid_argument);
  const std::vector<ImuSample> imu = Recording(
      1.0, [](double) { return 0.0; }, 6);
  EXPECT_THROW(AnalyseImuAtRest(imu, RestSegment{0, 19, 0.0}), std::invalid_argument);
  EXPECT_THROW(AnalyseImuAtRest(imu, RestSegment{0, imu.size() + 1, 0.0}), std::invalid_argument);
  EXPECT_THROW(AnalyseImuAtRest(imu, RestSegment{50, 10, 0.0}), std::invalid_argument);
}

// EuRoC V1_01_easy: the MAV stands on the floor for its first seconds, rotors spinning up before
// take-off. Its ADIS16448's white densities, read from that rest, against the datasheet figures
// in imu0_sensor.yaml.
TEST(AnalyseImuAtRest, EurocV101RestBeforeTakeOffVibrates) {
  const std::string dir = std::string(SKERRY_SHARED_DATA_DIR) + "/euroc_v1_01";
  if (!std::filesystem::exists(dir + "/imu0_data.csv")) GTEST_SKIP() << "no EuRoC data at " << dir;
  const Dataset data = ImportEuroc(dir);
  const std::vector<RestSegment> rest = FindRestSegments(data.imu_samples, 5.0);
  if (rest.empty()) GTEST_SKIP() << "no rest of 5 s in " << dir;
  // The rest before take-off (at 5.0 s the specific force jumps by 0.8 m/s^2): the data's first
  // 5 s; nothing else in the recording stands still for 5 s.
  ASSERT_EQ(rest.size(), 1u);
  EXPECT_EQ(rest[0].begin, 0u);
  EXPECT_NEAR(rest[0].duration_s, 5.0, 0.5);
  const ImuAllanReport r = AnalyseImuAtRest(data.imu_samples, rest[0]);
  const double t0 = NsToSeconds(data.imu_samples.front().t_ns);
  std::printf("EuRoC V1_01 rest: [%zu, %zu) = %.3f..%.3f s from the start, %.3f s, %.2f Hz\n",
              rest[0].begin, rest[0].end, NsToSeconds(data.imu_samples[rest[0].begin].t_ns) - t0,
              NsToSeconds(data.imu_samples[rest[0].end - 1].t_ns) - t0, rest[0].duration_s,
              r.rate_hz);
  const double gyro_datasheet = 1.6968e-04, accel_datasheet = 2.0e-3;  // imu0_sensor.yaml
  for (int a = 0; a < 3; ++a) {
    std::printf("  axis %d: gyro N %.4g +- %.2g (%s), accel N %.4g +- %.2g (%s)\n", a,
                r.gyro_fit[a].white_density.value, r.gyro_fit[a].white_density.sigma,
                r.gyro_fit[a].white_density.identified ? "identified" : "shortest tau",
                r.accel_fit[a].white_density.value, r.accel_fit[a].white_density.sigma,
                r.accel_fit[a].white_density.identified ? "identified" : "shortest tau");
  }
  const IdentifiedValue& g = r.gyro_combined.white_density;
  const IdentifiedValue& acc = r.accel_combined.white_density;
  std::printf("  gyro N %.4g +- %.2g rad/s/sqrt(Hz) (datasheet %.4g, x%.2f)%s\n", g.value, g.sigma,
              gyro_datasheet, g.value / gyro_datasheet, g.identified ? "" : ", not identified");
  std::printf("  accel N %.4g +- %.2g m/s^2/sqrt(Hz) (datasheet %.4g, x%.2f)%s\n", acc.value,
              acc.sigma, accel_datasheet, acc.value / accel_datasheet,
              acc.identified ? "" : ", not identified");
  const std::filesystem::path out = std::filesystem::path(SKERRY_TEST_TMP_DIR) / "allan";
  std::filesystem::create_directories(out);
  WriteAllanCsv((out / "euroc_v1_01.csv").string(), r);
  WriteAllanSvg((out / "euroc_v1_01.svg").string(), r, "EuRoC V1_01 ADIS16448 before take-off");
  // The MAV stands still, but is it quiet? Sensor noise at rest never makes the Allan deviation
  // rise at the shortest taus (quantisation falls as 1/tau, white noise as 1/sqrt(tau)); a rise
  // there is a vibration (a sine peaks near 0.37 of its period, SineClosedForm) such as spinning
  // rotors shake the airframe with, and it is not the sensor's noise density.
  std::string vibration;
  for (int a = 0; a < 3; ++a) {
    for (const auto& [name, curve] :
         {std::pair{"gyro", &r.gyro[a]}, std::pair{"accel", &r.accel[a]}}) {
      const AllanPoint& first = curve->front();
      for (const AllanPoint& p : *curve) {
        if (p.tau_s < 0.1 && p.adev - first.adev > 3.0 * p.adev_sigma && vibration.empty()) {
          char buf[200];
          std::snprintf(buf, sizeof(buf), "%s %c rises from %.3g at %.3f s to %.3g at %.3f s", name,
                        "xyz"[a], first.adev, first.tau_s, p.adev, p.tau_s);
          vibration = buf;
        }
      }
    }
  }
  // Vibration only adds to the sensor's own noise.
  EXPECT_GT(g.value, gyro_datasheet / 3.0);
  EXPECT_GT(acc.value, accel_datasheet / 3.0);
  // What the recording holds: the rotors' vibration, found, and therefore no white density
  // identified on the gyro (the twin then takes its noise from the residuals).
  EXPECT_FALSE(vibration.empty()) << "the rest before take-off looks quiet";
  std::printf("  %s\n", vibration.c_str());
  EXPECT_FALSE(g.identified);
  EXPECT_GT(g.value, gyro_datasheet * 3.0);
}

}  // namespace
}  // namespace skerry
