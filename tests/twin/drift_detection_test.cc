// The drift detection limit (drift_detection.h): the probed correlation times, a Gauss-Markov
// error of the stated variance and correlation, the batch's gain measured through a known linear
// smoother (slow errors absorbed, fast ones kept, the recording's own noise irrelevant), and the
// limit stated for a drift that was not identified.

#include "skerry/twin/drift_detection.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

namespace skerry {
namespace {

TEST(DriftDetection, ProbesThreeDecadesClippedToTheSpan) {
  EXPECT_EQ(DriftProbeTaus(600.0, 0.5), (std::vector<double>{3.0, 30.0, 300.0}));
  EXPECT_EQ(DriftProbeTaus(100.0, 1.0), (std::vector<double>{3.0, 30.0, 50.0}));
  // A slow receiver: 3 s is below two periods.
  EXPECT_EQ(DriftProbeTaus(1000.0, 5.0), (std::vector<double>{10.0, 30.0, 300.0}));
  // A short recording: everything clips to one value.
  EXPECT_EQ(DriftProbeTaus(4.0, 1.0), (std::vector<double>{2.0}));
  EXPECT_THROW(DriftProbeTaus(0.0, 1.0), std::invalid_argument);
  EXPECT_THROW(DriftProbeTaus(100.0, std::nan("")), std::invalid_argument);
}

std::vector<double> Stamps(int n, double dt) {
  std::vector<double> t(n);
  for (int i = 0; i < n; ++i) t[i] = i * dt;
  return t;
}

TEST(DriftDetection, GaussMarkovHasItsVarianceAndCorrelation) {
  // Uneven intervals (3 s and 1 s alternating: 0, 3, 4, 7, 8, ...): the exact discretisation
  // keeps the variance.
  std::vector<double> t;
  for (int i = 0; i < 200000; ++i) t.push_back(2.0 * i + (i % 2 == 0 ? 0.0 : 1.0));
  const double tau = 10.0, sh = 0.3, sv = 0.7;
  const auto d = GaussMarkovPerturbation(t, tau, sh, sv, 42);
  ASSERT_EQ(d.size(), t.size());
  double var[3] = {0, 0, 0}, cov1[3] = {0, 0, 0};  // cov1 over the 1 s intervals
  int pairs = 0;
  for (size_t i = 0; i < d.size(); ++i) {
    for (int a = 0; a < 3; ++a) var[a] += d[i][a] * d[i][a] / d.size();
    if (i % 2 == 1 && i + 1 < d.size()) {  // from an odd index: the 1 s interval
      for (int a = 0; a < 3; ++a) cov1[a] += d[i][a] * d[i + 1][a];
      ++pairs;
    }
  }
  // Relative sampling error of a variance over n samples of correlation time tau / dt ~ 5:
  // sqrt(2 * 2 * 5 / n) ~ 1 %; 5 % is 5 sigma.
  EXPECT_NEAR(var[0], sh * sh, 0.05 * sh * sh);
  EXPECT_NEAR(var[1], sh * sh, 0.05 * sh * sh);
  EXPECT_NEAR(var[2], sv * sv, 0.05 * sv * sv);
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(cov1[a] / pairs / var[a], std::exp(-1.0 / tau), 0.02) << "axis " << a;
  }
  // Reproducible in the seed, different across seeds.
  EXPECT_EQ(GaussMarkovPerturbation(Stamps(10, 1.0), 5.0, 1.0, 1.0, 7)[9],
            GaussMarkovPerturbation(Stamps(10, 1.0), 5.0, 1.0, 1.0, 7)[9]);
  EXPECT_NE(GaussMarkovPerturbation(Stamps(10, 1.0), 5.0, 1.0, 1.0, 7)[9],
            GaussMarkovPerturbation(Stamps(10, 1.0), 5.0, 1.0, 1.0, 8)[9]);
  // A zero sigma adds nothing.
  for (const auto& x : GaussMarkovPerturbation(Stamps(50, 1.0), 5.0, 0.5, 0.0, 3)) {
    EXPECT_EQ(x.z(), 0.0);
  }
  EXPECT_THROW(GaussMarkovPerturbation({0.0, 2.0, 1.0}, 5.0, 1.0, 1.0, 1), std::invalid_argument);
  EXPECT_THROW(GaussMarkovPerturbation(Stamps(5, 1.0), 0.0, 1.0, 1.0, 1), std::invalid_argument);
  EXPECT_THROW(GaussMarkovPerturbation(Stamps(5, 1.0), 5.0, -1.0, 1.0, 1), std::invalid_argument);
}

// A stand-in for the batch: a linear smoother, the truth being the centred moving average of the
// fixes over `half` samples each side. Residuals = fixes - truth.
std::vector<Eigen::Vector3d> Residuals(const std::vector<Eigen::Vector3d>& z, int half) {
  const int n = static_cast<int>(z.size());
  std::vector<Eigen::Vector3d> r(n);
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int count = 0;
    for (int j = std::max(0, i - half); j <= std::min(n - 1, i + half); ++j, ++count) sum += z[j];
    r[i] = z[i] - sum / count;
  }
  return r;
}

TEST(DriftDetection, GainOfALinearSmootherFromPerturbAndResolve) {
  const auto t = Stamps(6000, 1.0);
  const int half = 30;  // a 61 s moving average: it follows what changes slower than that
  // The recording's own noise: white plus a drift, its errors the batch must not confuse with the
  // injected one's.
  auto noise = GaussMarkovPerturbation(t, 20.0, 0.2, 0.3, 1);
  const auto white = GaussMarkovPerturbation(t, 1e-3, 0.5, 0.8, 2);
  for (size_t i = 0; i < t.size(); ++i) noise[i] += white[i];
  const auto before = Residuals(noise, half);
  auto gain_at = [&](double tau, const std::vector<Eigen::Vector3d>& base,
                     const std::vector<Eigen::Vector3d>& base_residuals) {
    const auto d = GaussMarkovPerturbation(t, tau, 0.5, 0.8, 99);
    std::vector<Eigen::Vector3d> z(t.size()), change(t.size());
    for (size_t i = 0; i < t.size(); ++i) z[i] = base[i] + d[i];
    const auto after = Residuals(z, half);
    for (size_t i = 0; i < t.size(); ++i) change[i] = after[i] - base_residuals[i];
    return MeasureBatchGain({{d, change, {}}});
  };
  const DriftBatchGain fast = gain_at(1.0, noise, before);
  const DriftBatchGain mid = gain_at(30.0, noise, before);
  const DriftBatchGain slow = gain_at(1000.0, noise, before);
  // Fast errors survive nearly whole, slow ones are taken by the smoother.
  EXPECT_GT(fast.horizontal, 0.9);
  EXPECT_GT(fast.vertical, 0.9);
  EXPECT_LT(slow.horizontal, 0.3);
  EXPECT_LT(slow.vertical, 0.3);
  EXPECT_GT(mid.horizontal, slow.horizontal);
  EXPECT_LT(mid.horizontal, fast.horizontal);
  // Linear in the fixes: the recording's own noise does not change the gain.
  const std::vector<Eigen::Vector3d> quiet(t.size(), Eigen::Vector3d::Zero());
  const DriftBatchGain slow_quiet = gain_at(1000.0, quiet, Residuals(quiet, half));
  EXPECT_NEAR(slow_quiet.horizontal, slow.horizontal, 1e-9);
  EXPECT_NEAR(slow_quiet.vertical, slow.vertical, 1e-9);
}

TEST(DriftDetection, GainIgnoresAConstantOffset) {
  const auto d = GaussMarkovPerturbation(Stamps(1000, 1.0), 5.0, 0.5, 0.5, 5);
  std::vector<Eigen::Vector3d> change;
  for (const auto& x : d) change.push_back(0.25 * x + Eigen::Vector3d(3.0, -2.0, 1.0));
  const DriftBatchGain g = MeasureBatchGain({{d, change, {}}});
  EXPECT_NEAR(g.horizontal, 0.25, 1e-12);
  EXPECT_NEAR(g.vertical, 0.25, 1e-12);
  EXPECT_EQ(MeasureBatchGain({{d, d, {}}}).horizontal, 1.0);
  // Pooled: each run about its own mean (offsets differ), sums of squares added.
  const auto d2 = GaussMarkovPerturbation(Stamps(1000, 1.0), 5.0, 1.0, 1.0, 6);
  std::vector<Eigen::Vector3d> change2;
  for (const auto& x : d2) change2.push_back(0.5 * x - Eigen::Vector3d(9.0, 9.0, 9.0));
  double ss_d[2] = {0, 0}, ss_d2[2] = {0, 0};
  for (int a = 0; a < 3; ++a) {
    double m = 0, m2 = 0;
    for (size_t i = 0; i < d.size(); ++i) m += d[i][a] / d.size(), m2 += d2[i][a] / d2.size();
    for (size_t i = 0; i < d.size(); ++i) {
      ss_d[a / 2] += (d[i][a] - m) * (d[i][a] - m);
      ss_d2[a / 2] += (d2[i][a] - m2) * (d2[i][a] - m2);
    }
  }
  const DriftBatchGain pooled = MeasureBatchGain({{d, change, {}}, {d2, change2, {}}});
  for (int k = 0; k < 2; ++k) {
    const double expected = std::sqrt((0.0625 * ss_d[k] + 0.25 * ss_d2[k]) / (ss_d[k] + ss_d2[k]));
    EXPECT_NEAR(k == 0 ? pooled.horizontal : pooled.vertical, expected, 1e-12);
  }
  EXPECT_THROW(MeasureBatchGain({}), std::invalid_argument);
  EXPECT_THROW(MeasureBatchGain({{d, std::vector<Eigen::Vector3d>(5), {}}}), std::invalid_argument);
  change[3].x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(MeasureBatchGain({{d, change, {}}}), std::invalid_argument);
}

TEST(DriftDetection, ThresholdAndLimit) {
  // The share of the white noise, or two bootstrap sigmas, whichever is larger.
  EXPECT_DOUBLE_EQ(DriftSeenThreshold(0.3, 0.03), 0.06);
  EXPECT_DOUBLE_EQ(DriftSeenThreshold(0.3, 0.01), 0.03);
  EXPECT_THROW(DriftSeenThreshold(-0.3, 0.01), std::invalid_argument);
  const DriftDetection d = DriftDetectionAt(300.0, {0.2, 0.0}, 0.06, 0.1);
  EXPECT_DOUBLE_EQ(d.detectable_sigma_horizontal_m, 0.3);
  EXPECT_TRUE(std::isinf(d.detectable_sigma_vertical_m));
}

TEST(DriftDetection, ScaledResidualsAddTheScaledChangeOnTheRunsFixes) {
  GnssResidualSeries before;
  for (int i = 0; i < 5; ++i) {
    before.t_s.push_back(i);
    before.e_enu_m.push_back(Eigen::Vector3d(i, -i, 2.0 * i));
    before.v_enu_m_s.push_back(Eigen::Vector3d(0.0, i, 0.0));
  }
  PerturbedBatchRun run;
  run.index = {1, 3, 4};  // fix 0 and 2 not covered by the perturbed batch
  run.residual_change_enu_m = {Eigen::Vector3d(1, 1, 1), Eigen::Vector3d(2, 0, -1),
                               Eigen::Vector3d(0, 0, 0)};
  run.injected_enu_m = run.residual_change_enu_m;
  const GnssResidualSeries r = ScaledPerturbedResiduals(before, run, 2.0, 10.0);
  ASSERT_EQ(r.t_s, (std::vector<double>{1, 3, 4}));
  EXPECT_EQ(r.e_enu_m[0], Eigen::Vector3d(3, 1, 12));
  EXPECT_EQ(r.e_enu_m[1], Eigen::Vector3d(7, -3, -4));
  EXPECT_EQ(r.v_enu_m_s[1], Eigen::Vector3d(0, 3, 0));
  run.index = {1, 5, 6};
  EXPECT_THROW(ScaledPerturbedResiduals(before, run, 1.0, 1.0), std::invalid_argument);
  run.index = {3, 1, 4};
  EXPECT_THROW(ScaledPerturbedResiduals(before, run, 1.0, 1.0), std::invalid_argument);
}

// A stand-in for the identification: a drift is seen when the residuals' RMS about their mean
// reaches 1 m horizontally, 2 m vertically.
GnssErrorModelFit SeenAboveRms(const GnssResidualSeries& r) {
  const double n = static_cast<double>(r.e_enu_m.size());
  Eigen::Vector3d mean = Eigen::Vector3d::Zero(), var = Eigen::Vector3d::Zero();
  for (const auto& x : r.e_enu_m) mean += x / n;
  for (const auto& x : r.e_enu_m) var += (x - mean).cwiseAbs2() / n;
  GnssErrorModelFit f;
  f.drift_sigma_horizontal_m.identified = std::sqrt(0.5 * (var.x() + var.y())) >= 1.0;
  f.drift_sigma_vertical_m.identified = std::sqrt(var.z()) >= 2.0;
  return f;
}

TEST(DriftDetection, TheLimitIsConfirmedByTheIdentificationOrRaised) {
  GnssResidualSeries before;
  PerturbedBatchRun run, dead;
  for (int i = 0; i < 100; ++i) {
    before.t_s.push_back(i);
    before.e_enu_m.push_back(Eigen::Vector3d::Zero());
    before.v_enu_m_s.push_back(Eigen::Vector3d::Zero());
    const double s = i % 2 == 0 ? 1.0 : -1.0;  // RMS 1 about a zero mean
    run.residual_change_enu_m.push_back(Eigen::Vector3d(s, s, s));
    dead.residual_change_enu_m.push_back(Eigen::Vector3d::Zero());  // the batch took it all
    run.index.push_back(i);
    dead.index.push_back(i);
  }
  run.injected_enu_m = run.residual_change_enu_m;
  dead.injected_enu_m = run.residual_change_enu_m;
  // Injected at sigma 1, all of it survives: the stand-in sees it from 1 m (h) and 2 m (v).
  const DriftDetection start = DriftDetectionAt(30.0, {1.0, 1.0}, 0.3, 0.3);
  // Seen in 2 of 3 runs: a majority. 0.3 -> 0.6 -> 1.2 (h); -> 2.4 (v).
  const DriftDetection d =
      ConfirmDetection(start, {run, run, dead}, before, 1.0, 1.0, SeenAboveRms);
  EXPECT_TRUE(d.confirmed_horizontal);
  EXPECT_TRUE(d.confirmed_vertical);
  EXPECT_DOUBLE_EQ(d.detectable_sigma_horizontal_m, 1.2);
  EXPECT_DOUBLE_EQ(d.detectable_sigma_vertical_m, 2.4);
  EXPECT_DOUBLE_EQ(d.gain_limit_sigma_horizontal_m, 0.3);  // the gain's limit is kept beside
  EXPECT_EQ(d.tau_s, 30.0);
  // Seen in 1 of 3: never a majority; the limit stops at the last level tried, not confirmed.
  const DriftDetection n =
      ConfirmDetection(start, {run, dead, dead}, before, 1.0, 1.0, SeenAboveRms, 2);
  EXPECT_FALSE(n.confirmed_horizontal);
  EXPECT_FALSE(n.confirmed_vertical);
  EXPECT_DOUBLE_EQ(n.detectable_sigma_horizontal_m, 1.2);
  EXPECT_DOUBLE_EQ(n.detectable_sigma_vertical_m, 1.2);
  // Seen in 1 of 2: half is not a majority.
  EXPECT_FALSE(
      ConfirmDetection(start, {run, dead}, before, 1.0, 1.0, SeenAboveRms, 2).confirmed_horizontal);
  // Already seen at the gain's limit: unchanged.
  const DriftDetection at = DriftDetectionAt(30.0, {1.0, 1.0}, 1.5, 3.0);
  const DriftDetection c = ConfirmDetection(at, {run}, before, 1.0, 1.0, SeenAboveRms);
  EXPECT_DOUBLE_EQ(c.detectable_sigma_horizontal_m, 1.5);
  EXPECT_DOUBLE_EQ(c.detectable_sigma_vertical_m, 3.0);
  EXPECT_TRUE(c.confirmed_horizontal && c.confirmed_vertical);
  // Nothing survives (gain 0): infinite, left as it is.
  const DriftDetection none = ConfirmDetection(DriftDetectionAt(300.0, {0.0, 0.0}, 0.3, 0.3), {run},
                                               before, 1.0, 1.0, SeenAboveRms);
  EXPECT_TRUE(std::isinf(none.detectable_sigma_horizontal_m));
  EXPECT_FALSE(none.confirmed_horizontal);
}

TEST(DriftDetection, ADriftNotSeenIsStatedUpToTheLargestLimit) {
  GnssErrorModelFit fit;
  fit.drift_sigma_horizontal_m = {0.0, 0.03, false};
  fit.drift_sigma_vertical_m = {0.4, 0.05, true};
  StateDriftDetectionLimit({}, &fit);
  EXPECT_EQ(fit.drift_sigma_horizontal_m.sigma, 0.03);  // nothing measured: unchanged
  const std::vector<DriftDetection> probes = {DriftDetectionAt(3.0, {0.9, 0.9}, 0.06, 0.1),
                                              DriftDetectionAt(300.0, {0.1, 0.2}, 0.06, 0.1)};
  StateDriftDetectionLimit(probes, &fit);
  EXPECT_DOUBLE_EQ(fit.drift_sigma_horizontal_m.sigma, 0.6);  // 0.06 / 0.1, the slowest probe
  EXPECT_EQ(fit.drift_sigma_horizontal_m.value, 0.0);
  EXPECT_FALSE(fit.drift_sigma_horizontal_m.identified);
  EXPECT_EQ(fit.drift_sigma_vertical_m.sigma, 0.05);  // identified: its bootstrap sigma stays
}

}  // namespace
}  // namespace skerry
