#pragma once
/// \file
/// The frontend seam: how any sensor beyond the IMU and GNSS puts residual blocks on the keyframe
/// states, in the sliding window and in the batch smoother alike.
///
/// A frontend (a camera matching the skyline against a DEM, a LiDAR matched against an aerial
/// image, an external pose matcher) owns its sensor data and its map. It registers a sensor
/// (SensorSpec: a name, a robust loss, a chi-square gate, optionally an extrinsic T_b_s) and hands
/// the estimator one SensorMeasurement per frame, scan or fix: a time and a Ceres cost function
/// whose residual is whitened (|r|^2 ~ chi-square with dim(r) degrees of freedom at the truth)
/// over the keyframe's blocks it names and, if the sensor has an extrinsic, q_b_s and p_b_s after
/// them. It never touches the states: the back end puts a keyframe at the measurement's time
/// (keyframe_policy.h), gates the whole block against the keyframe's predicted covariance before
/// it enters (innovation_gate.h), adds it with the sensor's loss, carries it into the
/// marginalisation prior when its keyframe leaves the window, and the batch builds the same
/// blocks over the whole run.
///
/// The cost may re-predict its measurement from the current estimate inside Evaluate (a skyline
/// slides over rounded terrain as the camera moves); it must be safe to evaluate from several
/// places (the gate, the window, the batch) and is shared by them.

#include <ceres/cost_function.h>

#include <Eigen/Geometry>
#include <functional>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "skerry/core/nav_state.h"
#include "skerry/core/time.h"
#include "skerry/factors/robust_loss.h"
#include "skerry/io/estimate_io.h"
#include "skerry/solvers/nav_graph.h"

namespace skerry {

struct SensorMeasurement;

/// A pose found by a sensor on its own (sensor_block.h SensorSpec::relocate).
struct Relocation {
  Eigen::Quaterniond q_w_b = Eigen::Quaterniond::Identity();
  Eigen::Vector3d p_w_b = Eigen::Vector3d::Zero();
  /// Covariance of (world rotation vector, position), rad and m.
  Eigen::Matrix<double, 6, 6> covariance = Eigen::Matrix<double, 6, 6>::Identity();
  std::string reason;  ///< for the log
};

/// What a sensor's gate tests (innovation_gate.h).
enum class GateSpace {
  /// The whole whitened residual, chi-square in dim(r) degrees of freedom: a fix, a skyline's
  /// samples, whose misfit at the truth is their noise.
  kResidual,
  /// Only the part of the residual that the keyframe's state can explain (its projection on the
  /// column space of the block's Jacobian), chi-square in the rank of that space: a dense
  /// registration (a LiDAR scan's thousands of distances to a map's edges), whose misfit at the
  /// truth is the scene's (edges in one source and not the other) and not noise, and whose
  /// residual is far too long for a dim(r)-square innovation covariance.
  kState,
};

/// A sensor as it registers: its name (summary.json counts its decisions under it), the robust
/// loss and gate of its blocks, and its mounting.
struct SensorSpec {
  std::string name;
  RobustLoss loss{LossType::kHuber, 3.0};
  /// Chi-square gate on the whole block's innovation at this probability; 0 turns it off.
  double gate_probability = 0.999;
  GateSpace gate_space = GateSpace::kResidual;
  /// The sensor's cost functions take q_b_s and p_b_s after the keyframe blocks.
  bool has_extrinsic = false;
  Eigen::Quaterniond q_b_s = Eigen::Quaterniond::Identity();  ///< sensor -> body rotation
  Eigen::Vector3d p_b_s = Eigen::Vector3d::Zero();            ///< sensor origin in body, m
  /// Estimate the extrinsic as a parameter block with a Gaussian prior at (q_b_s, p_b_s) of
  /// these sigmas (calibrate: in the configuration); otherwise it is held constant.
  bool calibrate = false;
  double extrinsic_prior_sigma_rad = 0.02;
  double extrinsic_prior_sigma_m = 0.1;
  /// One number of the sensor's own model that its cost functions take as a last parameter
  /// block of size 1, after the extrinsic's (a camera's coefficient of terrestrial refraction):
  /// constant at `parameter`, or, with `parameter_prior_sigma` > 0, estimated with the states
  /// under a Gaussian prior of that sigma at `parameter`: one value for the run, which the
  /// window carries in its marginalisation prior as it carries a calibrated extrinsic.
  bool has_parameter = false;
  double parameter = 0.0;
  double parameter_prior_sigma = 0.0;
  std::string parameter_name;  ///< what the parameter is, for the run's outputs
  /// Re-acquisition: after this many of the sensor's blocks in a row are rejected by the gate
  /// (0: never), the window has lost what the sensor sees. It restarts from its newest estimate
  /// with the covariance inflated so that the rejected block is a typical innovation (as GNSS
  /// re-acquisition does) and takes the block.
  int reacquire_after_rejections = 0;
  /// Before re-acquiring, the sensor may relocate the vessel from the rejected block's own data
  /// (a camera's global search around the estimate): the body pose it returns at the block's
  /// keyframe replaces the estimate's, with its covariance. nullopt: re-acquire without it.
  /// `after_rejections`: called after a rejected streak (the estimate may be overconfident), or
  /// because the estimate is uncertain (relocate_above_heading_sigma_rad).
  std::function<std::optional<Relocation>(const SensorMeasurement& block,
                                          const NavState& estimate,
                                          const StateCovariance& covariance,
                                          bool after_rejections)>
      relocate;
  /// A sensor whose residual has a narrow basin in heading (a skyline: about half a peak's
  /// width) cannot correct a heading far outside it, and its gate cannot tell: while the
  /// estimate's heading sigma is above this (rad; 0: never), a block is first relocated, and the
  /// relocated orientation (and position, where the sensor's is the better) replaces the
  /// estimate's before the block goes in.
  double relocate_above_heading_sigma_rad = 0.0;
  /// The same for position: while the estimate's horizontal position sigma (the larger axis) is
  /// above this (m; 0: never), a block is first relocated (a LiDAR's map alignment has a basin of
  /// a metre or two among a harbour's edges: a start from a drifting receiver lies outside it).
  double relocate_above_position_sigma_m = 0.0;
  /// A relocated position replaces the estimate's even while GNSS is accepted, where it is the
  /// better known (a map alignment to decimetres against a receiver drifting by metres); a
  /// camera's single-frame range is not, and leaves it to GNSS.
  bool relocate_position_over_gnss = false;
};

/// Who makes a block from its `prepare` (SensorMeasurement): the window, or the batch from its
/// initial values (the window's pass). A frontend may make the two differently: the LiDAR's
/// batch blocks take a redescending loss that the window's gate and relocation cannot live with
/// (docs/lidar_aerial.md).
enum class BlockConsumer { kWindow, kBatch };

/// What a block made at a state (SensorMeasurement::prepare) gives its consumer: the cost and,
/// when the block's weight depends on that state too, its gate scale.
struct PreparedBlock {
  PreparedBlock() = default;
  /// A cost whose gate scale is the measurement's own (implicit: `prepare` may return a cost).
  PreparedBlock(std::shared_ptr<ceres::CostFunction> c) : cost(std::move(c)) {}  // NOLINT
  PreparedBlock(std::shared_ptr<ceres::CostFunction> c, double scale)
      : cost(std::move(c)), gate_scale(scale) {}
  explicit operator bool() const { return cost != nullptr; }

  std::shared_ptr<ceres::CostFunction> cost;
  /// In (0, 1]: replaces SensorMeasurement::gate_scale; 0: the measurement's stands.
  double gate_scale = 0.0;
};

/// One measurement block: the residuals of one frame, scan or fix.
struct SensorMeasurement {
  SensorId sensor = 0;
  TimeNs t_ns = 0;
  /// Whitened residual; parameter blocks: the keyframe slots of `slots` in that order, then
  /// q_b_s and p_b_s when the sensor has an extrinsic.
  std::shared_ptr<ceres::CostFunction> cost;
  std::vector<Slot> slots;
  /// The cost's residual is the measurement's own whitened residual times this (0 < s <= 1): a
  /// block down-weighted because its errors are correlated with its neighbours' in time (a
  /// skyline frame against the same DEM a second later) carries part of its information, but
  /// its misfit is still its own noise. The gates (the window's before it enters, the batch's
  /// after a solve) test residual / s and Jacobian / s, so that a down-weighted block is judged
  /// by its own noise and not 1 / s^2 more loosely.
  double gate_scale = 1.0;
  /// Instead of `cost`: a block whose cost depends on the state it is made at (a LiDAR scan
  /// levelled with the estimated roll and pitch and deskewed with the estimated motion; a skyline
  /// frame whose weight depends on how far its crest moved since the previous frame). Each
  /// consumer calls it once, with the keyframe's state when the block reaches it (the window: the
  /// prediction, before the gate; the batch: its initial values) and the gyro there, and uses
  /// what it returns as `cost` from then on (and its gate_scale, when it gives one, as the
  /// block's); a null cost: the block cannot be used there (dropped).
  std::function<PreparedBlock(
      const NavState& at, const Eigen::Vector3d& gyro_rad_s, BlockConsumer consumer)>
      prepare;
};

enum class SensorDecision {
  kAccepted,
  kRejectedByGate,
  /// Never reached a keyframe: older than the window's newest keyframe when it came, before the
  /// estimator started, or the cost could not be evaluated there.
  kDropped,
};

/// The decision about one measurement, in the order they were given (per estimator).
struct SensorRecord {
  SensorId sensor = 0;
  TimeNs t_ns = 0;
  SensorDecision decision = SensorDecision::kDropped;
  int dim = 0;              ///< degrees of freedom of the gate (residual size, or rank: kState)
  double d2 = 0.0;          ///< gated innovation r^T S^-1 r (0 when not gated)
  bool reacquired = false;  ///< accepted on a re-acquisition (the window restarted on it)
};

/// Decisions per sensor, counted.
struct SensorStats {
  int accepted = 0;
  int rejected = 0;
  int dropped = 0;
  int reacquired = 0;  ///< accepted blocks that re-initialised the window (counted in accepted)
  /// Sum of d2 / dim over the accepted blocks: its mean is 1 when the predicted covariance and
  /// the sensor's noise match the errors.
  double nis_per_dof_sum_accepted = 0.0;

  SensorStats& operator+=(const SensorStats& a) {
    accepted += a.accepted;
    rejected += a.rejected;
    dropped += a.dropped;
    reacquired += a.reacquired;
    nis_per_dof_sum_accepted += a.nis_per_dof_sum_accepted;
    return *this;
  }
};

/// A frontend's own figures per block, by block time (a LiDAR scan's edge points and its
/// degeneracy), written beside the window's decision about each block (`skerry run`'s
/// blocks.csv). A NaN value is a figure the block does not have.
struct FrontendBlockTable {
  std::vector<std::string> columns;
  std::map<TimeNs, std::vector<double>> rows;  ///< one value per column
};

/// The sensors and blocks of a run: what a program hands RunWindow and the batch, and what they
/// hand back with the window's decision about each block (decisions[k] about measurements[k];
/// empty before a window has run). Ids are indices into `sensors`, as an estimator gives them when
/// the sensors register in this order; a frontend can register here as with an estimator.
struct SensorLog {
  std::vector<SensorSpec> sensors;
  std::vector<SensorMeasurement> measurements;
  std::vector<SensorRecord> decisions;
  /// Per sensor name: the frontend's own figures (frames read, frames skipped and why, time per
  /// frame), reported beside the estimator's decisions in summary.json.
  std::map<std::string, std::map<std::string, double>> frontend_stats;
  /// Per sensor name: figures a frontend gathers while the estimators run (blocks it makes at
  /// the estimate), read when a window run ends and merged into its frontend_stats.
  std::map<std::string, std::function<std::map<std::string, double>()>> live_frontend_stats;
  /// Per sensor name: the frontend's per-block figures, read when a window run ends.
  std::map<std::string, std::function<FrontendBlockTable()>> live_frontend_blocks;
  /// A first state a sensor found on its own (a camera's global search, init.mode skyline):
  /// RunWindow starts from it when it is given no initial state.
  std::optional<EstimateRecord> start;

  SensorId RegisterSensor(const SensorSpec& spec) {
    sensors.push_back(spec);
    return static_cast<SensorId>(sensors.size() - 1);
  }
};

/// The blocks of a measurement's cost in the graph: the keyframe's slots, then the extrinsic,
/// then the sensor's parameter.
std::vector<BlockRef> SensorBlocks(const SensorSpec& spec,
                                   const SensorMeasurement& m,
                                   KeyframeId keyframe);

/// Checks a measurement against its sensor: a cost (or a `prepare`), one parameter block per
/// slot (and two for an extrinsic, one for a sensor parameter) of the right sizes, and a time after
/// the sensor's previous one (`*last_t_ns`, advanced to it). std::invalid_argument naming the
/// sensor otherwise.
void CheckMeasurement(const SensorSpec& spec, const SensorMeasurement& m, TimeNs* last_t_ns);

/// Gives a block made with `prepare` its cost at `at` for `consumer` (checked as
/// CheckMeasurement does); a block with a cost is left alone. False when `prepare` returns
/// nullptr.
bool PrepareMeasurement(const SensorSpec& spec,
                        SensorMeasurement* m,
                        const NavState& at,
                        const Eigen::Vector3d& gyro_rad_s,
                        BlockConsumer consumer);

/// The blocks of `log` in time order (each sensor's are already; together they are merged by
/// time, ties in the order given), those after `t_end_ns` left out.
std::vector<const SensorMeasurement*> InTimeOrder(
    const SensorLog& log, TimeNs t_end_ns = std::numeric_limits<TimeNs>::max());

/// Adds a sensor's extrinsic to a graph: constant, or (calibrate) estimated with its prior: the
/// spec's mounting and sigmas, or `current` with `covariance` (6x6, rotation vector then
/// position) when given (a window restarting its graph keeps what it has learnt).
void AddSensorExtrinsic(NavGraph* graph,
                        SensorId id,
                        const SensorSpec& spec,
                        const Extrinsic* current = nullptr,
                        const Eigen::Matrix<double, 6, 6>* covariance = nullptr);

/// Adds a sensor's parameter to a graph (nothing when it has none): constant, or estimated with
/// its prior: the spec's value and sigma, or `current` and `variance` when given (a window
/// restarting its graph keeps what it has learnt).
void AddSensorParameter(NavGraph* graph,
                        SensorId id,
                        const SensorSpec& spec,
                        const double* current = nullptr,
                        const double* variance = nullptr);

}  // namespace skerry
