#pragma once
/// \file
/// The factor graph shared by the sliding window and the batch smoother: keyframe states as Ceres
/// parameter blocks (q_w_b with ceres::EigenQuaternionManifold, p, v, bg, ba, and the GNSS position
/// bias gb), factors with stored
/// ResidualBlockIds, symmetric add/remove, marginalisation of the oldest keyframe by Schur
/// complement, and marginal covariances exploiting the chain structure (every factor touches one
/// keyframe or two consecutive ones, so the information matrix is block tridiagonal).
///
/// The graph's state per keyframe is 18-D: the 15-D tangent of nav_state.h followed by the GNSS
/// bias gb (3, m, ENU; gnss_drift_factor.h). Public estimates stay 15-D (the top-left block).
/// Without the drift model (NavGraph(false)) every gb block is constant at zero: it contributes
/// no Jacobian columns, gets a unit-information placeholder in the 18x18 algebra (decoupled, so
/// the 15x15 blocks are exactly those of a 15-D graph) and is reported with zero covariance.

#include <ceres/ceres.h>

#include <algorithm>
#include <atomic>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "skerry/core/nav_state.h"
#include "skerry/solvers/estimator_config.h"

namespace skerry {

using KeyframeId = std::int64_t;
using FactorId = std::int64_t;

enum class FactorKind {
  kStatePrior,
  kImu,
  kBiasRandomWalk,
  kGnssPosition,
  kGnssHeading,
  kMarginalPrior,
  kGnssDrift,
  kGnssDriftPrior,
  kSensor,          ///< a measurement block of a registered sensor (sensor_block.h)
  kExtrinsicPrior,  ///< the prior of a calibrated extrinsic or of an estimated sensor parameter
};

/// Parameter slots of a keyframe, in the tangent order of nav_state.h, then the GNSS bias; then
/// the two blocks of a sensor's extrinsic T_b_s (q_b_s [x,y,z,w] with EigenQuaternionManifold,
/// p_b_s in metres) and a sensor's parameter (one number of its own model, e.g. a camera's
/// refraction coefficient), which belong to a sensor rather than to a keyframe; and the IMU's
/// gyro calibration (its scale factors and misalignment, GyroCalibrationJacobians: 9 numbers for
/// the run), which belongs to the graph.
enum class Slot : int {
  kQ = 0,
  kP = 1,
  kV = 2,
  kBg = 3,
  kBa = 4,
  kGb = 5,
  kExtrinsicQ = 6,
  kExtrinsicP = 7,
  kSensorParameter = 8,
  kImuCalibration = 9
};
constexpr int kNumSlots = 6;  ///< slots per keyframe

/// A sensor registered with the estimator (sensor_block.h): an index, the same in every engine.
using SensorId = int;

/// Tangent dimension of a keyframe inside the graph, and the offset of gb in it.
constexpr int kGraphStateDim = 18;
constexpr int kGraphGb = 15;
/// Offset of a slot's tangent in the keyframe's 18-D tangent.
constexpr int SlotTangentOffset(Slot s) { return 3 * static_cast<int>(s); }
/// Covariance in the graph's 18-D tangent order (the top-left 15x15 is a StateCovariance).
using GraphCovariance = Eigen::Matrix<double, kGraphStateDim, kGraphStateDim>;

struct Keyframe {
  KeyframeId id = 0;
  TimeNs t_ns = 0;
  double q[4] = {0, 0, 0, 1};
  double p[3] = {0, 0, 0};
  double v[3] = {0, 0, 0};
  double bg[3] = {0, 0, 0};
  double ba[3] = {0, 0, 0};
  double gb[3] = {0, 0, 0};                              ///< GNSS position bias, m, ENU
  Eigen::Vector3d gyro_rad_s = Eigen::Vector3d::Zero();  ///< raw gyro at t (lever-arm velocity)
  bool has_first_estimate = false;
  double fe[19] = {};  ///< first estimate of q,p,v,bg,ba,gb (FEJ)

  double* block(Slot s);
  const double* block(Slot s) const;
  NavState state() const;
  void set_state(const NavState& s);
  Eigen::Vector3d gnss_bias() const { return Eigen::Vector3d(gb[0], gb[1], gb[2]); }
};

/// A parameter block of the graph: a keyframe's slot, or (slot kExtrinsicQ / kExtrinsicP /
/// kSensorParameter) the extrinsic or the parameter of the sensor whose SensorId is in
/// `keyframe`.
struct BlockRef {
  KeyframeId keyframe;
  Slot slot;
};

inline bool IsExtrinsic(Slot s) { return s == Slot::kExtrinsicQ || s == Slot::kExtrinsicP; }
/// A block of a sensor's (its extrinsic or its parameter) or the IMU's calibration: not of a
/// keyframe (the arrow beside the chain when estimated).
inline bool IsSensorBlock(Slot s) {
  return IsExtrinsic(s) || s == Slot::kSensorParameter || s == Slot::kImuCalibration;
}
/// Numbers in the IMU's calibration block: the gyro's E, column-major (GyroCalibrationJacobians).
constexpr int kImuCalibrationSize = 9;
/// The ambient size of a slot's parameter block: 4 for the quaternions, 1 for a sensor's
/// parameter, 9 for the IMU's calibration, 3 otherwise.
constexpr int SlotSize(Slot s) {
  return s == Slot::kQ || s == Slot::kExtrinsicQ
             ? 4
             : (s == Slot::kSensorParameter
                    ? 1
                    : (s == Slot::kImuCalibration ? kImuCalibrationSize : 3));
}
/// The block of the IMU's calibration (one per graph).
inline BlockRef ImuCalibrationBlock() { return {0, Slot::kImuCalibration}; }
/// The two blocks of a sensor's extrinsic, q_b_s then p_b_s.
inline std::vector<BlockRef> ExtrinsicBlocks(SensorId sensor) {
  return {{sensor, Slot::kExtrinsicQ}, {sensor, Slot::kExtrinsicP}};
}
/// The block of a sensor's parameter.
inline BlockRef SensorParameterBlock(SensorId sensor) { return {sensor, Slot::kSensorParameter}; }

/// A number of a sensor's own model in the graph (a camera's refraction coefficient): constant,
/// or estimated with the states (its prior a factor the caller adds, as a calibrated extrinsic's).
struct SensorParameter {
  double value[1] = {0.0};
  bool estimated = false;
  bool has_first_estimate = false;
  double fe[1] = {0.0};  ///< first estimate (FEJ)
};

/// The IMU's gyro calibration in the graph (the 9 numbers of E, GyroCalibrationJacobians):
/// estimated with the states under a prior the caller adds, as a calibrated extrinsic's.
struct ImuCalibration {
  double value[kImuCalibrationSize] = {};
  bool has_first_estimate = false;
  double fe[kImuCalibrationSize] = {};  ///< first estimate (FEJ)
};

/// A sensor's extrinsic T_b_s in the graph: constant, or estimated (calibrated) with a prior.
struct Extrinsic {
  double q[4] = {0, 0, 0, 1};  ///< q_b_s, Eigen order
  double p[3] = {0, 0, 0};     ///< p_b_s, m
  bool estimated = false;
  bool has_first_estimate = false;
  double fe[7] = {};  ///< first estimate of q, p (FEJ)

  Eigen::Quaterniond q_b_s() const {
    return Eigen::Quaterniond(Eigen::Map<const Eigen::Vector4d>(q)).normalized();
  }
  Eigen::Vector3d p_b_s() const { return Eigen::Map<const Eigen::Vector3d>(p); }
};

class NavGraph {
 public:
  /// `estimate_gnss_bias`: false keeps every gb block constant at zero.
  explicit NavGraph(bool estimate_gnss_bias = false);
  ~NavGraph();
  NavGraph(const NavGraph&) = delete;
  NavGraph& operator=(const NavGraph&) = delete;

  /// Adds a keyframe after the newest one (ids increase with time).
  Keyframe& AddKeyframe(const NavState& initial, const Eigen::Vector3d& gyro_rad_s);
  FactorId AddFactor(FactorKind kind,
                     std::unique_ptr<ceres::CostFunction> cost,
                     std::unique_ptr<ceres::LossFunction> loss,
                     const std::vector<BlockRef>& blocks);
  /// The same with a cost function shared with its owner (a sensor's measurement block, which
  /// the gate, the window and the batch all evaluate).
  FactorId AddSharedFactor(FactorKind kind,
                           std::shared_ptr<ceres::CostFunction> cost,
                           std::unique_ptr<ceres::LossFunction> loss,
                           const std::vector<BlockRef>& blocks);

  /// Adds a sensor's extrinsic blocks (constant unless `estimated`: then a calibrated extrinsic,
  /// whose prior the caller adds as a kExtrinsicPrior factor). Once per sensor.
  void AddExtrinsic(SensorId sensor,
                    const Eigen::Quaterniond& q_b_s,
                    const Eigen::Vector3d& p_b_s,
                    bool estimated);
  bool has_extrinsic(SensorId sensor) const { return extrinsics_.count(sensor) > 0; }
  const Extrinsic& extrinsic(SensorId sensor) const { return *extrinsics_.at(sensor); }
  /// Marginal covariance of an estimated extrinsic (6x6: rotation vector, then position) at the
  /// current estimate, from the chain's information with the extrinsic's arrow (other sensors'
  /// extrinsics held fixed). False when the extrinsic is constant or the information singular.
  bool ExtrinsicCovariance(SensorId sensor, Eigen::Matrix<double, 6, 6>* covariance) const;
  /// Adds a sensor's parameter block (constant unless `estimated`; then its prior is a factor the
  /// caller adds). Once per sensor.
  void AddSensorParameter(SensorId sensor, double value, bool estimated);
  bool has_sensor_parameter(SensorId sensor) const { return parameters_.count(sensor) > 0; }
  const SensorParameter& sensor_parameter(SensorId sensor) const { return *parameters_.at(sensor); }
  /// Marginal variance of an estimated sensor parameter at the current estimate, as
  /// ExtrinsicCovariance (the other sensors' blocks held fixed). False when it is constant or
  /// the information singular.
  bool SensorParameterVariance(SensorId sensor, double* variance) const;
  /// Adds the IMU's calibration block (ImuCalibrationBlock), estimated with the states from
  /// `value`; its prior is a kExtrinsicPrior factor the caller adds. Once per graph; the IMU
  /// factors that take it are calibrated ones (ImuFactor::CreateCalibrated).
  void AddImuCalibration(const Eigen::Matrix<double, kImuCalibrationSize, 1>& value);
  bool has_imu_calibration() const { return imu_calibration_ != nullptr; }
  const ImuCalibration& imu_calibration() const { return *imu_calibration_; }
  /// Marginal covariance of the IMU's calibration at the current estimate, as
  /// ExtrinsicCovariance. False without one or when the information is singular.
  bool ImuCalibrationCovariance(
      Eigen::Matrix<double, kImuCalibrationSize, kImuCalibrationSize>* covariance) const;
  /// The value of any block (keyframe slot, extrinsic, sensor parameter, IMU calibration).
  const double* BlockValue(const BlockRef& ref) const;
  void RemoveFactor(FactorId id);

  /// Solves with Ceres, or with `config.linear_solver` "chain" by SolveChain.
  ceres::Solver::Summary Solve(const CeresConfig& config);
  /// Levenberg-Marquardt as Ceres' (the same damping on the Jacobi-scaled normal equations, the
  /// same radius updates, step acceptance and tolerances) with the damped normal equations of
  /// the keyframe chain solved by block elimination (block_tridiagonal.h) instead of a general
  /// sparse Cholesky: no symbolic analysis, no compressed-row assembly, the information
  /// assembled keyframe by keyframe as the elimination consumes it: memory of one 18x18 block
  /// per keyframe (the elimination's gain). Quaternions take skerry's left full-angle perturbation
  /// (factor_linearization.h); robust losses enter by their sqrt(rho') weight (iteratively
  /// reweighted Gauss-Newton: the same gradient and stationary points as Ceres' corrector).
  /// The estimated extrinsics and sensor parameters, which every keyframe may touch, are an
  /// arrow beside the chain, eliminated last (BlockTridiagonalSolver's arrow; 18 x m more per
  /// keyframe for m arrow columns). Needs every factor on one keyframe or two consecutive ones,
  /// sensor blocks aside (std::logic_error otherwise). The summary holds what StepsTried,
  /// BriefReport and IsSolutionUsable read.
  ///
  /// `decide` (may be empty), a caller's outlier gate run inside the iterations instead of
  /// after the solve: it may add and remove factors on the chain's keyframes and returns how
  /// many decisions it changed. It is called at every iterate the last accepted step lowered the
  /// cost by less than kDecideBelowRelativeDecrease of it, before that iterate's linearisation,
  /// and at an iterate where the solve would stop as converged unless it was just called there;
  /// when it changes something, the iterations go on with the new factors from that iterate
  /// (the cost is taken anew, the trust region kept). A solve thus never ends at an iterate the
  /// gate has not seen, unless `decide` stops changing anything by itself (its own round cap),
  /// and a decision does not cost a linearisation of its own: each one after a converged solve
  /// did (two of the eight linearisations of the hour at sea's batch).
  ceres::Solver::Summary SolveChain(const CeresConfig& config,
                                    const std::function<int()>& decide = {});
  /// SolveChain's threshold for calling its `decide`: a step that lowered the cost by less than
  /// this share of it leaves an iterate near enough to the optimum to judge outliers at.
  static constexpr double kDecideBelowRelativeDecrease = 1e-3;
  /// 1/2 sum rho(|r|^2) over every factor at the current estimate (Ceres' cost); false when a
  /// cost function fails. With `threads` > 1 and 512 factors or more they are evaluated on that
  /// many threads and summed in the same order, so the cost is the same to the last bit.
  bool Cost(double* cost, int threads = 1) const;
  /// While `*stop` is set (may be null: never), a solve ends at its next iteration with the
  /// iterate it has (Ceres' USER_SUCCESS): how a batch solve is interrupted by SIGINT.
  void set_stop(const std::atomic<bool>* stop) { stop_ = stop; }
  bool stopped() const { return stop_ != nullptr && stop_->load(std::memory_order_relaxed); }

  /// Marginalises the oldest keyframe into a LinearPriorFactor on the next one (and on the
  /// estimated extrinsics its factors touch) and removes it.
  void MarginalizeOldest(bool first_estimate_jacobians);

  /// Marginal covariance of the newest keyframe (18x18 graph order, or its 15x15 block). The
  /// chain recursion below is conditional on the sensors' blocks (an estimated extrinsic or
  /// parameter held at its estimate); their own uncertainty is then added through the arrow
  /// (ArrowMarginals), so these and AllCovariances' are the full marginals. ExtrinsicCovariance
  /// and SensorParameterVariance give the sensor blocks' own.
  bool NewestCovariance(GraphCovariance* covariance) const;
  bool NewestCovariance(StateCovariance* covariance) const;
  /// Marginal covariances of every keyframe, oldest first (block-tridiagonal recursion, in
  /// segments: the memory of 4096 keyframes' blocks, not of the run's).
  bool AllCovariances(std::vector<GraphCovariance>* covariances) const;
  bool AllCovariances(std::vector<StateCovariance>* covariances) const;
  /// The same, each keyframe's 15x15 block handed to `each` (index, covariance), once per
  /// keyframe in no promised order (newest first today): the batch writes them into its records,
  /// no second copy of a whole run's covariances.
  bool AllCovariances(const std::function<void(size_t, const StateCovariance&)>& each) const;
  /// The estimated sensor blocks' joint marginal covariance (extrinsics, sensor parameters, the
  /// IMU's calibration: the arrow beside the chain), which AllCovariances' pass finds before it
  /// hands out the keyframes' (their Sigma_ee). Unlike ExtrinsicCovariance and its kin it holds
  /// no sensor block fixed: with one estimated block the two agree; with several this is the
  /// marginal a Ceres covariance of the whole problem gives.
  struct SensorBlocksCovariance {
    std::vector<BlockRef> blocks;  ///< in the order of their tangents
    std::vector<int> col;          ///< the first column of each
    Eigen::MatrixXd covariance;    ///< empty when the pass did not find it
    /// The marginal of `refs` (adjacent tangents, in order: an extrinsic's rotation and
    /// position), false when one of them is not among `blocks` or the covariance is empty.
    bool Of(const std::vector<BlockRef>& refs, Eigen::MatrixXd* marginal) const;
  };
  /// AllCovariances' `each` form that also fills `*sensor_blocks` (when not null) on the way.
  bool AllCovariances(const std::function<void(size_t, const StateCovariance&)>& each,
                      SensorBlocksCovariance* sensor_blocks) const;
  /// Keyframes per segment of AllCovariances (4096 by default: 21 MB; at least 1). Shorter
  /// segments hold less and linearise the chain twice once a run is longer than one segment.
  void set_covariance_segment(size_t keyframes) {
    covariance_segment_ = std::max<size_t>(1, keyframes);
  }
  /// How AllCovariances eliminates the chain: the square-root form (kSquareRoot, the default:
  /// positive semi-definite by construction, with the conditioning of the Jacobian), or the
  /// information form (kInformation: 1.3-1.4x faster, falling back to the square-root form when
  /// a pivot comes out indefinite; for comparisons). The information form's subtraction can
  /// cancel without any pivot turning indefinite: a consumer-grade IMU 60 s into an outage that
  /// lasts to the run's end gets 31x the vertical variance
  /// (NavGraphTest.CovariancesStayPositiveThroughALongOutage).
  enum class CovarianceForm { kInformation, kSquareRoot };
  void set_covariance_form(CovarianceForm form) { covariance_form_ = form; }

  /// Covariance of `next` given a covariance of `prev` and the factors that touch `next` and no
  /// keyframe other than `prev` (those between the two and those on `next` alone): cheap
  /// propagation for keyframes that got no new measurement.
  bool PropagateCovariance(KeyframeId prev,
                           KeyframeId next,
                           const GraphCovariance& prev_covariance,
                           GraphCovariance* next_covariance) const;

  bool estimates_gnss_bias() const { return estimate_gnss_bias_; }

  size_t num_keyframes() const { return keyframes_.size(); }
  size_t num_factors() const { return factors_.size(); }
  const Keyframe& oldest() const { return *keyframes_.begin()->second; }
  const Keyframe& newest() const { return *keyframes_.rbegin()->second; }
  Keyframe& newest() { return *keyframes_.rbegin()->second; }
  const Keyframe& keyframe(KeyframeId id) const { return *keyframes_by_index_[IndexOf(id)]; }
  std::vector<KeyframeId> keyframe_ids() const;
  /// Whitened residual of a factor at the current estimate (before robust loss).
  Eigen::VectorXd FactorResidual(FactorId id) const;
  FactorKind factor_kind(FactorId id) const;
  /// The cost function of a factor (for inspection).
  const ceres::CostFunction& cost_function(FactorId id) const;
  std::vector<FactorId> factor_ids(FactorKind kind) const;

 private:
  struct Factor;
  struct Linearized;
  double* BlockPtr(const BlockRef& ref);
  /// The block's first estimate with FEJ when it has one, else its value.
  const double* LinearizationPoint(const BlockRef& ref, bool fej) const;
  bool LinearizeFactor(const Factor& f, bool fej, Linearized* out) const;
  /// Every factor on the chain by the position of the oldest keyframe it touches (factors on
  /// extrinsics alone are left out): factors[start[k] .. start[k+1]) have position k.
  struct ChainIndex {
    std::vector<size_t> start;
    std::vector<const Factor*> factors;
  };
  ChainIndex IndexChain() const;
  /// Every factor in the order Cost adds their terms (the order of their ids).
  std::vector<const Factor*> FactorsInOrder() const;
  /// Cost over `factors` (FactorsInOrder of the graph as it stands): what a solve, whose factors
  /// do not change, lists once instead of on every evaluation.
  bool CostOf(const std::vector<const Factor*>& factors, double* cost, int threads) const;
  /// The estimated sensor blocks as an arrow beside the chain: the blocks in a fixed order, each
  /// with its first column among the arrow's tangents.
  struct Arrow {
    std::vector<BlockRef> blocks;
    std::vector<int> col;
    int dim = 0;
    /// The factors on arrow blocks alone (their priors), which the chain index leaves out.
    std::vector<const Factor*> own_factors;
    /// The column of `b`, -1 when it is not in the arrow.
    int ColumnOf(const BlockRef& b) const;
    /// Appends a block, its tangent after the others'.
    void Add(const BlockRef& b);
  };
  /// The chain's information keyframe by keyframe: linearises the factors whose oldest keyframe
  /// is k and adds them in. On entry `*D` (and `*g`) hold the share of keyframe k that k-1's
  /// factors left; on return they are D_k (and g_k) complete, `*O` is O_k (coupling k to k+1)
  /// and `*D_next` (and `*g_next`) k+1's share so far. `g` and `g_next` may be null. With
  /// `arrow`, the arrow's share too (AddArrowInformation): into C (keyframe k's rows, partly
  /// filled by k-1's factors) and C_next (k+1's), E and g_e. `linearized`: keyframe k's factors
  /// already linearised, in their chain order (LinearizeChainFactors: the sensor blocks among
  /// them); null, and the other factors: each is linearised here into `*L`.
  bool AssembleChainStep(const ChainIndex& chain,
                         size_t k,
                         Linearized* L,
                         GraphCovariance* D,
                         GraphCovariance* O,
                         GraphCovariance* D_next,
                         Eigen::Matrix<double, kGraphStateDim, 1>* g,
                         Eigen::Matrix<double, kGraphStateDim, 1>* g_next,
                         const Arrow* arrow = nullptr,
                         Eigen::Matrix<double, kGraphStateDim, Eigen::Dynamic>* C = nullptr,
                         Eigen::Matrix<double, kGraphStateDim, Eigen::Dynamic>* C_next = nullptr,
                         Eigen::MatrixXd* E = nullptr,
                         Eigen::VectorXd* g_e = nullptr,
                         const Linearized* linearized = nullptr) const;
  /// Linearises the sensor blocks (FactorKind::kSensor) among chain.factors[first, last) into
  /// out[i - first] on `threads` threads (LinearizeFactor without FEJ, each once); false when a
  /// cost function fails.
  bool LinearizeChainFactors(const ChainIndex& chain,
                             size_t first,
                             size_t last,
                             int threads,
                             std::vector<Linearized>* out) const;
  Arrow EstimatedSensorBlocks() const;
  /// Fills `arrow->own_factors`: the factors on sensor blocks alone (no keyframe) that touch one
  /// of its blocks, in id order.
  void CollectOwnFactors(Arrow* arrow) const;
  /// Adds the arrow's share of a linearised factor whose oldest keyframe has position `lo` (or
  /// none: a factor on arrow blocks alone, C_lo and C_hi unused): J_c^T J_e to C_lo / C_hi (the
  /// keyframes' rows), J_e^T J_e to E, J_e^T r to g_e.
  void AddArrowInformation(const Factor& f,
                           const Linearized& L,
                           size_t lo,
                           const Arrow& arrow,
                           Eigen::Matrix<double, kGraphStateDim, Eigen::Dynamic>* C_lo,
                           Eigen::Matrix<double, kGraphStateDim, Eigen::Dynamic>* C_hi,
                           Eigen::MatrixXd* E,
                           Eigen::VectorXd* g_e) const;
  /// Adds a linearised factor whose oldest keyframe has position `lo`: its J^T J blocks on that
  /// keyframe to `*D_lo`, on the next to `*D_hi`, between them to `*O` (upper block), and J^T r to
  /// `*g_lo`, `*g_hi`. D_hi, O and g_hi may be null for a factor on one keyframe; g_lo null: no
  /// gradient.
  void AddFactorInformation(const Factor& f,
                            const Linearized& L,
                            size_t lo,
                            GraphCovariance* D_lo,
                            GraphCovariance* D_hi,
                            GraphCovariance* O,
                            Eigen::Matrix<double, kGraphStateDim, 1>* g_lo,
                            Eigen::Matrix<double, kGraphStateDim, 1>* g_hi) const;
  /// Every keyframe's marginal covariance (18x18) handed to `each`, newest first. With `arrow`
  /// (estimated sensor blocks), the full marginals: the arrow is eliminated after the chain.
  /// The square-root form instead when it is configured, or when a pivot or the arrow's Schur
  /// complement comes out indefinite (found before any covariance is handed out).
  /// `sigma_ee` (may be null): the arrow's joint marginal, as found before the first covariance
  /// is handed out.
  bool ForEachCovariance(const std::function<void(size_t, const GraphCovariance&)>& each,
                         const Arrow* arrow = nullptr,
                         Eigen::MatrixXd* sigma_ee = nullptr) const;
  /// The same by square-root (QR) elimination: positive semi-definite by construction.
  /// With `arrow` (estimated sensor blocks), the full marginals: its columns ride along.
  bool ForEachCovarianceSqrt(const std::function<void(size_t, const GraphCovariance&)>& each,
                             const Arrow* arrow = nullptr,
                             Eigen::MatrixXd* sigma_ee = nullptr) const;
  /// The whole chain's block-tridiagonal information and the arrow of the sensor blocks in
  /// `arrow` (AddFactorInformation and AddArrowInformation over every factor): C[k] = J_k^T J_e
  /// per keyframe, E = J_e^T J_e; the sensor blocks not in `arrow` held fixed.
  bool BuildChain(std::vector<GraphCovariance>* D,
                  std::vector<GraphCovariance>* O,
                  const Arrow& arrow,
                  std::vector<Eigen::Matrix<double, kGraphStateDim, Eigen::Dynamic>>* C,
                  Eigen::MatrixXd* E) const;
  /// The marginal covariance of the sensor blocks `arrow` (tangents in order) from the chain's
  /// information with their arrow; false when singular.
  bool ArrowCovariance(const std::vector<BlockRef>& arrow, Eigen::MatrixXd* covariance) const;
  /// The newest keyframe's covariance from a square-root pass along the chain, with the
  /// arrow's columns carried through it: its full marginal with `arrow` the estimated sensor
  /// blocks, conditional on them with an empty one. False when the pass cannot give it (with an
  /// arrow, also when a keyframe inside the window is not determined on its own).
  bool NewestSqrtCovariance(const Arrow& arrow, GraphCovariance* covariance) const;
  /// Which keyframes' share of the arrow's uncertainty ArrowMarginals gives.
  enum class ArrowSpan { kNewest, kAll };
  /// ArrowCovariance, and for the keyframes of `span` (the newest, or all oldest first) U_k with
  /// U_k U_k^T what the arrow's uncertainty adds to keyframe k's covariance conditional on it:
  /// the full marginal is H_cc^-1 + (H_cc^-1 H_ce) Sigma_e (H_cc^-1 H_ce)^T (the inverse of a
  /// bordered matrix by its Schur complement). kAll holds the whole chain's information once.
  bool ArrowMarginals(const std::vector<BlockRef>& arrow,
                      ArrowSpan span,
                      Eigen::MatrixXd* covariance,
                      std::vector<Eigen::Matrix<double, kGraphStateDim, Eigen::Dynamic>>* U) const;
  /// With estimated sensor blocks: hands `add` each U_k of ArrowMarginals over the estimated
  /// ones (nothing without them, or when their marginal is not positive definite).
  void AddArrowUncertainty(
      ArrowSpan span,
      const std::function<
          void(size_t, const Eigen::Matrix<double, kGraphStateDim, Eigen::Dynamic>&)>& add) const;
  /// ForEachCovariance with the estimated sensor blocks' uncertainty added (AddArrowUncertainty).
  /// `sensor_blocks` (may be null) as AllCovariances'.
  bool ForEachMarginal(const std::function<void(size_t, const GraphCovariance&)>& each,
                       SensorBlocksCovariance* sensor_blocks = nullptr) const;
  /// Adds the tangent Jacobian of `L` to `J` (columns: keyframe `first` at 0, `second` at
  /// kGraphStateDim); constant gb blocks contribute nothing.
  void ScatterJacobian(const Factor& f,
                       const Linearized& L,
                       KeyframeId first,
                       KeyframeId second,
                       Eigen::MatrixXd* J) const;
  /// The whitened rows of `f` on [first | second | arrow] (2 kGraphStateDim + arrow.dim
  /// columns): ScatterJacobian's, none when `first` is null (a prior on sensor blocks alone),
  /// then the arrow's blocks at their columns; sensor blocks outside the arrow held fixed.
  Eigen::MatrixXd ScatterWithArrow(const Factor& f,
                                   const Linearized& L,
                                   const KeyframeId* first,
                                   const KeyframeId* second,
                                   const Arrow& arrow) const;

  // The Ceres problem mirrors the graph only once a solve needs Ceres (the window, or the batch
  // with another linear solver): built from the graph then, kept in step after. The batch's chain
  // solver never builds it (2.4 kB of parameter and residual bookkeeping per keyframe saved).
  ceres::Problem& CeresProblem();
  void MirrorKeyframe(const Keyframe& kf);
  void MirrorExtrinsic(Extrinsic* e);
  void MirrorSensorParameter(SensorParameter* s);
  void MirrorFactor(Factor* f);

  bool estimate_gnss_bias_ = false;
  const std::atomic<bool>* stop_ = nullptr;
  size_t covariance_segment_ = 4096;
  CovarianceForm covariance_form_ = CovarianceForm::kSquareRoot;

  std::map<KeyframeId, std::unique_ptr<Keyframe>> keyframes_;
  // The same keyframes by position, oldest first: ids are consecutive (only the oldest is ever
  // removed), so a keyframe is found in O(1) (the chain's linearisation looks one up per block
  // of every factor; the map's lookups were a tenth of a batch iteration).
  std::deque<Keyframe*> keyframes_by_index_;
  // Position of keyframe `id` in keyframes_by_index_; std::out_of_range for an id not in the
  // graph (the one check for BlockValue, keyframe() and the chain's columns).
  size_t IndexOf(KeyframeId id) const {
    const size_t k = keyframes_by_index_.empty()
                         ? SIZE_MAX
                         : static_cast<size_t>(id - keyframes_by_index_.front()->id);
    if (k >= keyframes_by_index_.size()) {
      throw std::out_of_range("NavGraph: keyframe " + std::to_string(id) + " is not in the graph");
    }
    return k;
  }
  std::map<SensorId, std::unique_ptr<Extrinsic>> extrinsics_;
  std::map<SensorId, std::unique_ptr<SensorParameter>> parameters_;
  std::unique_ptr<ImuCalibration> imu_calibration_;
  std::map<FactorId, std::unique_ptr<Factor>> factors_;
  std::unique_ptr<ceres::Problem> problem_;
  std::unique_ptr<ceres::Manifold> quaternion_manifold_;
  KeyframeId next_keyframe_id_ = 0;
  FactorId next_factor_id_ = 0;
};

/// Iterations of a solve that tried a step: Ceres' Summary::iterations also holds its iteration
/// 0, the evaluation at the starting point.
inline int StepsTried(const ceres::Solver::Summary& summary) {
  return summary.iterations.empty() ? 0 : static_cast<int>(summary.iterations.size()) - 1;
}

/// Ceres solver options from a validated CeresConfig (throws std::invalid_argument on bad names).
ceres::Solver::Options MakeSolverOptions(const CeresConfig& config);

}  // namespace skerry
