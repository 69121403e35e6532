// Prior work's planar EKF (baseline_planar_ekf.h) against a known planar motion: it follows a
// turning vessel from GNSS, recovers a wrong start from the matcher's poses, deweights GNSS during
// a loss as its alpha2 says, and refuses time going back.

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "skerry/lidar_aerial/baseline_planar_ekf.h"

namespace skerry::lidar_aerial::baseline {
namespace {

constexpr double kDeg = M_PI / 180.0;

// A vessel at 4 m/s surge turning at 3 deg/s from the origin heading east.
struct Circle {
  double u = 4.0, r = 3.0 * kDeg;
  PlanarPose At(double t) const {
    const double psi = r * t, R = u / r;
    return {{R * std::sin(psi), R * (1.0 - std::cos(psi))}, psi};
  }
};

PlanarEstimate Start(const PlanarPose& p, double u, double sigma_m, double sigma_deg) {
  PlanarEstimate s;
  s.x << p.t.x(), p.t.y(), u, 0.0, p.yaw;
  s.P.setZero();
  s.P.diagonal() << sigma_m * sigma_m, sigma_m * sigma_m, 1.0, 1.0, std::pow(sigma_deg * kDeg, 2);
  return s;
}

TEST(BaselinePlanarEkf, FollowsATurnFromGnssAndRecoversFromTheMatchersPoses) {
  const Circle c;
  std::mt19937_64 rng(5);
  std::normal_distribution<double> n01;
  // Started 6 m and 4 deg off; GNSS of 0.5 m at 10 Hz.
  PlanarPose wrong = c.At(0.0);
  wrong.t += Eigen::Vector2d(6.0, -3.0);
  wrong.yaw += 4.0 * kDeg;
  PlanarEkf ekf(Start(wrong, c.u, 10.0, 10.0));
  for (int k = 1; k <= 600; ++k) {
    const double t = 0.1 * k;
    ekf.Predict(SecondsToNs(t), c.r);
    const PlanarPose truth = c.At(t);
    ekf.UpdatePosition(truth.t + 0.5 * Eigen::Vector2d(n01(rng), n01(rng)), false);
  }
  const PlanarPose end = c.At(60.0);
  EXPECT_LT((ekf.estimate().x.head<2>() - end.t).norm(), 1.0);
  // GNSS gives the course over ground, psi + atan(v_sway / v_surge), not the heading: with sway
  // free the start's heading error stays (prior work needed the matcher for heading).
  const auto& x = ekf.estimate().x;
  EXPECT_LT(std::abs(WrapAngle(x(4) + std::atan2(x(3), x(2)) - end.yaw)), 1.0 * kDeg);
  EXPECT_GT(std::abs(WrapAngle(x(4) - end.yaw)), 2.0 * kDeg);

  // The matcher's poses alone (1 Hz, exact) pull a 3 deg heading error in.
  PlanarPose off = c.At(60.0);
  off.yaw += 3.0 * kDeg;
  PlanarEkf m(Start(off, c.u, 1.0, 5.0));
  for (int k = 61; k <= 80; ++k) {
    m.Predict(SecondsToNs(k), c.r);
    m.UpdatePose(c.At(k));
  }
  EXPECT_LT(std::abs(WrapAngle(m.estimate().x(4) - c.At(80).yaw)), 0.2 * kDeg);
}

TEST(BaselinePlanarEkf, DuringALossAJumpMovesItHundredTimesLess) {
  const Circle c;
  const auto pulled = [&](bool loss) {
    PlanarEkf ekf(Start(c.At(0.0), c.u, 0.5, 1.0));
    for (int k = 1; k <= 100; ++k) {
      ekf.Predict(SecondsToNs(0.1 * k), c.r);
      ekf.UpdatePosition(c.At(0.1 * k).t, false);
    }
    ekf.Predict(SecondsToNs(10.1), c.r);
    const Eigen::Vector2d before = ekf.estimate().x.head<2>();
    ekf.UpdatePosition(c.At(10.1).t + Eigen::Vector2d(14.5, 0.0), loss);
    return (ekf.estimate().x.head<2>() - before).norm();
  };
  const double normal = pulled(false), lost = pulled(true);
  EXPECT_GT(normal, 0.05);
  EXPECT_LT(lost, normal / 50.0);
}

TEST(BaselinePlanarEkf, TimeGoingBackIsRefused) {
  PlanarEkf ekf(Start({}, 1.0, 1.0, 1.0));
  ekf.Predict(SecondsToNs(1.0), 0.0);
  EXPECT_THROW(ekf.Predict(SecondsToNs(0.5), 0.0), std::invalid_argument);
  EXPECT_EQ(ekf.estimate().t_ns, SecondsToNs(1.0));
  EXPECT_NEAR(ekf.estimate().x(0), 1.0, 1e-9);  // 1 m/s east for a second
}

}  // namespace
}  // namespace skerry::lidar_aerial::baseline
