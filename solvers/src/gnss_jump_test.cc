#include "skerry/solvers/gnss_jump_test.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>

#include "skerry/core/mahalanobis.h"

namespace skerry {
namespace {

// y^T S^-1 y, or a negative number when S is not positive definite.
double Mahalanobis2(const Eigen::Vector3d& y, const Eigen::Matrix3d& S) {
  return SquaredMahalanobis<3>(y, S).value_or(-1.0);
}

}  // namespace

void GnssJumpTest::Accepted(TimeNs t_ns, const MetricInnovation& in, double gate) {
  // A jump still outstanding when a fix gets in: the window now follows the jumped receiver, and
  // the receiver's step back will be the end of that jump, not a new one.
  if (in_streak_ && Significant(outstanding_m_, in, gate)) TakeIn();
  EndStreakAt(t_ns, in);
}

void GnssJumpTest::EndStreakAt(TimeNs t_ns, const MetricInnovation& in) {
  in_streak_ = false;
  outstanding_m_.setZero();
  explained_ = 0;
  last_accepted_ns_ = in.valid() ? t_ns : -1;  // a covariance that gates nothing: no reference
  if (in.valid()) last_accepted_ = in;
}

StreakStart GnssJumpTest::StreakStarted(TimeNs t_ns,
                                        const MetricInnovation& in,
                                        double gate,
                                        double max_gap_s) {
  outstanding_m_.setZero();
  explained_ = 0;
  in_streak_ = in.valid();
  previous_ = in;
  if (!in_streak_ || last_accepted_ns_ < 0 || t_ns < last_accepted_ns_ ||
      NsToSeconds(t_ns - last_accepted_ns_) > max_gap_s) {
    return StreakStart::kNoStep;
  }
  const Eigen::Vector3d step = in.y - last_accepted_.y;
  const Eigen::Matrix3d cov = in.S + last_accepted_.S;
  const double d2_step = Mahalanobis2(step, cov);
  if (!(d2_step > gate)) return StreakStart::kNoStep;
  if (UndoesTaken(step, cov, gate)) return StreakStart::kBack;
  outstanding_m_ = step;
  outstanding_cov_ = cov;
  Tally(t_ns, in, gate);
  return StreakStart::kJump;
}

bool GnssJumpTest::Observe(TimeNs t_ns, const MetricInnovation& in, double gate) {
  if (!in_streak_ || !in.valid()) return false;
  const Eigen::Vector3d step = in.y - previous_.y;
  // The receivers' noise, and what the estimate's error grew by in between (S's growth: exact
  // for a random walk, an upper bound for an error growing smoothly, as a drifting heading's).
  Eigen::Matrix3d cov = in.R + previous_.R;
  const Eigen::Matrix3d growth = (in.S - in.R) - (previous_.S - previous_.R);
  if (Eigen::LLT<Eigen::Matrix3d>(0.5 * (growth + growth.transpose())).info() == Eigen::Success) {
    cov += 0.5 * (growth + growth.transpose());
  }
  const bool stepped = Mahalanobis2(step, cov) > gate;
  // A step that undoes a jump the window took in, inside a streak that something else opened:
  // the window, pulled by the jumped fixes it took, can leave the gate before the receiver steps
  // back. The receiver is back, as at the start of a streak (StreakStarted).
  if (stepped && UndoesTaken(step, cov, gate)) {
    previous_ = in;
    return true;
  }
  // Only a jump that opened the streak is followed, and only back: a streak opened by the
  // estimate drifting out of the gate is the gate's alone, and a receiver that steps while its
  // fixes are being rejected anyway changes nothing the gate does not see.
  if (!outstanding_m_.isZero() && stepped &&
      Mahalanobis2(outstanding_m_ + step, cov) < Mahalanobis2(outstanding_m_, cov)) {
    outstanding_m_ += step;
    outstanding_cov_ += cov;
    explained_ = 0;  // a jump of another size from here on
  }
  previous_ = in;
  Tally(t_ns, in, gate);
  return false;
}

bool GnssJumpTest::UndoesTaken(const Eigen::Vector3d& step,
                               const Eigen::Matrix3d& cov,
                               double gate) {
  if (taken_m_.isZero()) return false;
  // The step undoes a jump the window took in, within the noise of both steps: the receiver is
  // back, and it is the window that is off, by the jump it followed.
  const double d2_back = Mahalanobis2(taken_m_ + step, cov + taken_cov_);
  if (!(d2_back >= 0.0 && d2_back <= gate)) return false;
  taken_m_.setZero();
  taken_cov_.setZero();
  return true;
}

void GnssJumpTest::Tally(TimeNs t_ns, const MetricInnovation& in, double gate) {
  if (!in_streak_ || !Significant(outstanding_m_, in, gate)) return;
  // The jump explains the fix: y - o is inside the gate (o is the step in y: y jumped with it),
  // against the fix's innovation covariance and the error of o, which came from two fixes.
  const double d2_jump = Mahalanobis2(in.y - outstanding_m_, in.S + outstanding_cov_);
  if (!(d2_jump >= 0.0 && d2_jump <= gate)) return;
  if (explained_ == 0) {
    explained_since_ns_ = t_ns;
    sum_y_.setZero();
    sum_shared_.setZero();
    sum_r_.setZero();
  }
  ++explained_;
  sum_y_ += in.y;
  sum_shared_ += in.S - in.R;
  sum_r_ += in.R;
}

bool GnssJumpTest::Step(
    TimeNs t_ns, int min_fixes, double min_s, double gate, JumpStep* step) const {
  if (!in_streak_ || explained_ < std::max(1, min_fixes) || t_ns < explained_since_ns_ ||
      NsToSeconds(t_ns - explained_since_ns_) < min_s) {
    return false;
  }
  const double n = explained_;
  MetricInnovation mean;
  mean.y = sum_y_ / n;
  mean.R = sum_r_ / n;
  if (!Significant(mean.y, mean, gate)) return false;
  // y is predicted minus measured: the receiver's offset is -y.
  step->step_m = -mean.y;
  const Eigen::Matrix3d cov = sum_shared_ / n + mean.R / n;
  step->cov = 0.5 * (cov + cov.transpose());
  step->fixes = explained_;
  return step->step_m.allFinite() && step->cov.allFinite();
}

void GnssJumpTest::Absorbed(TimeNs t_ns, const MetricInnovation& in) {
  outstanding_cov_.setZero();
  EndStreakAt(t_ns, in);
}

bool GnssJumpTest::Significant(const Eigen::Vector3d& jump_m,
                               const MetricInnovation& in,
                               double gate) {
  return !jump_m.isZero() && in.valid() && Mahalanobis2(jump_m, 2.0 * in.R) > gate;
}

bool GnssJumpTest::Explains(const MetricInnovation& in, double d2, double gate) const {
  if (!in_streak_ || !Significant(outstanding_m_, in, gate)) return false;
  const double d2_jump = Mahalanobis2(in.y - outstanding_m_, in.S);
  return d2_jump >= 0.0 && d2_jump < d2;
}

void GnssJumpTest::Reacquired(const MetricInnovation& in, double gate) {
  if (in_streak_ && Significant(outstanding_m_, in, gate)) TakeIn();
  const Eigen::Vector3d taken = taken_m_;
  const Eigen::Matrix3d taken_cov = taken_cov_;
  Reset();
  taken_m_ = taken;
  taken_cov_ = taken_cov;
}

void GnssJumpTest::TakeIn() {
  taken_m_ += outstanding_m_;
  taken_cov_ += outstanding_cov_;
}

void GnssJumpTest::Reset() {
  last_accepted_ns_ = -1;
  in_streak_ = false;
  explained_ = 0;
  outstanding_m_.setZero();
  taken_m_.setZero();
  taken_cov_.setZero();
}

}  // namespace skerry
