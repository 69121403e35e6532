#pragma once
/// \file
/// Telling a GNSS jump from a drifting estimate, for the window's position gate.
///
/// The chi-square gate (innovation_gate.h) rejects a fix whose innovation y (fix minus predicted
/// antenna position) is too large for its covariance S. While fixes are rejected the window
/// dead-reckons and S grows, so a receiver that has jumped (multipath, a lost RTK or SBAS
/// correction, spoofing) and stays jumped longer than the window's error takes to grow to the
/// jump's size is eventually let in, and the fixes after the jump ends are then locked out in
/// their turn. A jump is a step in y between two fixes a fraction of a second apart, which the
/// vessel's motion (carried by the IMU, whose error over that time is far below a receiver's
/// noise) cannot make; a drifting estimate moves y slowly. This is the detection and estimation
/// of jumps from the innovation sequence (Willsky and Jones 1976, "A generalized likelihood ratio
/// approach to the detection and estimation of jumps in linear systems", IEEE TAC 21(1)), in the
/// simplest form a gate needs:
///  - when a rejection streak begins, its first fix's innovation y is compared with the last
///    accepted fix's y_a (no more than `max_gap_s` before): the difference is a step if
///    (y - y_a)^T (S + S_a)^-1 (y - y_a) is beyond the gate (S, S_a their innovation
///    covariances: without a jump both are draws of the same kind, and the accepted fix moved the
///    estimate by up to its innovation, large while the window converges after an outage);
///  - inside the streak every fix's innovation is compared with the previous fix's: with no fix
///    taken in between, their difference is the receivers' noise and what the estimate's error
///    grew by, covariance R + R_prev + (S - R) - (S_prev - R_prev) (the growth exact for a random
///    walk, an upper bound for an error growing smoothly, as a drifting heading's); a difference
///    beyond the gate that takes the jump back towards zero is subtracted from it (a step
///    further off is not added: the fixes are being rejected anyway, and a jump grown by every
///    later step would come to explain whatever the estimate drifts to);
///  - the steps add up to the jump still outstanding, o. A fix the gate passes is refused while
///    o is significant against the fixes' noise (o^T (2R)^-1 o beyond the gate) and explains the
///    fix better than no jump: (y - o)^T S^-1 (y - o) < y^T S^-1 y. When the receiver steps
///    back, o returns to about zero and fixes are taken again; if it never does, the window's
///    re-acquisition after `gnss.gate_max_reject_s` takes over, as without this test;
///  - a fix the gate passes while a significant jump is outstanding and that the jump does not
///    explain better (the estimate has drifted as far as the jump: an IMU that cannot bridge it)
///    is taken (or the streak outlasts `gnss.gate_max_reject_s` and the window re-acquires on a
///    jumped fix), and the window follows the jumped receiver from then on. That jump is
///    remembered as taken in, and a later streak opened by a step that undoes it (taken + step
///    inside the gate, against the covariance of both: the steps that made the jump and this one)
///    is the receiver coming back (`kBack`), not a jump of its own: the window's position is off
///    by the jump it followed, and it re-acquires on that fix at once (position only,
///    SlidingWindowEstimator::Reinitialize). The same step inside a streak that the window's own
///    drift opened (pulled by the jumped fixes it took, it can leave the gate before the receiver
///    steps back) is the receiver coming back as well (Observe).
/// A streak that does not begin with a step (the estimate drifting out of the gate, a single
/// outlier) has no jump outstanding for its whole length: it is the gate's alone.
///
/// A jump outstanding can also be taken into the state (`gnss.jump_as_drift_step`): once it has
/// explained the streak's fixes for a while (Step), the window steps its receiver drift by the
/// jump's estimate (gnss_drift_step_factor.h) and takes the fixes again (Absorbed). The estimate
/// is the streak's mean innovation over the fixes the jump explains, -mean(y) (y is predicted
/// minus measured), with covariance mean(S - R) + mean(R) / n: the estimate's own uncertainty,
/// which all of them share, and the receivers' noise averaged over n fixes (Willsky and Jones
/// 1976, sec. III: the jump's maximum-likelihood size over its window, and its covariance).
///
/// Innovations are in metres in the local level frame of the fix, so that receivers whose sigmas
/// change between fixes compare in the same units.

#include <Eigen/Core>

#include "skerry/core/time.h"

namespace skerry {

/// A fix's position innovation in metres (local level frame): y, its covariance S = H P H^T + R,
/// and the receiver's noise covariance R.
struct MetricInnovation {
  Eigen::Vector3d y = Eigen::Vector3d::Zero();
  Eigen::Matrix3d S = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  bool valid() const { return y.allFinite() && S.allFinite() && R.allFinite(); }
};

/// A jump outstanding, estimated over the fixes it explains (GnssJumpTest::Step): the receiver's
/// offset s (measured minus predicted, metres, local level frame) and its covariance.
struct JumpStep {
  Eigen::Vector3d step_m = Eigen::Vector3d::Zero();
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  int fixes = 0;  ///< how many fixes it rests on
};

/// How a rejection streak began (GnssJumpTest::StreakStarted).
enum class StreakStart {
  kNoStep,  ///< no step from the last accepted fix (or none to compare with): the gate's alone
  kJump,    ///< a step: a jump is outstanding
  kBack,    ///< a step that undoes a jump the window took in: the receiver is back
};

class GnssJumpTest {
 public:
  /// A fix was accepted: the reference for the next streak's first step; no jump outstanding (a
  /// jump still outstanding and significant, `gate` the chi-square bound, is remembered as taken
  /// in).
  void Accepted(TimeNs t_ns, const MetricInnovation& in, double gate);

  /// The first rejected fix of a streak, `gate` the chi-square bound: whether it stepped from the
  /// last accepted fix (no more than `max_gap_s` before), and whether that step undid a jump taken
  /// in (then forgotten).
  StreakStart StreakStarted(TimeNs t_ns, const MetricInnovation& in, double gate, double max_gap_s);

  /// A later fix of the same streak (before it is decided): adds its step from the previous fix
  /// of the streak, if it made one. True when that step undid a jump the window took in (then
  /// forgotten): the receiver is back, as StreakStart::kBack at a streak's start.
  bool Observe(TimeNs t_ns, const MetricInnovation& in, double gate);

  /// The jump outstanding as a step for the state, once it is significant and has explained at
  /// least `min_fixes` fixes of the streak over at least `min_s` seconds since the first of
  /// them; false otherwise.
  bool Step(TimeNs t_ns, int min_fixes, double min_s, double gate, JumpStep* step) const;

  /// The window took the jump outstanding into its state (Step) and accepted the fix at `t_ns`,
  /// whose innovation is now `in`: the streak is over, nothing is outstanding, and that fix is
  /// the reference for the next streak's first step. (The jump is in the state, not followed by
  /// the window's position: it is not remembered as taken in.)
  void Absorbed(TimeNs t_ns, const MetricInnovation& in);

  /// Whether a fix the gate passes (innovation `in`, in.y^T in.S^-1 in.y = d2) is better
  /// explained by the jump still outstanding. False when none is.
  bool Explains(const MetricInnovation& in, double d2, double gate) const;

  /// The window re-acquired on a fix of the streak (innovation `in`) and restarts around it: it
  /// follows the receiver from then on, so a jump still outstanding and significant is taken in;
  /// everything else is forgotten, as by Reset.
  void Reacquired(const MetricInnovation& in, double gate);

  /// Forget everything (the window restarted: old innovations say nothing of the receiver).
  void Reset();

  /// The jump outstanding in the current streak (zero when none), metres.
  const Eigen::Vector3d& outstanding_m() const { return outstanding_m_; }

  /// The jump the window took in and follows (zero when none), metres.
  const Eigen::Vector3d& taken_m() const { return taken_m_; }

 private:
  /// Whether `jump_m` is beyond the gate against two draws of the fix's noise.
  static bool Significant(const Eigen::Vector3d& jump_m, const MetricInnovation& in, double gate);
  /// The jump outstanding is taken in (added to the one the window follows).
  void TakeIn();
  /// Whether a step beyond the gate (`cov` its covariance) undoes the jump the window took in:
  /// the receiver is back, and the jump is forgotten.
  bool UndoesTaken(const Eigen::Vector3d& step, const Eigen::Matrix3d& cov, double gate);
  /// The streak is over at a fix taken at `t_ns` (innovation `in`): nothing outstanding, and the
  /// fix is the reference for the next streak's first step.
  void EndStreakAt(TimeNs t_ns, const MetricInnovation& in);
  /// Counts the fix into the jump's estimate if the jump outstanding explains it.
  void Tally(TimeNs t_ns, const MetricInnovation& in, double gate);

  TimeNs last_accepted_ns_ = -1;
  MetricInnovation last_accepted_;
  bool in_streak_ = false;
  MetricInnovation previous_;  ///< the previous fix of the streak
  Eigen::Vector3d outstanding_m_ = Eigen::Vector3d::Zero();
  Eigen::Matrix3d outstanding_cov_ = Eigen::Matrix3d::Zero();  ///< of the steps that made it
  Eigen::Vector3d taken_m_ = Eigen::Vector3d::Zero();          ///< a jump the window follows
  Eigen::Matrix3d taken_cov_ = Eigen::Matrix3d::Zero();
  // The fixes the jump outstanding explains, since it last changed: count, first time, sums of
  // y, S - R and R.
  int explained_ = 0;
  TimeNs explained_since_ns_ = 0;
  Eigen::Vector3d sum_y_ = Eigen::Vector3d::Zero();
  Eigen::Matrix3d sum_shared_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d sum_r_ = Eigen::Matrix3d::Zero();
};

}  // namespace skerry
