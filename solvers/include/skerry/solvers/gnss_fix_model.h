#pragma once
/// \file
/// How a GNSS fix enters the graph, written once for the sliding window and the batch smoother:
/// the keyframe it is tied to (the nearer one), its factors there, and what was decided about it.
///
/// A fix at t_fix tied to a keyframe at t_kf (|dt| = |t_fix - t_kf| <= half a keyframe period)
/// sees the keyframe's state moved to the fix time to first order: the position by v dt
/// (GnssPositionFactor), the attitude by the body's turn Exp(omega_b dt), applied to the lever
/// arm and the dual-antenna baseline, with omega_b the keyframe's gyro less its bias and less the
/// Earth's rate (the body's rate relative to the Earth-fixed world). The receiver's sigmas and
/// heading are taken in the local level frame at the fix (EarthModel::LocalLevel).

#include <ceres/cost_function.h>

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "skerry/core/earth_model.h"
#include "skerry/core/measurements.h"
#include "skerry/core/sensor_config.h"
#include "skerry/solvers/estimator_config.h"
#include "skerry/solvers/nav_graph.h"

namespace skerry {

/// A fix tied to a keyframe.
struct TiedFix {
  double dt_s = 0.0;                                      ///< t_fix - t_keyframe
  Eigen::Vector3d lever_arm_b = Eigen::Vector3d::Zero();  ///< antenna, turned by omega_b dt
  Eigen::Vector3d baseline_b = Eigen::Vector3d::UnitX();  ///< dual-antenna baseline, turned
  Eigen::Matrix3d R_n_w = Eigen::Matrix3d::Identity();    ///< local level at the fix
  Eigen::Vector3d sigma_enu_m = Eigen::Vector3d::Ones();  ///< receiver sigmas x sigma scale
};

TiedFix TieFix(const GnssFix& fix,
               const Keyframe& kf,
               const GnssConfig& gnss,
               const ImuConfig& imu,
               const EarthModel& earth,
               double sigma_scale);

/// The position factor (blocks GnssPositionBlocks) and the heading factor (block q; the fix must
/// have a heading) of a tied fix.
std::unique_ptr<ceres::CostFunction> GnssPositionCost(const GnssFix& fix, const TiedFix& tied);
std::vector<BlockRef> GnssPositionBlocks(KeyframeId id);
std::unique_ptr<ceres::CostFunction> GnssHeadingCost(const GnssFix& fix, const TiedFix& tied);

/// The wiring of a tied fix's factors into a graph, one path for the window and the batch: the
/// position factor on keyframe `id` with `config.gnss_loss`, and the heading factor with
/// `config.heading_loss`. Return the factors' ids.
FactorId AddGnssPositionFactor(NavGraph* graph,
                               const GnssFix& fix,
                               const TiedFix& tied,
                               KeyframeId id,
                               const EstimatorConfig& config);
FactorId AddGnssHeadingFactor(NavGraph* graph,
                              const GnssFix& fix,
                              const TiedFix& tied,
                              KeyframeId id,
                              const EstimatorConfig& config);

/// What happened to a GNSS fix's position.
enum class FixDecision { kAccepted, kRejectedByGate, kAcceptedOnReacquisition, kDropped };
/// ... and to its dual-antenna heading: kNone when it had none or headings are not used;
/// kLeftOut when the position was not accepted (a rejected, dropped or re-acquisition fix).
enum class HeadingDecision { kNone, kAccepted, kRejectedByGate, kLeftOut };

/// The decision about one fix, in the order the fixes were given to the estimator.
struct FixRecord {
  TimeNs t_ns = 0;
  FixDecision position = FixDecision::kAccepted;
  HeadingDecision heading = HeadingDecision::kNone;
  /// Accepted against a receiver drift that carries jumps taken in as steps and not yet stepped
  /// back (gnss.jump_as_drift_step): the fix is offset by them. The batch, which models no steps,
  /// leaves such fixes out.
  bool across_jump = false;
};

/// A fix never put into the graph (too late for its keyframe, before the start, or left to an
/// engine that stopped): its heading, if it had one that would have been used, is left out.
inline FixRecord DroppedFixRecord(const GnssFix& fix, bool use_gnss_heading) {
  return {fix.t_ns, FixDecision::kDropped,
          fix.has_heading && use_gnss_heading ? HeadingDecision::kLeftOut : HeadingDecision::kNone};
}

}  // namespace skerry
