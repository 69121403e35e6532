#include "skerry/solvers/gnss_jump_test.h"

#include <Eigen/Cholesky>
#include <cmath>

namespace skerry {
namespace {

// y^T S^-1 y, or a negative number when S is not positive definite.
double Mahalanobis2(const Eigen::Vector3d& y, const Eigen::Matrix3d& S) {
  const Eigen::LLT<Eigen::Matrix3d> llt(S);
  if (llt.info() != Eigen::Success) return -1.0;
  const double d2 = y.dot(llt.solve(y));
  return std::isfinite(d2) ? d2 : -1.0;
}

}  // namespace

void GnssJumpTest::Accepted(TimeNs t_ns, const MetricInnovation& in) {
  in_streak_ = false;
  outstanding_m_.setZero();
  if (!in.valid()) {
    last_accepted_ns_ = -1;
    return;
  }
  last_accepted_ns_ = t_ns;
  last_accepted_ = in;
}

bool GnssJumpTest::StreakStarted(TimeNs t_ns,
                                 const MetricInnovation& in,
                                 double gate,
                                 double max_gap_s) {
  outstanding_m_.setZero();
  in_streak_ = in.valid();
  previous_ = in;
  if (!in_streak_ || last_accepted_ns_ < 0 || t_ns < last_accepted_ns_ ||
      NsToSeconds(t_ns - last_accepted_ns_) > max_gap_s) {
    return false;
  }
  const Eigen::Vector3d step = in.y - last_accepted_.y;
  if (Mahalanobis2(step, in.S + last_accepted_.S) > gate) outstanding_m_ = step;
  return !outstanding_m_.isZero();
}

void GnssJumpTest::Observe(const MetricInnovation& in, double gate) {
  if (!in_streak_ || !in.valid()) return;
  const Eigen::Vector3d step = in.y - previous_.y;
  // The receivers' noise, and what the estimate's error grew by in between (S's growth: exact
  // for a random walk, an upper bound for an error growing smoothly, as a drifting heading's).
  Eigen::Matrix3d cov = in.R + previous_.R;
  const Eigen::Matrix3d growth = (in.S - in.R) - (previous_.S - previous_.R);
  if (Eigen::LLT<Eigen::Matrix3d>(0.5 * (growth + growth.transpose())).info() == Eigen::Success) {
    cov += 0.5 * (growth + growth.transpose());
  }
  // Only a jump that opened the streak is followed, and only back: a streak opened by the
  // estimate drifting out of the gate is the gate's alone, and a receiver that steps while its
  // fixes are being rejected anyway changes nothing the gate does not see.
  if (!outstanding_m_.isZero() && Mahalanobis2(step, cov) > gate &&
      Mahalanobis2(outstanding_m_ + step, cov) < Mahalanobis2(outstanding_m_, cov)) {
    outstanding_m_ += step;
  }
  previous_ = in;
}

bool GnssJumpTest::Explains(const MetricInnovation& in, double d2, double gate) const {
  if (!in_streak_ || !in.valid() || outstanding_m_.isZero()) return false;
  if (!(Mahalanobis2(outstanding_m_, 2.0 * in.R) > gate)) return false;
  const double d2_jump = Mahalanobis2(in.y - outstanding_m_, in.S);
  return d2_jump >= 0.0 && d2_jump < d2;
}

void GnssJumpTest::Reset() {
  last_accepted_ns_ = -1;
  in_streak_ = false;
  outstanding_m_.setZero();
}

}  // namespace skerry
