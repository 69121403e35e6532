#include "skerry/solvers/nav_graph.h"

#include <spdlog/spdlog.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/QR>
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <future>
#include <stdexcept>
#include <utility>

#include "skerry/core/parallel_for.h"
#include "skerry/core/so3.h"
#include "skerry/factors/factor_linearization.h"
#include "skerry/factors/linear_prior_factor.h"
#include "skerry/solvers/block_tridiagonal.h"
#include "skerry/solvers/householder_triangularize.h"

namespace skerry {

namespace {
constexpr int kSlotOffset[kNumSlots + 2] = {0, 4, 7, 10, 13, 16, 0, 4};  // in Keyframe/Extrinsic fe
constexpr int kSlotTangent[kNumSlots] = {0, 3, 6, 9, 12, kGraphGb};      // in the 18-D tangent
constexpr int kExtrinsicDim = 6;  // tangent of an extrinsic: rotation, then position
bool IsQuaternion(Slot s) { return s == Slot::kQ || s == Slot::kExtrinsicQ; }
static_assert(SlotTangentOffset(Slot::kGb) == kGraphGb && SlotTangentOffset(Slot::kBa) == kBa);
constexpr int kN = kGraphStateDim;
using Mat = GraphCovariance;
using Mat2 = Eigen::Matrix<double, 2 * kN, 2 * kN>;
using Vec2 = Eigen::Matrix<double, 2 * kN, 1>;
using Vec = Eigen::Matrix<double, kN, 1>;

// The first tangent column of `b` among `blocks` (their columns `col`), -1 when it is not there:
// the arrow's lookup (Arrow::ColumnOf) and its covariance's (SensorBlocksCovariance::Of).
int ColumnAmong(const std::vector<BlockRef>& blocks,
                const std::vector<int>& col,
                const BlockRef& b) {
  for (size_t a = 0; a < blocks.size(); ++a) {
    if (blocks[a].slot == b.slot && blocks[a].keyframe == b.keyframe) return col[a];
  }
  return -1;
}

// x (-) x0 for one slot in skerry's tangent convention.
Eigen::VectorXd SlotMinus(Slot slot, const double* x, const double* x0) {
  if (IsQuaternion(slot)) {
    const Eigen::Map<const Eigen::Quaterniond> q(x), q0(x0);
    return LogQ<double>(q * q0.conjugate());
  }
  const int n = SlotSize(slot);
  return Eigen::Map<const Eigen::VectorXd>(x, n) - Eigen::Map<const Eigen::VectorXd>(x0, n);
}

// Jacobi scaling D = diag(sqrt(A_ii)) of a symmetric positive (semi-)definite matrix, 1 where a
// diagonal entry is not positive. The information of a navigation-grade IMU's bias states is
// ~1e20 next to ~1e2 for position: factorised in raw units, double precision keeps nothing of
// the weak directions (an LDLT pivot of 1e20 leaves an absolute error of ~1e4 in the rest);
// D^-1 A D^-1 has a unit diagonal and only the conditioning of the correlations.
template <typename Matrix>
Eigen::Matrix<double, Matrix::RowsAtCompileTime, 1> JacobiScale(const Matrix& A) {
  Eigen::Matrix<double, Matrix::RowsAtCompileTime, 1> d = A.diagonal();
  for (int i = 0; i < d.size(); ++i) d[i] = d[i] > 0.0 ? std::sqrt(d[i]) : 1.0;
  return d;
}

// Inverse of a symmetric positive (semi-)definite block, Jacobi-scaled (above), regularised by
// 1e-12 of the unit diagonal when the factorisation is not positive.
Mat InverseSpd(const Mat& A, bool* indefinite = nullptr) {
  const Eigen::Matrix<double, kN, 1> d = JacobiScale(A);
  const Eigen::Matrix<double, kN, 1> d_inv = d.cwiseInverse();
  Mat S = d_inv.asDiagonal() * (0.5 * (A + A.transpose())) * d_inv.asDiagonal();
  Eigen::LDLT<Mat> ldlt(S);
  if (indefinite != nullptr) *indefinite = ldlt.info() != Eigen::Success || !ldlt.isPositive();
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) {
    S.diagonal().array() += 1e-12;
    ldlt.compute(S);
  }
  return d_inv.asDiagonal() * ldlt.solve(Mat::Identity()) * d_inv.asDiagonal();
}

// Without the drift model the gb blocks are constant: unit information on their diagonal (no
// factor column touches them) keeps the 18x18 algebra regular and decoupled.
template <typename Matrix>
void AddPlaceholderInformation(bool estimate_gnss_bias, Matrix* H) {
  if (estimate_gnss_bias) return;
  for (int k = 0; k < H->rows() / kN; ++k) {
    H->diagonal().template segment<3>(k * kN + kGraphGb).array() += 1.0;
  }
}

// The chain positions [lo, hi] of the keyframes a factor touches (extrinsics left out; lo is
// SIZE_MAX for a factor on extrinsics alone). A factor spans one keyframe or two consecutive ones.
template <typename Index>
std::pair<size_t, size_t> ChainSpan(const std::vector<BlockRef>& blocks, const Index& index) {
  size_t lo = SIZE_MAX, hi = 0;
  for (const BlockRef& b : blocks) {
    if (IsSensorBlock(b.slot)) continue;
    lo = std::min(lo, index(b.keyframe));
    hi = std::max(hi, index(b.keyframe));
  }
  if (lo != SIZE_MAX && hi > lo + 1) {
    throw std::logic_error("NavGraph: factor spans non-consecutive keyframes");
  }
  return {lo, hi};
}

// AddPlaceholderInformation as whitened rows: unit rows on the gb columns starting at `col` of a
// two-keyframe Jacobian (`width` columns: more when an arrow's follow), for the square-root and
// covariance-form eliminations.
Eigen::MatrixXd PlaceholderRows(int col, Eigen::Index width = 2 * kN) {
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(3, width);
  J.block<3, 3>(0, col).setIdentity();
  return J;
}

// One keyframe k of the square-root elimination along the chain (NewestCovariance,
// ForEachCovarianceSqrt): the rows carried onto k from k-1 and the whitened rows of the factors
// whose oldest keyframe is k (on the columns [k | k+1 | arrow]; [k | arrow] when k is the newest),
// reduced by Householder reflections (HouseholderTriangularize, which skips the rows' zeros).
// `arrow_dim` columns of sensor blocks (0: none) ride along at the right, never eliminated.
// `*QR` gets R (zeros below its diagonal), whose first kN rows are
// [R_kk R_k,k+1 R_ke]; `*carry` the rows carried onto [k+1 | arrow] (unless k is the newest).
// False, with nothing changed, when fewer than kN rows are there to determine k (kN + arrow_dim
// at the newest, whose R must determine the arrow too).
bool EliminateKeyframe(const std::vector<Eigen::MatrixXd>& rows,
                       bool newest,
                       Eigen::Index arrow_dim,
                       Eigen::MatrixXd* carry,
                       Eigen::MatrixXd* QR) {
  const Eigen::Index chain_cols = newest ? kN : 2 * kN;
  const Eigen::Index cols = chain_cols + arrow_dim;
  Eigen::Index m = carry->rows();
  for (const Eigen::MatrixXd& J : rows) m += J.rows();
  if (m < kN + (newest ? arrow_dim : 0)) return false;
  // Assembled in *QR's storage (reallocated only when the size changes): a fresh zeroed matrix
  // per keyframe (calloc of ~18 kB) was 9 % of the batch's square-root covariance pass.
  Eigen::MatrixXd& M = *QR;
  M.setZero(m, cols);
  M.topLeftCorner(carry->rows(), kN) = carry->leftCols(kN);
  M.topRightCorner(carry->rows(), arrow_dim) = carry->rightCols(arrow_dim);
  Eigen::Index row = carry->rows();
  for (const Eigen::MatrixXd& J : rows) {
    M.block(row, 0, J.rows(), chain_cols) = J.leftCols(chain_cols);
    M.block(row, chain_cols, J.rows(), arrow_dim) = J.rightCols(arrow_dim);
    row += J.rows();
  }
  HouseholderTriangularize(&M);
  if (!newest) {
    const Eigen::Index carried = std::min<Eigen::Index>(m, cols) - kN;
    *carry = QR->block(kN, kN, carried, kN + arrow_dim).triangularView<Eigen::Upper>();
  }
  return true;
}

// ... and their variance is zero (they are known exactly).
void ClearConstantBlocks(bool estimate_gnss_bias, Mat* P) {
  if (estimate_gnss_bias) return;
  P->middleRows<3>(kGraphGb).setZero();
  P->middleCols<3>(kGraphGb).setZero();
}
}  // namespace

double* Keyframe::block(Slot s) {
  switch (s) {
    case Slot::kQ:
      return q;
    case Slot::kP:
      return p;
    case Slot::kV:
      return v;
    case Slot::kBg:
      return bg;
    case Slot::kBa:
      return ba;
    case Slot::kGb:
      return gb;
    case Slot::kExtrinsicQ:
    case Slot::kExtrinsicP:
    case Slot::kSensorParameter:
    case Slot::kImuCalibration:
      break;  // a sensor's or the graph's, not a keyframe's
  }
  return nullptr;
}

const double* Keyframe::block(Slot s) const { return const_cast<Keyframe*>(this)->block(s); }

NavState Keyframe::state() const {
  NavState s;
  s.t_ns = t_ns;
  s.q_w_b = Eigen::Quaterniond(Eigen::Map<const Eigen::Vector4d>(q)).normalized();
  s.p_w_b = Eigen::Map<const Eigen::Vector3d>(p);
  s.v_w = Eigen::Map<const Eigen::Vector3d>(v);
  s.bg = Eigen::Map<const Eigen::Vector3d>(bg);
  s.ba = Eigen::Map<const Eigen::Vector3d>(ba);
  return s;
}

void Keyframe::set_state(const NavState& s) {
  t_ns = s.t_ns;
  Eigen::Map<Eigen::Vector4d>{q} = s.q_w_b.normalized().coeffs();
  Eigen::Map<Eigen::Vector3d>{p} = s.p_w_b;
  Eigen::Map<Eigen::Vector3d>{v} = s.v_w;
  Eigen::Map<Eigen::Vector3d>{bg} = s.bg;
  Eigen::Map<Eigen::Vector3d>{ba} = s.ba;
}

struct NavGraph::Factor {
  FactorKind kind;
  std::shared_ptr<ceres::CostFunction> cost;
  std::unique_ptr<ceres::LossFunction> loss;
  std::vector<BlockRef> blocks;
  ceres::ResidualBlockId residual_id = nullptr;
};

struct NavGraph::Linearized {
  LinearizedResidual lin;
};

NavGraph::NavGraph(bool estimate_gnss_bias)
    : estimate_gnss_bias_(estimate_gnss_bias),
      quaternion_manifold_(std::make_unique<ceres::EigenQuaternionManifold>()) {}

NavGraph::~NavGraph() = default;

Keyframe& NavGraph::AddKeyframe(const NavState& initial, const Eigen::Vector3d& gyro_rad_s) {
  if (!keyframes_.empty() && initial.t_ns <= newest().t_ns) {
    throw std::logic_error("NavGraph::AddKeyframe: time must increase");
  }
  auto kf = std::make_unique<Keyframe>();
  kf->id = next_keyframe_id_++;
  kf->set_state(initial);
  kf->gyro_rad_s = gyro_rad_s;
  if (problem_) MirrorKeyframe(*kf);
  Keyframe& ref = *kf;
  keyframes_by_index_.push_back(kf.get());
  keyframes_.emplace(kf->id, std::move(kf));
  return ref;
}

double* NavGraph::BlockPtr(const BlockRef& ref) { return const_cast<double*>(BlockValue(ref)); }

const double* NavGraph::BlockValue(const BlockRef& ref) const {
  if (ref.slot == Slot::kImuCalibration) {
    if (!imu_calibration_) throw std::logic_error("NavGraph: no IMU calibration block");
    return imu_calibration_->value;
  }
  if (ref.slot == Slot::kSensorParameter) {
    return parameters_.at(static_cast<SensorId>(ref.keyframe))->value;
  }
  if (IsExtrinsic(ref.slot)) {
    const Extrinsic& e = *extrinsics_.at(static_cast<SensorId>(ref.keyframe));
    return ref.slot == Slot::kExtrinsicQ ? e.q : e.p;
  }
  return keyframes_by_index_[IndexOf(ref.keyframe)]->block(ref.slot);
}

const double* NavGraph::LinearizationPoint(const BlockRef& ref, bool fej) const {
  if (!fej) return BlockValue(ref);
  if (ref.slot == Slot::kImuCalibration) {
    return imu_calibration_->has_first_estimate ? imu_calibration_->fe : BlockValue(ref);
  }
  if (ref.slot == Slot::kSensorParameter) {
    const SensorParameter& s = *parameters_.at(static_cast<SensorId>(ref.keyframe));
    return s.has_first_estimate ? s.fe : BlockValue(ref);
  }
  const int offset = kSlotOffset[static_cast<int>(ref.slot)];
  if (IsExtrinsic(ref.slot)) {
    const Extrinsic& e = *extrinsics_.at(static_cast<SensorId>(ref.keyframe));
    return e.has_first_estimate ? e.fe + offset : BlockValue(ref);
  }
  const Keyframe& kf = keyframe(ref.keyframe);
  return kf.has_first_estimate ? kf.fe + offset : BlockValue(ref);
}

void NavGraph::AddExtrinsic(SensorId sensor,
                            const Eigen::Quaterniond& q_b_s,
                            const Eigen::Vector3d& p_b_s,
                            bool estimated) {
  if (extrinsics_.count(sensor) > 0) throw std::logic_error("NavGraph: extrinsic added twice");
  auto e = std::make_unique<Extrinsic>();
  Eigen::Map<Eigen::Vector4d>{e->q} = q_b_s.normalized().coeffs();
  Eigen::Map<Eigen::Vector3d>{e->p} = p_b_s;
  e->estimated = estimated;
  if (problem_) MirrorExtrinsic(e.get());
  extrinsics_.emplace(sensor, std::move(e));
}

void NavGraph::AddSensorParameter(SensorId sensor, double value, bool estimated) {
  if (parameters_.count(sensor) > 0) {
    throw std::logic_error("NavGraph: sensor parameter added twice");
  }
  auto s = std::make_unique<SensorParameter>();
  s->value[0] = value;
  s->estimated = estimated;
  if (problem_) MirrorSensorParameter(s.get());
  parameters_.emplace(sensor, std::move(s));
}

void NavGraph::AddImuCalibration(const Eigen::Matrix<double, kImuCalibrationSize, 1>& value) {
  if (imu_calibration_) throw std::logic_error("NavGraph: IMU calibration added twice");
  imu_calibration_ = std::make_unique<ImuCalibration>();
  Eigen::Map<Eigen::Matrix<double, kImuCalibrationSize, 1>>{imu_calibration_->value} = value;
  if (problem_) problem_->AddParameterBlock(imu_calibration_->value, kImuCalibrationSize);
}

void NavGraph::MirrorSensorParameter(SensorParameter* s) {
  problem_->AddParameterBlock(s->value, 1);
  if (!s->estimated) problem_->SetParameterBlockConstant(s->value);
}

void NavGraph::MirrorKeyframe(const Keyframe& kf) {
  for (int s = 0; s < kNumSlots; ++s) {
    double* block = const_cast<double*>(kf.block(static_cast<Slot>(s)));
    if (static_cast<Slot>(s) == Slot::kQ) {
      problem_->AddParameterBlock(block, 4, quaternion_manifold_.get());
    } else {
      problem_->AddParameterBlock(block, 3);
    }
  }
  if (!estimate_gnss_bias_) problem_->SetParameterBlockConstant(const_cast<double*>(kf.gb));
}

void NavGraph::MirrorExtrinsic(Extrinsic* e) {
  problem_->AddParameterBlock(e->q, 4, quaternion_manifold_.get());
  problem_->AddParameterBlock(e->p, 3);
  if (!e->estimated) {
    problem_->SetParameterBlockConstant(e->q);
    problem_->SetParameterBlockConstant(e->p);
  }
}

void NavGraph::MirrorFactor(Factor* f) {
  std::vector<double*> ptrs;
  for (const BlockRef& b : f->blocks) ptrs.push_back(BlockPtr(b));
  f->residual_id = problem_->AddResidualBlock(f->cost.get(), f->loss.get(), ptrs);
}

ceres::Problem& NavGraph::CeresProblem() {
  if (problem_) return *problem_;
  ceres::Problem::Options options;
  options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  options.enable_fast_removal = true;
  problem_ = std::make_unique<ceres::Problem>(options);
  for (auto& [sensor, e] : extrinsics_) MirrorExtrinsic(e.get());
  for (auto& [sensor, s] : parameters_) MirrorSensorParameter(s.get());
  if (imu_calibration_) {
    problem_->AddParameterBlock(imu_calibration_->value, kImuCalibrationSize);
  }
  for (const auto& [id, kf] : keyframes_) MirrorKeyframe(*kf);
  for (auto& [id, f] : factors_) MirrorFactor(f.get());
  return *problem_;
}

FactorId NavGraph::AddFactor(FactorKind kind,
                             std::unique_ptr<ceres::CostFunction> cost,
                             std::unique_ptr<ceres::LossFunction> loss,
                             const std::vector<BlockRef>& blocks) {
  return AddSharedFactor(kind, std::shared_ptr<ceres::CostFunction>(std::move(cost)),
                         std::move(loss), blocks);
}

FactorId NavGraph::AddSharedFactor(FactorKind kind,
                                   std::shared_ptr<ceres::CostFunction> cost,
                                   std::unique_ptr<ceres::LossFunction> loss,
                                   const std::vector<BlockRef>& blocks) {
  auto f = std::make_unique<Factor>();
  f->kind = kind;
  f->cost = std::move(cost);
  f->loss = std::move(loss);
  f->blocks = blocks;
  for (const BlockRef& b : blocks) BlockValue(b);  // std::out_of_range on a missing block
  if (problem_) MirrorFactor(f.get());
  const FactorId id = next_factor_id_++;
  factors_.emplace(id, std::move(f));
  return id;
}

void NavGraph::RemoveFactor(FactorId id) {
  auto it = factors_.find(id);
  if (it == factors_.end()) return;
  if (problem_) problem_->RemoveResidualBlock(it->second->residual_id);
  factors_.erase(it);
}

ceres::Solver::Options MakeSolverOptions(const CeresConfig& c) {
  ceres::Solver::Options o;
  if (c.trust_region == "levenberg_marquardt") {
    o.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  } else if (c.trust_region == "dogleg") {
    o.trust_region_strategy_type = ceres::DOGLEG;
  } else {
    throw std::invalid_argument("unknown trust_region '" + c.trust_region + "'");
  }
  if (c.dogleg_type == "traditional") {
    o.dogleg_type = ceres::TRADITIONAL_DOGLEG;
  } else if (c.dogleg_type == "subspace") {
    o.dogleg_type = ceres::SUBSPACE_DOGLEG;
  } else {
    throw std::invalid_argument("unknown dogleg_type '" + c.dogleg_type + "'");
  }
  if (c.chain_gains != "double" && c.chain_gains != "single") {
    throw std::invalid_argument("unknown chain_gains '" + c.chain_gains + "' (double or single)");
  }
  if (c.linear_solver == "chain" && o.trust_region_strategy_type != ceres::LEVENBERG_MARQUARDT) {
    throw std::invalid_argument("linear_solver 'chain' needs trust_region levenberg_marquardt");
  }
  if (!ceres::StringToLinearSolverType(
          [&] {
            // "chain" is NavGraph::SolveChain's; a Ceres problem built for it anyway (a caller
            // of CeresProblem) gets Ceres' sparse normal Cholesky.
            std::string s = c.linear_solver == "chain" ? "sparse_normal_cholesky" : c.linear_solver;
            std::transform(s.begin(), s.end(), s.begin(), ::toupper);
            return s;
          }(),
          &o.linear_solver_type)) {
    throw std::invalid_argument("unknown linear_solver '" + c.linear_solver + "'");
  }
  if (o.trust_region_strategy_type == ceres::DOGLEG) {
    // Ceres' dogleg regularises its Gauss-Newton step with mu * D^2, D^2 = diag(J^T J) clamped
    // to [min_lm_diagonal, max_lm_diagonal] (J is already Jacobi-scaled, so D^2 ~ 1), and mu
    // never drops below a hard-coded 1e-8, whatever the trust region radius. The IMU factors
    // carry so much more information than GNSS that the GNSS-determined directions of a window
    // have eigenvalues of ~5e-10 and below in that scaling: each step moved them a few percent
    // of the way, no window solve converged in 10 (or 300) iterations, the estimate drifted
    // off and the gate then rejected every fix (docs/configuration.md). Clamping D^2 to the
    // constant min_lm_diagonal (1e-6) makes the damping 1e-14 and the trust region a sphere in
    // the Jacobi-scaled space: the step is the Gauss-Newton step (1-2 iterations per solve).
    o.max_lm_diagonal = o.min_lm_diagonal;
  }
  o.max_num_iterations = c.max_iterations;
  o.initial_trust_region_radius = c.initial_trust_region_radius;
  o.max_trust_region_radius = std::max(1e16, c.initial_trust_region_radius);
  if (c.max_time_s > 0.0) o.max_solver_time_in_seconds = c.max_time_s;
  o.num_threads = c.num_threads;
  o.function_tolerance = c.function_tolerance;
  o.gradient_tolerance = c.gradient_tolerance;
  o.parameter_tolerance = c.parameter_tolerance;
  o.logging_type = ceres::SILENT;
  o.minimizer_progress_to_stdout = false;
  return o;
}

namespace {

// Ends a solve at its next iteration once the stop flag is set.
class StopCallback : public ceres::IterationCallback {
 public:
  explicit StopCallback(const std::atomic<bool>* stop) : stop_(stop) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
    return stop_->load(std::memory_order_relaxed) ? ceres::SOLVER_TERMINATE_SUCCESSFULLY
                                                  : ceres::SOLVER_CONTINUE;
  }

 private:
  const std::atomic<bool>* stop_;
};

}  // namespace

ceres::Solver::Summary NavGraph::Solve(const CeresConfig& config) {
  if (config.linear_solver == "chain") return SolveChain(config);
  ceres::Solver::Options options = MakeSolverOptions(config);
  StopCallback stop_callback(stop_);
  if (stop_ != nullptr) options.callbacks.push_back(&stop_callback);
  ceres::Solver::Summary summary;
  ceres::Solve(options, &CeresProblem(), &summary);
  return summary;
}

std::vector<const NavGraph::Factor*> NavGraph::FactorsInOrder() const {
  std::vector<const Factor*> factors;
  factors.reserve(factors_.size());
  for (const auto& [fid, f] : factors_) factors.push_back(f.get());
  return factors;
}

bool NavGraph::Cost(double* cost, int threads) const {
  return CostOf(FactorsInOrder(), cost, threads);
}

bool NavGraph::CostOf(const std::vector<const Factor*>& factors, double* cost, int threads) const {
  // One factor's rho(|r|^2) at the current values; false when its cost function fails.
  auto term = [this](const Factor& f, double* rho_out) {
    thread_local std::vector<const double*> values;
    thread_local std::vector<double> buffer;  // grows to the largest residual, then stays
    values.clear();
    for (const BlockRef& b : f.blocks) values.push_back(BlockValue(b));
    const int m = f.cost->num_residuals();
    if (buffer.size() < static_cast<size_t>(m)) buffer.resize(static_cast<size_t>(m));
    if (!f.cost->Evaluate(values.data(), buffer.data(), nullptr)) return false;
    double rho[3] = {Eigen::Map<const Eigen::VectorXd>(buffer.data(), m).squaredNorm(), 1.0, 0.0};
    if (f.loss != nullptr) f.loss->Evaluate(rho[0], rho);
    *rho_out = rho[0];
    return true;
  };
  double sum = 0.0;
  // A window's few dozen factors cost less than starting a thread: one thread there.
  constexpr size_t kMinParallelFactors = 512;
  if (threads <= 1 || factors.size() < kMinParallelFactors) {
    for (const Factor* f : factors) {
      double rho = 0.0;
      if (!term(*f, &rho)) return false;
      sum += rho;
    }
  } else {
    // Each factor's term on whichever thread, summed in the factors' order as above: the same
    // cost to the last bit.
    std::vector<double> rho(factors.size(), 0.0);
    if (!ParallelFor(factors.size(), threads,
                     [&](size_t i) { return term(*factors[i], &rho[i]); })) {
      return false;
    }
    for (const double r : rho) sum += r;
  }
  *cost = 0.5 * sum;
  return std::isfinite(*cost);
}

namespace {

// Keyframes per chunk of SolveChain's assembly: with num_threads > 1 and a longer chain, a
// worker assembles the next chunk while the elimination consumes this one (5.3 kB a keyframe).
constexpr size_t kChainChunk = 512;

// Keyframes [begin, end) of the chain linearised and assembled for the elimination: each one's
// diagonal block D_k, its coupling O_k to the next, its gradient g_k and its arrow rows C_k.
struct ChainSteps {
  size_t begin = 0, end = 0;
  bool ok = true;
  std::vector<Mat> D, O;
  std::vector<Vec> g;
  std::vector<Eigen::Matrix<double, kN, Eigen::Dynamic>> C;
};

}  // namespace

ceres::Solver::Summary NavGraph::SolveChain(const CeresConfig& config,
                                            const std::function<int()>& decide) {
  const auto t0 = std::chrono::steady_clock::now();
  auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  };
  ceres::Solver::Summary summary;
  summary.linear_solver_type_given = ceres::SPARSE_NORMAL_CHOLESKY;
  summary.linear_solver_type_used = ceres::SPARSE_NORMAL_CHOLESKY;
  summary.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  // Counted from zero, as Ceres' minimiser does (the Summary's own default is -1 each, which
  // BriefReport's "Iterations:" sums).
  summary.num_successful_steps = 0;
  summary.num_unsuccessful_steps = 0;
  // The estimated extrinsics and sensor parameters: an arrow beside the chain, eliminated last
  // (block_tridiagonal.h).
  Arrow arrow = EstimatedSensorBlocks();
  summary.num_parameter_blocks =
      static_cast<int>(keyframes_.size()) * kNumSlots + static_cast<int>(arrow.blocks.size());
  summary.num_residual_blocks = static_cast<int>(factors_.size());
  auto finish = [&](ceres::TerminationType type, const std::string& message) {
    summary.termination_type = type;
    summary.message = message;
    summary.total_time_in_seconds = elapsed();
    return summary;
  };
  // Only `decide` adds and removes factors: listed once for every evaluation of the cost, and
  // again after it changed them.
  std::vector<const Factor*> all_factors = FactorsInOrder();
  double cost = 0.0;
  if (!CostOf(all_factors, &cost, config.num_threads)) {
    return finish(ceres::FAILURE, "a cost function failed at the start");
  }
  summary.initial_cost = summary.final_cost = cost;
  auto record = [&](int iteration, double c, bool success, double step_norm) {
    ceres::IterationSummary it;
    it.iteration = iteration;
    it.cost = c;
    it.step_is_successful = success;
    it.step_norm = step_norm;
    it.cumulative_time_in_seconds = elapsed();
    summary.iterations.push_back(it);
  };
  record(0, cost, true, 0.0);

  const size_t n = keyframes_.size();
  std::vector<Keyframe*> kfs;
  for (auto& [id, kf] : keyframes_) kfs.push_back(kf.get());
  // Ceres' LevenbergMarquardtStrategy: damping 1/radius on the scaled problem; radius /=
  // max(1/3, 1 - (2 rho - 1)^3) after a step of quality rho, radius /= a factor that doubles
  // with every rejected step.
  double radius = config.initial_trust_region_radius;
  const double max_radius = std::max(1e16, radius);
  double decrease_factor = 2.0;
  constexpr double kMinRelativeDecrease = 1e-3;  // Ceres' min_relative_decrease
  ChainIndex chain = IndexChain();
  BlockTridiagonalSolver solver;
  std::vector<Vec> x;
  std::vector<std::array<double, 19>> saved(n);
  Linearized L;
  Mat D, D_next, O, O_prev;
  Vec g, g_next;
  int m = arrow.dim;
  using ArrowRows = Eigen::Matrix<double, kN, Eigen::Dynamic>;
  ArrowRows C, C_next;
  Eigen::MatrixXd E;
  Eigen::VectorXd g_e, x_e;
  std::vector<double> saved_arrow;              // the arrow blocks' values, block after block
  ChainSteps chunk_steps[2];                    // the chunk being eliminated and the next one
  std::vector<Linearized> chunk_linearized[2];  // their sensor blocks, with num_threads > 1
  // The caller's gate (`decide`): whether it has seen the current iterate, and the last accepted
  // step's decrease of the cost relative to it.
  bool decided_here = false;
  double last_relative_decrease = HUGE_VAL;
  // Runs the gate at the current iterate; true when it changed the factors, which are then
  // listed and indexed anew, with the cost they give here.
  auto run_decide = [&]() -> bool {
    if (!decide || decided_here) return false;
    decided_here = true;
    if (decide() == 0) return false;
    // The last step's gains and solution and the old lists are dead here: released before the
    // new lists are built, so that a round of the gate adds nothing to the solve's peak memory.
    solver.Release();
    std::vector<Vec>().swap(x);
    std::vector<const Factor*>().swap(all_factors);
    chain = ChainIndex();
    all_factors = FactorsInOrder();
    chain = IndexChain();
    arrow = EstimatedSensorBlocks();
    m = arrow.dim;
    summary.num_residual_blocks = static_cast<int>(factors_.size());
    if (!CostOf(all_factors, &cost, config.num_threads)) cost = HUGE_VAL;
    summary.final_cost = cost;
    return true;
  };
  for (int iteration = 1; iteration <= config.max_iterations; ++iteration) {
    if (stopped()) return finish(ceres::USER_SUCCESS, "stopped by the caller");
    if (config.max_time_s > 0.0 && elapsed() > config.max_time_s) {
      return finish(ceres::NO_CONVERGENCE, "maximum solver time reached");
    }
    if (last_relative_decrease < kDecideBelowRelativeDecrease) run_decide();
    if (!std::isfinite(cost)) return finish(ceres::FAILURE, "a cost function failed");
    // Linearised keyframe by keyframe and eliminated as the blocks come (block_tridiagonal.h):
    // the information is never held whole (two chunks of keyframes at most, below). Every iteration
    // relinearises (after a rejected step too: rare from a window's or a prediction's start).
    const double mu = 1.0 / radius;
    solver.Start(n, mu, m,
                 config.chain_gains == "single" ? GainPrecision::kSingle : GainPrecision::kDouble);
    bool solved = true;
    double g_max = 0.0;
    D.setZero();
    g.setZero();
    if (m > 0) {
      C.setZero(kN, m);
      E.setZero(m, m);
      g_e.setZero(m);
      for (const Factor* f : arrow.own_factors) {
        if (!LinearizeFactor(*f, false, &L)) {
          return finish(ceres::FAILURE, "a cost function failed in the linearisation");
        }
        AddArrowInformation(*f, L, SIZE_MAX, arrow, nullptr, nullptr, &E, &g_e);
      }
    }
    // Chunk after chunk: keyframes [a, b) linearised and assembled into `steps` (the carried
    // D, g and C of the keyframe after b stay in D, g and C), then pushed. With num_threads > 1
    // a worker assembles the next chunk while this thread eliminates the one at hand; the
    // assembly runs in keyframe order either way and the elimination sees the same blocks, so
    // the step is the same to the last bit whatever the thread count. The worker first
    // linearises the chunk's sensor blocks on num_threads threads (LinearizeChainFactors: a
    // camera frame's block is most of a skyline batch's time), each block on one thread, as Ceres
    // evaluates residual blocks with num_threads > 1, so cost functions must allow different
    // blocks at once (the skyline's and the LiDAR's do); the elimination touches none.
    auto assemble = [&](size_t a, size_t b, ChainSteps* steps, std::vector<Linearized>* lin) {
      steps->begin = a;
      steps->end = b;
      steps->ok = true;
      steps->D.resize(b - a);
      steps->O.resize(b - a);
      steps->g.resize(b - a);
      steps->C.resize(m > 0 ? b - a : 0);
      const bool parallel = config.num_threads > 1;
      if (parallel &&
          !LinearizeChainFactors(chain, chain.start[a], chain.start[b], config.num_threads, lin)) {
        steps->ok = false;
        return;
      }
      for (size_t k = a; k < b; ++k) {
        if (m > 0) C_next.setZero(kN, m);
        const Linearized* linearized =
            parallel ? lin->data() + (chain.start[k] - chain.start[a]) : nullptr;
        if (!AssembleChainStep(chain, k, &L, &D, &O, &D_next, &g, &g_next, m > 0 ? &arrow : nullptr,
                               &C, &C_next, &E, &g_e, linearized)) {
          steps->ok = false;
          return;
        }
        if (!estimate_gnss_bias_) g.segment<3>(kGraphGb).setZero();
        const size_t i = k - a;
        steps->D[i] = D;
        steps->O[i] = O;
        steps->g[i] = g;
        if (m > 0) steps->C[i] = C;
        D = D_next;
        g = g_next;
        if (m > 0) std::swap(C, C_next);
      }
    };
    std::future<void> pending;
    auto start_chunk = [&](size_t a, int slot) {
      const size_t b = std::min(n, a + kChainChunk);
      ChainSteps* steps = &chunk_steps[slot];
      std::vector<Linearized>* lin = &chunk_linearized[slot];
      if (config.num_threads > 1 && n > kChainChunk) {
        pending = std::async(std::launch::async, assemble, a, b, steps, lin);
      } else {
        assemble(a, b, steps, lin);
      }
    };
    start_chunk(0, 0);
    for (size_t c = 0; c * kChainChunk < n; ++c) {
      if (pending.valid()) pending.get();  // no worker runs past this point until the next start
      const ChainSteps& steps = chunk_steps[c % 2];
      if (!steps.ok) return finish(ceres::FAILURE, "a cost function failed in the linearisation");
      if (steps.end < n) start_chunk(steps.end, static_cast<int>((c + 1) % 2));
      for (size_t k = steps.begin; k < steps.end; ++k) {
        const size_t i = k - steps.begin;
        g_max = std::max(g_max, steps.g[i].cwiseAbs().maxCoeff());
        solved = solved && solver.Push(steps.D[i], -steps.g[i], k > 0 ? &O_prev : nullptr,
                                       m > 0 ? &steps.C[i] : nullptr);
        O_prev = steps.O[i];
      }
    }
    if (m > 0) g_max = std::max(g_max, g_e.cwiseAbs().maxCoeff());
    if (g_max <= config.gradient_tolerance) {
      if (run_decide()) continue;  // converged, but not with the gate's new decisions
      return finish(ceres::CONVERGENCE, "gradient tolerance reached");
    }
    double y_norm2 = 0.0, bx = 0.0;
    solved = solved && (m > 0 ? solver.Finish(E, -g_e, &x, &x_e, &y_norm2, &bx)
                              : solver.Finish(&x, &y_norm2, &bx));
    const double model_decrease = 0.5 * (bx + mu * y_norm2);
    double x_norm2 = 0.0, step_norm2 = 0.0;
    double new_cost = HUGE_VAL;
    if (solved && model_decrease > 0.0) {
      for (size_t k = 0; k < n; ++k) {
        Keyframe& kf = *kfs[k];
        for (int sl = 0; sl < kNumSlots; ++sl) {  // the layout of Keyframe::fe
          const Slot slot = static_cast<Slot>(sl);
          std::copy_n(kf.block(slot), SlotSize(slot), saved[k].begin() + kSlotOffset[sl]);
        }
        for (double v : saved[k]) x_norm2 += v * v;
        if (!estimate_gnss_bias_) x[k].segment<3>(kGraphGb).setZero();
        step_norm2 += x[k].squaredNorm();
        Eigen::Map<Eigen::Quaterniond> q(kf.q);
        q = (ExpQ<double>(x[k].segment<3>(kRot)) * q).normalized();
        Eigen::Map<Eigen::Vector3d>(kf.p) += x[k].segment<3>(kPos);
        Eigen::Map<Eigen::Vector3d>(kf.v) += x[k].segment<3>(kVel);
        Eigen::Map<Eigen::Vector3d>(kf.bg) += x[k].segment<3>(kBg);
        Eigen::Map<Eigen::Vector3d>(kf.ba) += x[k].segment<3>(kBa);
        Eigen::Map<Eigen::Vector3d>(kf.gb) += x[k].segment<3>(kGraphGb);
      }
      saved_arrow.clear();
      for (size_t a = 0; a < arrow.blocks.size(); ++a) {
        double* v = BlockPtr(arrow.blocks[a]);
        const int size = SlotSize(arrow.blocks[a].slot);
        saved_arrow.insert(saved_arrow.end(), v, v + size);
        for (int i = 0; i < size; ++i) x_norm2 += v[i] * v[i];
        const auto dx = x_e.segment(arrow.col[a], TangentSize(size));
        step_norm2 += dx.squaredNorm();
        if (size == 4) {  // the left full-angle perturbation of factor_linearization.h
          Eigen::Map<Eigen::Quaterniond> q(v);
          q = (ExpQ<double>(Eigen::Vector3d(dx)) * q).normalized();
        } else {
          for (int i = 0; i < size; ++i) v[i] += dx[i];
        }
      }
      if (!CostOf(all_factors, &new_cost, config.num_threads)) new_cost = HUGE_VAL;
    }
    auto undo = [&] {
      for (size_t k = 0; k < n; ++k) {
        for (int sl = 0; sl < kNumSlots; ++sl) {
          const Slot slot = static_cast<Slot>(sl);
          std::copy_n(saved[k].begin() + kSlotOffset[sl], SlotSize(slot), kfs[k]->block(slot));
        }
      }
      size_t offset = 0;
      for (const BlockRef& b : arrow.blocks) {
        const int size = SlotSize(b.slot);
        std::copy_n(saved_arrow.begin() + static_cast<std::ptrdiff_t>(offset), size, BlockPtr(b));
        offset += static_cast<size_t>(size);
      }
    };
    const bool evaluated = solved && model_decrease > 0.0;
    const double step_norm = std::sqrt(step_norm2);
    if (evaluated) {
      // Ceres' order: the tolerances on the candidate first, which is then not taken.
      if (step_norm <=
          config.parameter_tolerance * (std::sqrt(x_norm2) + config.parameter_tolerance)) {
        undo();
        if (run_decide()) continue;
        return finish(ceres::CONVERGENCE, "parameter tolerance reached");
      }
      if (std::isfinite(new_cost) &&
          std::abs(cost - new_cost) <= config.function_tolerance * cost) {
        undo();
        if (run_decide()) continue;
        return finish(ceres::CONVERGENCE, "function tolerance reached");
      }
    }
    const double quality = (cost - new_cost) / model_decrease;
    if (!(evaluated && std::isfinite(new_cost) && quality > kMinRelativeDecrease)) {
      if (evaluated) undo();
      ++summary.num_unsuccessful_steps;
      record(iteration, cost, false, step_norm);
      radius /= decrease_factor;
      decrease_factor *= 2.0;
      if (radius < 1e-32) return finish(ceres::FAILURE, "trust region radius below 1e-32");
      continue;
    }
    ++summary.num_successful_steps;
    record(iteration, new_cost, true, step_norm);
    last_relative_decrease = (cost - new_cost) / cost;
    decided_here = false;
    cost = new_cost;
    summary.final_cost = cost;
    radius =
        std::min(max_radius, radius / std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * quality - 1.0, 3)));
    decrease_factor = 2.0;
  }
  return finish(ceres::NO_CONVERGENCE, "maximum number of iterations reached");
}

bool NavGraph::LinearizeFactor(const Factor& f, bool fej, Linearized* out) const {
  thread_local std::vector<const double*> current, at_jacobian;  // no allocation per factor
  current.clear();
  at_jacobian.clear();
  for (const BlockRef& b : f.blocks) {
    current.push_back(BlockValue(b));
    at_jacobian.push_back(LinearizationPoint(b, fej));
  }
  if (!LinearizeResidual(*f.cost, f.loss.get(), current, at_jacobian, &out->lin)) return false;
  if (at_jacobian != current) {
    // Move the residual to the first-estimate point: r(x_fe) ~ r(x) - J (x (-) x_fe).
    for (size_t k = 0; k < f.blocks.size(); ++k) {
      if (at_jacobian[k] == current[k]) continue;
      out->lin.residual -=
          out->lin.jacobians[k] * SlotMinus(f.blocks[k].slot, current[k], at_jacobian[k]);
    }
  }
  return true;
}

void NavGraph::ScatterJacobian(const Factor& f,
                               const Linearized& L,
                               KeyframeId first,
                               KeyframeId second,
                               Eigen::MatrixXd* J) const {
  for (size_t k = 0; k < f.blocks.size(); ++k) {
    const BlockRef& b = f.blocks[k];
    if (b.slot == Slot::kGb && !estimate_gnss_bias_) continue;  // constant block
    if (IsSensorBlock(b.slot)) continue;  // the chain is conditional on the sensors' blocks
    int col = kSlotTangent[static_cast<int>(b.slot)];
    if (b.keyframe == first) {
      // columns of the first keyframe
    } else if (b.keyframe == second) {
      col += kN;
    } else {
      throw std::logic_error("NavGraph: factor spans non-consecutive keyframes");
    }
    J->middleCols(col, TangentSize(SlotSize(b.slot))) += L.lin.jacobians[k];
  }
}

Eigen::MatrixXd NavGraph::ScatterWithArrow(const Factor& f,
                                           const Linearized& L,
                                           const KeyframeId* first,
                                           const KeyframeId* second,
                                           const Arrow& arrow) const {
  Eigen::MatrixXd J = Eigen::MatrixXd::Zero(L.lin.residual.size(), 2 * kN + arrow.dim);
  if (first != nullptr) ScatterJacobian(f, L, *first, *second, &J);
  for (size_t b = 0; arrow.dim > 0 && b < f.blocks.size(); ++b) {
    const int col = IsSensorBlock(f.blocks[b].slot) ? arrow.ColumnOf(f.blocks[b]) : -1;
    if (col >= 0) J.middleCols(2 * kN + col, L.lin.jacobians[b].cols()) += L.lin.jacobians[b];
  }
  return J;
}

void NavGraph::MarginalizeOldest(bool first_estimate_jacobians) {
  if (keyframes_.size() < 2) throw std::logic_error("MarginalizeOldest needs two keyframes");
  const KeyframeId id0 = keyframes_.begin()->first;
  const KeyframeId id1 = std::next(keyframes_.begin())->first;
  Keyframe& kf1 = *keyframes_by_index_[IndexOf(id1)];
  // Linearisation point of the kept keyframe: with FEJ its first estimate (fixed from now on).
  if (!kf1.has_first_estimate) {
    for (int s = 0; s < kNumSlots; ++s) {
      std::copy_n(kf1.block(static_cast<Slot>(s)), SlotSize(static_cast<Slot>(s)),
                  kf1.fe + kSlotOffset[s]);
    }
    kf1.has_first_estimate = true;
  }

  // Square-root marginalisation (cf. Demmel et al., "Square Root Marginalization for Sliding-
  // Window Bundle Adjustment", ICCV 2021): the whitened Jacobians and residuals of the factors
  // on keyframe 0 are stacked as A = [J_0 J_1 J_e | r] (columns: keyframe 0's tangent, keyframe
  // 1's, then the estimated extrinsics those factors touch) and reduced by a Householder QR
  // (HouseholderTriangularize: only the rows with nonzeros in a column are reflected),
  // Q^T A = [R_00 R_0k r_0; 0 R_kk r_k; 0 0 e]. Minimising over keyframe 0 leaves
  // |R_kk dx_k + r_k|^2 on x_k = (keyframe 1, extrinsics): the prior, whose information
  // R_kk^T R_kk is the Schur complement (Sibley et al. 2010, eq. 9) formed without ever squaring
  // J. A navigation-grade IMU puts bias information of 1e20 next to position information of 1e2;
  // the normal equations' conditioning (2.8e12 even after Jacobi scaling) cost ~1e-3 of the
  // prior's covariance, and the eigenvalue cut of LinearPriorFactor::FromInformation dropped its
  // weakest real directions. Without the drift model the constant gb blocks have no columns, and
  // constant extrinsics none either.
  const int n = estimate_gnss_bias_ ? kN : kStateDim;  // columns per keyframe
  auto touches = [&](const Factor& f, KeyframeId id) {
    return std::any_of(f.blocks.begin(), f.blocks.end(), [&](const BlockRef& b) {
      return !IsSensorBlock(b.slot) && b.keyframe == id;
    });
  };
  // The marginalised factors (in id order) and their rows, and the estimated extrinsics and
  // sensor parameters in them, each with its first column.
  std::vector<std::pair<FactorId, const Factor*>> marginalised;
  std::map<SensorId, int> extrinsic_col, parameter_col;
  int calibration_col = -1;  // the IMU calibration's, when a marginalised factor takes it
  int cols = 2 * n;
  int m = 0;
  for (const auto& [fid, f] : factors_) {
    if (!touches(*f, id0)) continue;
    marginalised.emplace_back(fid, f.get());
    m += f->cost->num_residuals();
    for (const BlockRef& b : f->blocks) {
      const SensorId sensor = static_cast<SensorId>(b.keyframe);
      if (IsExtrinsic(b.slot) && extrinsics_.at(sensor)->estimated) extrinsic_col[sensor] = 0;
      if (b.slot == Slot::kSensorParameter && parameters_.at(sensor)->estimated) {
        parameter_col[sensor] = 0;
      }
      if (b.slot == Slot::kImuCalibration) calibration_col = 0;
    }
  }
  for (auto& [sensor, col] : extrinsic_col) {  // columns in the order of the prior's blocks
    col = cols;
    cols += kExtrinsicDim;
    Extrinsic& e = *extrinsics_.at(sensor);
    if (!e.has_first_estimate) {
      std::copy_n(e.q, 4, e.fe);
      std::copy_n(e.p, 3, e.fe + 4);
      e.has_first_estimate = true;
    }
  }
  for (auto& [sensor, col] : parameter_col) {
    col = cols;
    cols += 1;
    SensorParameter& s = *parameters_.at(sensor);
    if (!s.has_first_estimate) {
      s.fe[0] = s.value[0];
      s.has_first_estimate = true;
    }
  }
  if (calibration_col >= 0) {
    calibration_col = cols;
    cols += kImuCalibrationSize;
    ImuCalibration& c = *imu_calibration_;
    if (!c.has_first_estimate) {
      std::copy_n(c.value, kImuCalibrationSize, c.fe);
      c.has_first_estimate = true;
    }
  }
  // Each factor's rows straight into A (one Linearized and one J for all of them).
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(m, cols + 1);
  Linearized L;
  Eigen::MatrixXd J;
  Eigen::Index row = 0;
  for (const auto& [fid, f] : marginalised) {
    if (!LinearizeFactor(*f, first_estimate_jacobians, &L)) {
      throw std::runtime_error("marginalisation: a factor failed to evaluate");
    }
    const Eigen::Index rows = L.lin.residual.size();
    J.setZero(rows, 2 * kN);
    ScatterJacobian(*f, L, id0, id1, &J);
    A.block(row, 0, rows, n) = J.leftCols(n);
    A.block(row, n, rows, n) = J.middleCols(kN, n);
    for (size_t k = 0; k < f->blocks.size(); ++k) {
      const BlockRef& b = f->blocks[k];
      if (b.slot == Slot::kImuCalibration) {
        A.block(row, calibration_col, rows, kImuCalibrationSize) += L.lin.jacobians[k];
        continue;
      }
      if (b.slot == Slot::kSensorParameter) {
        const auto it = parameter_col.find(static_cast<SensorId>(b.keyframe));
        if (it != parameter_col.end()) A.block(row, it->second, rows, 1) += L.lin.jacobians[k];
        continue;
      }
      if (!IsExtrinsic(b.slot)) continue;
      const auto it = extrinsic_col.find(static_cast<SensorId>(b.keyframe));
      if (it == extrinsic_col.end()) continue;  // constant
      A.block(row, it->second + (b.slot == Slot::kExtrinsicQ ? 0 : 3), rows, 3) +=
          L.lin.jacobians[k];
    }
    A.block(row, cols, rows, 1) = L.lin.residual;
    row += rows;
  }
  HouseholderTriangularize(&A);
  const int kept_cols = cols - n;
  const int kept_rows = std::max(0, std::min(m, cols) - n);
  const Eigen::MatrixXd R = A.topRows(std::min(m, cols + 1));  // upper triangular

  for (const auto& [fid, f] : marginalised) RemoveFactor(fid);
  const Keyframe& kf0 = *keyframes_.at(id0);
  for (int s = 0; problem_ && s < kNumSlots; ++s) {
    problem_->RemoveParameterBlock(const_cast<double*>(kf0.block(static_cast<Slot>(s))));
  }
  keyframes_.erase(id0);
  keyframes_by_index_.pop_front();
  if (kept_rows == 0) return;  // nothing known about keyframe 1 beyond its own factors

  // The prior's linearisation point: the first estimate of keyframe 1 (with FEJ), else now; the
  // same for the extrinsics.
  const int num_slots = estimate_gnss_bias_ ? kNumSlots : kNumSlots - 1;
  std::vector<Eigen::VectorXd> x0;
  std::vector<int> sizes;
  std::vector<BlockRef> blocks;
  auto add_block = [&](const BlockRef& b) {
    sizes.push_back(SlotSize(b.slot));
    x0.push_back(Eigen::Map<const Eigen::VectorXd>(LinearizationPoint(b, first_estimate_jacobians),
                                                   SlotSize(b.slot)));
    blocks.push_back(b);
  };
  for (int s = 0; s < num_slots; ++s) add_block({id1, static_cast<Slot>(s)});
  for (const auto& [sensor, col] : extrinsic_col) {
    for (const BlockRef& b : ExtrinsicBlocks(sensor)) add_block(b);
  }
  for (const auto& [sensor, col] : parameter_col) add_block(SensorParameterBlock(sensor));
  if (calibration_col >= 0) add_block(ImuCalibrationBlock());
  AddFactor(
      FactorKind::kMarginalPrior,
      std::make_unique<LinearPriorFactor>(sizes, std::move(x0), R.block(n, n, kept_rows, kept_cols),
                                          R.block(n, cols, kept_rows, 1)),
      nullptr, blocks);
}

namespace {
// The Gram products of AddFactorInformation and AddArrowInformation with the factor's residual
// rows R fixed at compile time where R is a common count (an IMU factor's 9, its bias walk's 6,
// a fix's 3; Eigen::Dynamic for any other): Eigen then unrolls and vectorises the R-long dot
// products, which its coefficient loops over run-time sizes did not. The two functions, at every
// linearisation of the chain, were 12.9 % of a harbour smooth's instructions (callgrind; 15 % of
// the hour at sea's), 6.6 % after this.
template <int R>
using RowsMap = Eigen::Map<const Eigen::Matrix<double, R, Eigen::Dynamic>>;

template <int R>
RowsMap<R> Rows(const Eigen::MatrixXd& J) {
  return RowsMap<R>(J.data(), J.rows(), J.cols());
}

// J^T J and J^T r block by block for the blocks with a column in [lo | hi] (col[a] >= 0, every
// such block 3 wide); `add(r, c, M)` places one 3x3 product.
template <int R, typename Add>
void AddChainGram(const LinearizedResidual& lin,
                  const std::array<int, 16>& col,
                  size_t nb,
                  const Add& add,
                  Eigen::Matrix<double, kN, 1>* g_lo,
                  Eigen::Matrix<double, kN, 1>* g_hi) {
  using Block = Eigen::Map<const Eigen::Matrix<double, R, 3>>;
  const Eigen::Map<const Eigen::Matrix<double, R, 1>> r(lin.residual.data(), lin.residual.size());
  for (size_t a = 0; a < nb; ++a) {
    if (col[a] < 0) continue;
    const Block Ja(lin.jacobians[a].data(), lin.jacobians[a].rows(), 3);
    if (g_lo != nullptr) {
      const Eigen::Vector3d ga = Ja.transpose().lazyProduct(r);
      ((col[a] < kN) ? *g_lo : *g_hi).template segment<3>(col[a] % kN) += ga;
    }
    for (size_t b = a; b < nb; ++b) {
      if (col[b] < 0) continue;
      const Block Jb(lin.jacobians[b].data(), lin.jacobians[b].rows(), 3);
      const Eigen::Matrix3d M = Ja.transpose().lazyProduct(Jb);
      add(col[a], col[b], M);
      if (b != a) add(col[b], col[a], M.transpose());
    }
  }
}
}  // namespace

void NavGraph::AddFactorInformation(const Factor& f,
                                    const Linearized& L,
                                    size_t lo,
                                    Mat* D_lo,
                                    Mat* D_hi,
                                    Mat* O,
                                    Vec* g_lo,
                                    Vec* g_hi) const {
  // Block by block: every slot's tangent is 3 wide, so J^T J is a sum of 3x3 products J_a^T J_b
  // placed in D_lo, D_hi or O (a factor on one keyframe fills D_lo only).
  const size_t nb = f.blocks.size();
  std::array<int, 16> col{};  // in [lo | hi], -1 for constant blocks and extrinsics
  if (nb > col.size()) throw std::logic_error("NavGraph: factor with more than 16 blocks");
  for (size_t a = 0; a < nb; ++a) {
    const BlockRef& b = f.blocks[a];
    col[a] = (IsSensorBlock(b.slot) || (b.slot == Slot::kGb && !estimate_gnss_bias_))
                 ? -1
                 : kSlotTangent[static_cast<int>(b.slot)] + (IndexOf(b.keyframe) == lo ? 0 : kN);
  }
  auto add = [&](int r, int c, const Eigen::Matrix3d& M) {
    if (r < kN && c < kN) {
      D_lo->block<3, 3>(r, c) += M;
    } else if (r >= kN && c >= kN) {
      D_hi->block<3, 3>(r - kN, c - kN) += M;
    } else if (r < kN) {
      O->block<3, 3>(r, c - kN) += M;
    }  // the lower off-diagonal block is O^T, not stored
  };
  // The products coefficient-wise (lazyProduct): a 3-column block is too small for Eigen's
  // general product, whose packing cost more than the arithmetic.
  switch (L.lin.residual.size()) {
    case 9:  // ImuFactor
      AddChainGram<9>(L.lin, col, nb, add, g_lo, g_hi);
      break;
    case 6:  // BiasRandomWalkFactor
      AddChainGram<6>(L.lin, col, nb, add, g_lo, g_hi);
      break;
    case 3:  // a fix, a drift
      AddChainGram<3>(L.lin, col, nb, add, g_lo, g_hi);
      break;
    default:
      AddChainGram<Eigen::Dynamic>(L.lin, col, nb, add, g_lo, g_hi);
  }
}

NavGraph::ChainIndex NavGraph::IndexChain() const {
  const size_t n = keyframes_.size();
  const auto index = [this](KeyframeId id) { return IndexOf(id); };
  ChainIndex chain;
  std::vector<std::pair<size_t, const Factor*>> spans;
  spans.reserve(factors_.size());
  chain.start.assign(n + 1, 0);
  for (const auto& [fid, f] : factors_) {
    const std::pair<size_t, size_t> span = ChainSpan(f->blocks, index);
    if (span.first == SIZE_MAX) continue;  // a prior on extrinsics alone
    spans.emplace_back(span.first, f.get());
    ++chain.start[span.first + 1];
  }
  for (size_t k = 0; k < n; ++k) chain.start[k + 1] += chain.start[k];
  chain.factors.resize(spans.size());
  std::vector<size_t> next(chain.start.begin(), chain.start.end() - 1);
  for (const auto& [lo, f] : spans) chain.factors[next[lo]++] = f;
  return chain;
}

bool NavGraph::AssembleChainStep(const ChainIndex& chain,
                                 size_t k,
                                 Linearized* L,
                                 Mat* D,
                                 Mat* O,
                                 Mat* D_next,
                                 Vec* g,
                                 Vec* g_next,
                                 const Arrow* arrow,
                                 Eigen::Matrix<double, kN, Eigen::Dynamic>* C,
                                 Eigen::Matrix<double, kN, Eigen::Dynamic>* C_next,
                                 Eigen::MatrixXd* E,
                                 Eigen::VectorXd* g_e,
                                 const Linearized* linearized) const {
  O->setZero();
  D_next->setZero();
  if (g_next != nullptr) g_next->setZero();
  for (size_t i = chain.start[k]; i < chain.start[k + 1]; ++i) {
    const Factor& f = *chain.factors[i];
    const Linearized* lin = L;
    if (linearized != nullptr && f.kind == FactorKind::kSensor) {
      lin = &linearized[i - chain.start[k]];
    } else if (!LinearizeFactor(f, false, L)) {
      return false;
    }
    const bool two = ChainSpan(f.blocks, [this](KeyframeId id) { return IndexOf(id); }).second > k;
    AddFactorInformation(f, *lin, k, D, two ? D_next : nullptr, two ? O : nullptr, g,
                         two ? g_next : nullptr);
    if (arrow != nullptr) AddArrowInformation(f, *lin, k, *arrow, C, C_next, E, g_e);
  }
  AddPlaceholderInformation(estimate_gnss_bias_, D);
  return true;
}

bool NavGraph::LinearizeChainFactors(const ChainIndex& chain,
                                     size_t first,
                                     size_t last,
                                     int threads,
                                     std::vector<Linearized>* out) const {
  if (out->size() < last - first) out->resize(last - first);
  // The sensors' blocks alone: a camera frame's costs milliseconds, an IMU factor's microseconds,
  // and those are cheaper linearised where they are added (held for a chunk, the IMU's Jacobians
  // left the cache and made the hour at sea slower on two threads than on one).
  std::vector<size_t> heavy;  // not thread_local: the helpers read this thread's
  for (size_t i = first; i < last; ++i) {
    if (chain.factors[i]->kind == FactorKind::kSensor) heavy.push_back(i);
  }
  return ParallelFor(heavy.size(), threads, [&](size_t j) {
    return LinearizeFactor(*chain.factors[heavy[j]], false, &(*out)[heavy[j] - first]);
  });
}

int NavGraph::Arrow::ColumnOf(const BlockRef& b) const { return ColumnAmong(blocks, col, b); }

void NavGraph::Arrow::Add(const BlockRef& b) {
  blocks.push_back(b);
  col.push_back(dim);
  dim += TangentSize(SlotSize(b.slot));
}

NavGraph::Arrow NavGraph::EstimatedSensorBlocks() const {
  Arrow arrow;
  for (const auto& [sensor, e] : extrinsics_) {
    if (!e->estimated) continue;
    for (const BlockRef& b : ExtrinsicBlocks(sensor)) arrow.Add(b);
  }
  for (const auto& [sensor, p] : parameters_) {
    if (p->estimated) arrow.Add(SensorParameterBlock(sensor));
  }
  if (imu_calibration_) arrow.Add(ImuCalibrationBlock());
  if (arrow.dim > 0) CollectOwnFactors(&arrow);
  return arrow;
}

void NavGraph::CollectOwnFactors(Arrow* arrow) const {
  const auto index = [this](KeyframeId id) { return IndexOf(id); };
  for (const auto& [fid, f] : factors_) {
    if (ChainSpan(f->blocks, index).first != SIZE_MAX) continue;
    if (std::any_of(f->blocks.begin(), f->blocks.end(),
                    [arrow](const BlockRef& b) { return arrow->ColumnOf(b) >= 0; })) {
      arrow->own_factors.push_back(f.get());
    }
  }
}

namespace {
// AddArrowInformation's products with R rows fixed as AddChainGram's. Block b goes to
// where[b] (0: nowhere, 1: C_lo, 2: C_hi, 3: E) from row[b] on.
template <int R>
void AddArrowGram(const LinearizedResidual& lin,
                  size_t nb,
                  const std::array<int, 16>& arrow_col,
                  const std::array<int, 16>& row,
                  const std::array<int, 16>& where,
                  Eigen::Matrix<double, kN, Eigen::Dynamic>* C_lo,
                  Eigen::Matrix<double, kN, Eigen::Dynamic>* C_hi,
                  Eigen::MatrixXd* E,
                  Eigen::VectorXd* g_e) {
  const Eigen::Map<const Eigen::Matrix<double, R, 1>> r(lin.residual.data(), lin.residual.size());
  for (size_t a = 0; a < nb; ++a) {
    const int ca = arrow_col[a];
    if (ca < 0) continue;
    const RowsMap<R> Ja = Rows<R>(lin.jacobians[a]);
    g_e->segment(ca, Ja.cols()).noalias() += Ja.transpose().lazyProduct(r);
    for (size_t b = 0; b < nb; ++b) {
      if (where[b] == 0) continue;
      const RowsMap<R> Jb = Rows<R>(lin.jacobians[b]);
      if (where[b] == 3) {
        E->block(row[b], ca, Jb.cols(), Ja.cols()).noalias() += Jb.transpose().lazyProduct(Ja);
      } else {
        (where[b] == 1 ? C_lo : C_hi)->block(row[b], ca, Jb.cols(), Ja.cols()).noalias() +=
            Jb.transpose().lazyProduct(Ja);
      }
    }
  }
}
}  // namespace

void NavGraph::AddArrowInformation(const Factor& f,
                                   const Linearized& L,
                                   size_t lo,
                                   const Arrow& arrow,
                                   Eigen::Matrix<double, kN, Eigen::Dynamic>* C_lo,
                                   Eigen::Matrix<double, kN, Eigen::Dynamic>* C_hi,
                                   Eigen::MatrixXd* E,
                                   Eigen::VectorXd* g_e) const {
  const size_t nb = f.blocks.size();
  std::array<int, 16> arrow_col{};  // the block's column in the arrow, -1 for keyframe blocks
  std::array<int, 16> row{};        // its first row in C (keyframe blocks) or E (arrow blocks)
  std::array<int, 16> where{};      // 0: none, 1: C_lo, 2: C_hi, 3: E
  if (nb > arrow_col.size()) throw std::logic_error("NavGraph: factor with more than 16 blocks");
  bool any = false;
  for (size_t b = 0; b < nb; ++b) {
    const BlockRef& rb = f.blocks[b];
    arrow_col[b] = -1;
    where[b] = 0;
    if (IsSensorBlock(rb.slot)) {
      arrow_col[b] = arrow.ColumnOf(rb);
      any |= arrow_col[b] >= 0;
      row[b] = arrow_col[b];
      where[b] = arrow_col[b] >= 0 ? 3 : 0;
    } else if (lo != SIZE_MAX && !(rb.slot == Slot::kGb && !estimate_gnss_bias_)) {
      row[b] = kSlotTangent[static_cast<int>(rb.slot)];
      where[b] = IndexOf(rb.keyframe) == lo ? 1 : 2;
    }
  }
  if (!any) return;
  // Coefficient-wise, as in AddFactorInformation: 3 x m blocks are too small for Eigen's
  // general product and its packing.
  switch (L.lin.residual.size()) {
    case 9:  // ImuFactor
      AddArrowGram<9>(L.lin, nb, arrow_col, row, where, C_lo, C_hi, E, g_e);
      break;
    case 6:  // BiasRandomWalkFactor
      AddArrowGram<6>(L.lin, nb, arrow_col, row, where, C_lo, C_hi, E, g_e);
      break;
    case 3:  // a fix, a drift
      AddArrowGram<3>(L.lin, nb, arrow_col, row, where, C_lo, C_hi, E, g_e);
      break;
    default:
      AddArrowGram<Eigen::Dynamic>(L.lin, nb, arrow_col, row, where, C_lo, C_hi, E, g_e);
  }
}

bool NavGraph::BuildChain(std::vector<Mat>* D,
                          std::vector<Mat>* O,
                          const Arrow& arrow,
                          std::vector<Eigen::Matrix<double, kN, Eigen::Dynamic>>* C,
                          Eigen::MatrixXd* E) const {
  const size_t n = keyframes_.size();
  const auto index = [this](KeyframeId id) { return IndexOf(id); };
  D->assign(n, Mat::Zero());
  O->assign(n > 0 ? n - 1 : 0, Mat::Zero());
  C->assign(n, Eigen::Matrix<double, kN, Eigen::Dynamic>::Zero(kN, arrow.dim));
  E->setZero(arrow.dim, arrow.dim);
  Eigen::VectorXd g_e = Eigen::VectorXd::Zero(arrow.dim);  // not wanted here
  Linearized L;  // reused: its matrices keep their storage from factor to factor
  for (const auto& [fid, f] : factors_) {
    if (!LinearizeFactor(*f, false, &L)) return false;
    const auto [lo, hi] = ChainSpan(f->blocks, index);
    // A prior on sensor blocks alone (lo = SIZE_MAX) has the arrow's share only.
    AddArrowInformation(*f, L, lo, arrow, lo == SIZE_MAX ? nullptr : &(*C)[lo],
                        lo != SIZE_MAX && hi > lo ? &(*C)[hi] : nullptr, E, &g_e);
    if (lo == SIZE_MAX) continue;
    AddFactorInformation(*f, L, lo, &(*D)[lo], hi > lo ? &(*D)[hi] : nullptr,
                         hi > lo ? &(*O)[lo] : nullptr, nullptr, nullptr);
  }
  for (Mat& d : *D) AddPlaceholderInformation(estimate_gnss_bias_, &d);
  return true;
}

namespace {
// Jacobi-scales a block-tridiagonal information in place, keyframe by keyframe (JacobiScale):
// D_k <- d_k^-1 D_k d_k^-1, O_k <- d_k^-1 O_k d_k+1^-1. Returns the d_k. The eliminations below
// then subtract O(1) terms instead of 1e20-scale ones; a covariance Sigma_s of the scaled problem
// is d_k^-1 Sigma_s d_k^-1 of the original.
std::vector<Eigen::Matrix<double, kN, 1>> ScaleChain(std::vector<Mat>* D, std::vector<Mat>* O) {
  std::vector<Eigen::Matrix<double, kN, 1>> d_inv(D->size());
  for (size_t k = 0; k < D->size(); ++k) {
    d_inv[k] = JacobiScale((*D)[k]).cwiseInverse();
    (*D)[k] = d_inv[k].asDiagonal() * (*D)[k] * d_inv[k].asDiagonal();
  }
  for (size_t k = 0; k < O->size(); ++k) {
    (*O)[k] = d_inv[k].asDiagonal() * (*O)[k] * d_inv[k + 1].asDiagonal();
  }
  return d_inv;
}
}  // namespace

// Square-root forward elimination along the chain (a square-root information filter: Bierman,
// "Factorization Methods for Discrete Sequential Estimation", 1977; Dellaert & Kaess, "Square
// Root SAM", IJRR 2006, on QR of the measurement Jacobian): the whitened rows of every factor
// whose oldest keyframe is k, with the rows carried onto k from k-1, are reduced by a Householder
// QR over the columns [k | k+1]; the first kN rows of R eliminate k, the next ones (on k+1 only)
// are carried. At the newest keyframe R_nn gives Cov = R_nn^-1 R_nn^-T, positive semi-definite
// by construction and with the conditioning of J, not of J^T J. The information-form recursion
// (S_k+1 = D_k+1 - O_k^T S_k^-1 O_k) cancels when a keyframe holds some directions to 1e-5 and
// others to metres (a sea horizon's roll against a position known to 20 m) and came out
// indefinite: negative variances in covariances.csv.
bool NavGraph::NewestCovariance(GraphCovariance* covariance) const {
  if (keyframes_.empty()) return false;
  // The estimated sensor blocks (the arrow) ride along as extra columns of the same pass, so that
  // R at the newest is the joint [x_n | e] and its inverse gives x_n's full marginal. Where that
  // cannot be had (a keyframe inside the window not determined on its own, an arrow that its
  // rows do not determine), the chain's pass conditional on the arrow and ArrowMarginals'
  // correction in information form, as before.
  const Arrow arrow = EstimatedSensorBlocks();
  if (arrow.dim == 0 || !NewestSqrtCovariance(arrow, covariance)) {
    if (!NewestSqrtCovariance(Arrow{}, covariance)) return false;
    AddArrowUncertainty(ArrowSpan::kNewest,
                        [covariance](size_t, const Eigen::Matrix<double, kN, Eigen::Dynamic>& U) {
                          covariance->noalias() += U * U.transpose();
                        });
  }
  ClearConstantBlocks(estimate_gnss_bias_, covariance);
  return covariance->allFinite();
}

bool NavGraph::NewestSqrtCovariance(const Arrow& arrow, GraphCovariance* covariance) const {
  const size_t n = keyframes_.size();
  const Eigen::Index a = arrow.dim;
  std::vector<KeyframeId> ids;
  for (const Keyframe* kf : keyframes_by_index_) ids.push_back(kf->id);
  const auto index = [this](KeyframeId id) { return IndexOf(id); };
  // Whitened rows on [k | k+1 | arrow], by the factor's oldest keyframe; a prior on sensor blocks
  // alone goes with the newest (with no arrow it has no columns here).
  std::vector<std::vector<Eigen::MatrixXd>> rows(n);
  Linearized L;  // reused: its matrices keep their storage from factor to factor
  for (const auto& [fid, f] : factors_) {
    const auto [lo, hi] = ChainSpan(f->blocks, index);
    if (lo == SIZE_MAX && a == 0) continue;
    if (!LinearizeFactor(*f, false, &L)) return false;
    const bool on_chain = lo != SIZE_MAX;
    rows[on_chain ? lo : n - 1].push_back(ScatterWithArrow(
        *f, L, on_chain ? &ids[lo] : nullptr, on_chain ? &ids[hi > lo ? hi : lo] : nullptr, arrow));
  }
  if (!estimate_gnss_bias_) {
    for (size_t k = 0; k < n; ++k) rows[k].push_back(PlaceholderRows(kGraphGb, 2 * kN + a));
  }
  Eigen::MatrixXd carry(0, kN + a), QR;
  for (size_t k = 0; k < n; ++k) {
    const bool last = k + 1 == n;
    if (!EliminateKeyframe(rows[k], last, a, &carry, &QR)) {
      // k is not determined: with no arrow it absorbs whatever ties it to k+1; with one, that
      // would drop what the carried rows know of the arrow, so the caller falls back.
      if (last || a > 0) return false;
      carry.resize(0, kN);
      continue;
    }
    if (last) {
      const Eigen::MatrixXd R = QR.topLeftCorner(kN + a, kN + a).triangularView<Eigen::Upper>();
      if (!(R.diagonal().array().abs() > 0.0).all()) return false;
      const Eigen::MatrixXd R_inv =
          R.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(kN + a, kN + a));
      *covariance = R_inv.topRows(kN) * R_inv.topRows(kN).transpose();
    }
  }
  return true;
}

void NavGraph::AddArrowUncertainty(
    ArrowSpan span,
    const std::function<void(size_t, const Eigen::Matrix<double, kN, Eigen::Dynamic>&)>& add)
    const {
  const Arrow arrow = EstimatedSensorBlocks();
  if (arrow.dim == 0) return;
  std::vector<Eigen::Matrix<double, kN, Eigen::Dynamic>> U;
  Eigen::MatrixXd covariance;
  // An arrow without a positive definite marginal cannot happen with its priors in the graph;
  // the covariances then stay conditional on the sensor blocks, as they were without this.
  if (!ArrowMarginals(arrow.blocks, span, &covariance, &U)) return;
  if (span == ArrowSpan::kNewest) {
    add(keyframes_.size() - 1, U[0]);
  } else {
    for (size_t k = 0; k < U.size(); ++k) add(k, U[k]);
  }
}

bool NavGraph::NewestCovariance(StateCovariance* covariance) const {
  GraphCovariance P;
  if (!NewestCovariance(&P)) return false;
  *covariance = P.topLeftCorner<kStateDim, kStateDim>();
  return true;
}

bool NavGraph::AllCovariances(std::vector<GraphCovariance>* covariances) const {
  covariances->assign(keyframes_.size(), Mat::Zero());
  return ForEachMarginal([covariances](size_t k, const Mat& P) { (*covariances)[k] = P; });
}

bool NavGraph::AllCovariances(std::vector<StateCovariance>* covariances) const {
  covariances->assign(keyframes_.size(), StateCovariance::Zero());
  return ForEachMarginal([covariances](size_t k, const Mat& P) {
    (*covariances)[k] = P.topLeftCorner<kStateDim, kStateDim>();
  });
}

bool NavGraph::AllCovariances(
    const std::function<void(size_t, const StateCovariance&)>& each) const {
  return AllCovariances(each, nullptr);
}

bool NavGraph::AllCovariances(const std::function<void(size_t, const StateCovariance&)>& each,
                              SensorBlocksCovariance* sensor_blocks) const {
  return ForEachMarginal(
      [&each](size_t k, const Mat& P) { each(k, P.topLeftCorner<kStateDim, kStateDim>()); },
      sensor_blocks);
}

bool NavGraph::SensorBlocksCovariance::Of(const std::vector<BlockRef>& refs,
                                          Eigen::MatrixXd* marginal) const {
  if (refs.empty() || covariance.size() == 0) return false;
  int first = -1, size = 0;
  for (const BlockRef& r : refs) {
    const int c = ColumnAmong(blocks, col, r);
    if (c < 0) return false;
    if (first < 0) first = c;
    if (c != first + size) return false;  // not adjacent, or out of order
    size += TangentSize(SlotSize(r.slot));
  }
  *marginal = covariance.block(first, first, size, size);
  return true;
}

bool NavGraph::ForEachMarginal(const std::function<void(size_t, const Mat&)>& each,
                               SensorBlocksCovariance* sensor_blocks) const {
  // With estimated sensor blocks, in either form, the square-root pass with the arrow in it
  // gives the full marginals (ForEachCovarianceSqrt). It fails, if at all, in its first forward
  // pass, before handing out any covariance; then the covariances conditional on the arrow plus
  // ArrowMarginals' share, which linearises the chain again and holds its whole information at
  // once (6.5 kB a keyframe with the gyro's calibration: 233 MB over the hour at sea).
  const Arrow arrow = EstimatedSensorBlocks();
  if (sensor_blocks != nullptr) {
    sensor_blocks->blocks = arrow.blocks;
    sensor_blocks->col = arrow.col;
    sensor_blocks->covariance.resize(0, 0);
  }
  if (arrow.dim > 0) {
    bool handed_out = false;
    const bool ok = ForEachCovariance(
        [&](size_t k, const Mat& P) {
          handed_out = true;
          each(k, P);
        },
        &arrow, sensor_blocks != nullptr ? &sensor_blocks->covariance : nullptr);
    if (ok || handed_out) return ok;
    if (sensor_blocks != nullptr) sensor_blocks->covariance.resize(0, 0);
  }
  std::vector<Eigen::Matrix<double, kN, Eigen::Dynamic>> U;
  AddArrowUncertainty(ArrowSpan::kAll,
                      [&U](size_t k, const Eigen::Matrix<double, kN, Eigen::Dynamic>& u) {
                        if (U.size() <= k) U.resize(k + 1);
                        U[k] = u;
                      });
  if (U.empty()) return ForEachCovariance(each);
  return ForEachCovariance([&](size_t k, const Mat& P) {
    Mat Q = P;
    if (k < U.size()) Q.noalias() += U[k] * U[k].transpose();
    ClearConstantBlocks(estimate_gnss_bias_, &Q);
    each(k, Q);
  });
}

namespace {
// One step of the backward (Rauch-Tung-Striebel) recursion over the chain, with the arrow e
// beside it: row block k reads x_k = w_k - G_k x_k+1 - H_k e, w_k of covariance P_k and
// independent of x_k+1 and e, so Sigma_k = P_k + [G_k H_k] [Sigma_k+1 Sigma_k+1,e;
// Sigma_e,k+1 Sigma_ee] [G_k H_k]^T and Sigma_k,e = -(G_k Sigma_k+1,e + H_k Sigma_ee).
// `G` null for the newest keyframe, `H` null without an arrow. On entry *sigma and *sigma_e are
// keyframe k+1's, on return k's. The arrow's products coefficient-wise (lazyProduct): at 18 x m
// Eigen's general product spends more on packing than on the arithmetic.
void BackwardStep(const Mat& P,
                  const Mat* G,
                  const Eigen::Matrix<double, kN, Eigen::Dynamic>* H,
                  const Eigen::MatrixXd& sigma_ee,
                  Mat* sigma,
                  Eigen::Matrix<double, kN, Eigen::Dynamic>* sigma_e) {
  using MatE = Eigen::Matrix<double, kN, Eigen::Dynamic>;
  Mat next = P;
  if (G != nullptr) next += *G * *sigma * G->transpose();
  if (H != nullptr) {
    const MatE H_ee = H->lazyProduct(sigma_ee);
    MatE next_e = -H_ee;
    if (G != nullptr) {
      const MatE G_ne = G->lazyProduct(*sigma_e);
      const Mat cross = G_ne.lazyProduct(H->transpose());
      next += cross + cross.transpose();
      next_e -= G_ne;
    }
    next.noalias() += H_ee.lazyProduct(H->transpose());
    *sigma_e = std::move(next_e);
  }
  *sigma = next;
}
}  // namespace

// The RTS smoother in information form for the block-tridiagonal H, Jacobi-scaled keyframe by
// keyframe (JacobiScale: D_k <- d_k^-1 D_k d_k^-1, O_k <- d_k^-1 O_k d_k+1^-1, so that the
// eliminations subtract O(1) terms instead of 1e20-scale ones; Sigma = d^-1 Sigma_s d^-1).
// Forward: S_0 = D_0, P_k = S_k^-1, G_k = P_k O_k, S_k+1 = D_k+1 - O_k^T G_k. Backward:
// Sigma_n-1 = P_n-1, Sigma_k = P_k + G_k Sigma_k+1 G_k^T. The backward pass needs P_k and G_k
// of every keyframe, two 18x18 blocks (5.2 kB): over an hour at 10 Hz that was 187 MB. Instead
// the forward pass keeps its pivot S_a at every kSegment-th keyframe a (a checkpoint), and the
// backward pass runs segment by segment, newest first, redoing the segment's forward pass
// from its checkpoint (Griewank & Walther, "Evaluating Derivatives", 2nd ed., ch. 12, on
// checkpointing a reversed recursion): memory of one segment, at most one more linearisation of
// every factor (none for a run of up to kSegment keyframes).
bool NavGraph::ForEachCovariance(const std::function<void(size_t, const Mat&)>& each,
                                 const Arrow* arrow,
                                 Eigen::MatrixXd* sigma_ee_out) const {
  if (covariance_form_ == CovarianceForm::kSquareRoot) {
    return ForEachCovarianceSqrt(each, arrow, sigma_ee_out);
  }
  const size_t n = keyframes_.size();
  if (n == 0) return false;
  const Eigen::Index m = arrow != nullptr ? arrow->dim : 0;
  using MatE = Eigen::Matrix<double, kN, Eigen::Dynamic>;
  bool indefinite = false;  // a pivot S_k came out indefinite in the first forward pass
  const size_t kSegment = covariance_segment_;  // P, G and d of a segment: 5.3 kB a keyframe
  const auto at = [kSegment](size_t k) { return k % kSegment; };
  const ChainIndex chain = IndexChain();
  const size_t num_segments = (n + kSegment - 1) / kSegment;
  std::vector<Mat> checkpoint_S(num_segments);
  std::vector<Vec> checkpoint_d(num_segments);
  std::vector<Mat> P(std::min(n, kSegment)), G(std::min(n, kSegment));
  std::vector<Vec> d(std::min(n, kSegment));  // d_k^-1 (the scaling is D_k <- d D_k d)
  // The arrow: Y_k (keyframe k's coupling to it once the chain before k is eliminated), kept at
  // the checkpoints; H_k = P_k Y_k over the segment; E and sum_k Y_k^T P_k Y_k from the first
  // pass (the passes after it add into `E_again`, unused).
  std::vector<MatE> checkpoint_Y(m > 0 ? num_segments : 0);
  std::vector<MatE> H(m > 0 ? std::min(n, kSegment) : 0);
  MatE C, C_next, Y, Y_prev;
  Eigen::MatrixXd E = Eigen::MatrixXd::Zero(m, m), E_again = E, YPY = E;
  Eigen::VectorXd g_e = Eigen::VectorXd::Zero(m);  // not wanted here
  bool first_pass = true;
  Linearized L;
  Mat D, D_next, O, O_prev;
  // Forward over [a, end), from the checkpoint at a when a > 0: P_k, d_k and G_k-1 of the
  // segment; the pivot of every multiple of kSegment kept as a checkpoint.
  auto forward = [&](size_t a, size_t end) -> bool {
    D.setZero();
    if (m > 0) C.setZero(kN, m);
    Vec d_prev;
    for (size_t k = a; k < end; ++k) {
      if (m > 0) C_next.setZero(kN, m);
      if (!AssembleChainStep(chain, k, &L, &D, &O, &D_next, nullptr, nullptr,
                             m > 0 ? arrow : nullptr, m > 0 ? &C : nullptr,
                             m > 0 ? &C_next : nullptr, first_pass ? &E : &E_again, &g_e)) {
        return false;
      }
      Mat S;
      Vec d_k;
      if (k == a && a > 0) {  // D_a (C_a) lacks the share of a-1's factors: the checkpoint has it
        S = checkpoint_S[k / kSegment];
        d_k = checkpoint_d[k / kSegment];
        if (m > 0) Y = checkpoint_Y[k / kSegment];
      } else {
        d_k = JacobiScale(D).cwiseInverse();
        S = d_k.asDiagonal() * D * d_k.asDiagonal();
        if (m > 0) Y = d_k.asDiagonal() * C;
        if (k > a) {
          const Mat O_scaled = d_prev.asDiagonal() * O_prev * d_k.asDiagonal();
          G[at(k - 1)] = P[at(k - 1)] * O_scaled;
          S -= O_scaled.transpose() * G[at(k - 1)];
          if (m > 0) {  // Y_k = C_k - G_k-1^T Y_k-1
            Y.noalias() -= G[at(k - 1)].transpose().lazyProduct(Y_prev);
          }
        }
        if (k % kSegment == 0) {
          checkpoint_S[k / kSegment] = S;
          checkpoint_d[k / kSegment] = d_k;
          if (m > 0) checkpoint_Y[k / kSegment] = Y;
        }
      }
      d[at(k)] = d_k;
      bool not_positive = false;
      P[at(k)] = InverseSpd(S, &not_positive);
      indefinite |= not_positive;
      if (m > 0) {
        H[at(k)].noalias() = P[at(k)].lazyProduct(Y);  // coefficient-wise: 18 x m is small
        if (first_pass) YPY.noalias() += Y.transpose().lazyProduct(H[at(k)]);
        Y_prev = Y;
        std::swap(C, C_next);
      }
      d_prev = d_k;
      O_prev = O;
      D = D_next;
    }
    return true;
  };
  // Backward as ForEachCovarianceSqrt's with its arrow: x_k = P_k r_k - G_k x_k+1 - H_k e.
  Mat sigma_next;            // scaled Sigma of the keyframe after the one at hand
  MatE sigma_next_e;         // its Cov(x_k+1, e), the chain's rows scaled
  Eigen::MatrixXd sigma_ee;  // the arrow's marginal, E - sum_k Y_k^T P_k Y_k inverted
  auto backward = [&](size_t a, size_t end) {
    for (size_t k = end; k-- > a;) {
      BackwardStep(P[at(k)], k + 1 < n ? &G[at(k)] : nullptr, m > 0 ? &H[at(k)] : nullptr, sigma_ee,
                   &sigma_next, &sigma_next_e);
      Mat covariance = d[at(k)].asDiagonal() * sigma_next * d[at(k)].asDiagonal();
      ClearConstantBlocks(estimate_gnss_bias_, &covariance);
      each(k, covariance);
    }
  };
  // Pass 1 writes every segment into the same storage: the newest one is left. It visits every
  // pivot before any covariance is handed out: an indefinite one (the subtraction cancelled: a
  // LiDAR holding a harbour vessel's position to centimetres beside a GNSS drift state of metres
  // left negative variances in covariances.csv) sends the whole chain to the square-root form.
  if (m > 0) {  // the arrow's own priors
    for (const Factor* f : arrow->own_factors) {
      if (!LinearizeFactor(*f, false, &L)) return false;
      AddArrowInformation(*f, L, SIZE_MAX, *arrow, nullptr, nullptr, &E, &g_e);
    }
  }
  if (!forward(0, n)) return false;
  first_pass = false;
  if (indefinite) {
    spdlog::debug("covariances: an information pivot is indefinite, square-root form instead");
    return ForEachCovarianceSqrt(each, arrow, sigma_ee_out);
  }
  if (m > 0) {  // the arrow's Schur complement, Jacobi-scaled by diag(E)^-1/2 to be inverted
    const Eigen::VectorXd e_inv = JacobiScale(E).cwiseInverse();
    const Eigen::MatrixXd schur = e_inv.asDiagonal() * (E - YPY) * e_inv.asDiagonal();
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(0.5 * (schur + schur.transpose()));
    if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) {
      spdlog::debug(
          "covariances: the sensor blocks' Schur complement is indefinite, square-root "
          "form instead");
      return ForEachCovarianceSqrt(each, arrow, sigma_ee_out);
    }
    sigma_ee =
        e_inv.asDiagonal() * ldlt.solve(Eigen::MatrixXd::Identity(m, m)) * e_inv.asDiagonal();
    if (sigma_ee_out != nullptr) *sigma_ee_out = sigma_ee;
  }
  const size_t newest = (num_segments - 1) * kSegment;
  backward(newest, n);
  for (size_t a = newest; a > 0;) {
    const size_t end = a;
    a -= kSegment;
    if (!forward(a, end)) return false;
    const Mat O_scaled =
        d[at(end - 1)].asDiagonal() * O_prev * checkpoint_d[end / kSegment].asDiagonal();
    G[at(end - 1)] = P[at(end - 1)] * O_scaled;
    backward(a, end);
  }
  return true;
}

// The RTS recursion above in square-root form (Bierman 1977; Dellaert & Kaess 2006, as
// NewestCovariance): the whitened rows of the factors whose oldest keyframe is k, with the rows
// carried onto k from k-1, reduced by a Householder QR over the columns [k | k+1], give
// [R_kk R_kk+1] for k and the rows carried onto k+1. x_k = -R_kk^-1 R_kk+1 x_k+1 + R_kk^-1 e, so
// Sigma_k = P_k + G_k Sigma_k+1 G_k^T with P_k = R_kk^-1 R_kk^-T and G_k = R_kk^-1 R_kk+1 (the
// sign does not matter): every term a Gram matrix, positive semi-definite by construction. The
// carried rows at every kSegment-th keyframe are its checkpoints, as the pivots are above.
//
// With an arrow (the estimated sensor blocks e, `arrow` non-empty) its columns ride along, never
// eliminated, as in NewestSqrtCovariance: row block k reads R_kk x_k + R_k,k+1 x_k+1 + R_ke e,
// so x_k = -G_k x_k+1 - H_k e + w_k with H_k = R_kk^-1 R_ke, and the newest's R gives
// Sigma_ee = R_ee^-1 R_ee^-T. Backward, with Sigma_k,e = Cov(x_k, e):
// Sigma_k = P_k + [G_k H_k] [Sigma_k+1 Sigma_k+1,e; Sigma_e,k+1 Sigma_ee] [G_k H_k]^T and
// Sigma_k,e = -(G_k Sigma_k+1,e + H_k Sigma_ee): the full marginals, with one more 18 x m block
// per keyframe of the segment and no second pass over the chain's information.
bool NavGraph::ForEachCovarianceSqrt(const std::function<void(size_t, const Mat&)>& each,
                                     const Arrow* arrow,
                                     Eigen::MatrixXd* sigma_ee_out) const {
  const size_t n = keyframes_.size();
  if (n == 0) return false;
  const Eigen::Index a = arrow != nullptr ? arrow->dim : 0;
  using MatE = Eigen::Matrix<double, kN, Eigen::Dynamic>;
  const size_t kSegment = covariance_segment_;
  const auto at = [kSegment](size_t k) { return k % kSegment; };
  const ChainIndex chain = IndexChain();
  std::vector<KeyframeId> ids;
  for (const Keyframe* kf : keyframes_by_index_) ids.push_back(kf->id);
  const auto index = [this](KeyframeId id) { return IndexOf(id); };
  const size_t num_segments = (n + kSegment - 1) / kSegment;
  std::vector<Eigen::MatrixXd> checkpoint(num_segments);
  std::vector<Mat> P(std::min(n, kSegment)), G(std::min(n, kSegment));
  std::vector<MatE> H(a > 0 ? std::min(n, kSegment) : 0);
  Eigen::MatrixXd sigma_ee;  // the arrow's marginal, from the newest's R
  Linearized L;
  std::vector<Eigen::MatrixXd> rows;
  Eigen::MatrixXd carry(0, kN + a), QR;
  const Arrow no_arrow;
  // The rows of a factor whose oldest keyframe is k (`first`, `second`; none: a prior on sensor
  // blocks alone).
  auto add_rows = [&](const Factor& f, const KeyframeId* first, const KeyframeId* second) {
    if (!LinearizeFactor(f, false, &L)) return false;
    rows.push_back(ScatterWithArrow(f, L, first, second, a > 0 ? *arrow : no_arrow));
    return true;
  };
  // The first pass over [0, n) keeps P, G and H of the newest segment only (`keep_from`): the
  // others are redone from their checkpoints on the way back.
  auto forward = [&](size_t a0, size_t end, size_t keep_from) -> bool {
    carry = a0 > 0 ? checkpoint[a0 / kSegment] : Eigen::MatrixXd(0, kN + a);
    for (size_t k = a0; k < end; ++k) {
      if (k % kSegment == 0) checkpoint[k / kSegment] = carry;
      const bool last = k + 1 == n;
      rows.clear();
      for (size_t i = chain.start[k]; i < chain.start[k + 1]; ++i) {
        const Factor& f = *chain.factors[i];
        const size_t hi = ChainSpan(f.blocks, index).second;
        if (!add_rows(f, &ids[k], hi > k ? &ids[hi] : &ids[k])) return false;
      }
      if (k == 0 && a > 0) {  // the arrow's own priors, carried from the first keyframe on
        for (const Factor* f : arrow->own_factors) {
          if (!add_rows(*f, nullptr, nullptr)) return false;
        }
      }
      if (!estimate_gnss_bias_) rows.push_back(PlaceholderRows(kGraphGb, 2 * kN + a));
      if (!EliminateKeyframe(rows, last, a, &carry, &QR)) return false;  // k is not determined
      const Mat R = QR.topLeftCorner(kN, kN).triangularView<Eigen::Upper>();
      if (!(R.diagonal().array().abs() > 0.0).all()) return false;
      if (k < keep_from) continue;
      const Mat R_inv = R.triangularView<Eigen::Upper>().solve(Mat::Identity());
      P[at(k)] = R_inv * R_inv.transpose();
      if (!last) G[at(k)] = R_inv * QR.block(0, kN, kN, kN);
      if (a > 0) H[at(k)] = R_inv * QR.block(0, last ? kN : 2 * kN, kN, a);
      if (last && a > 0 && sigma_ee.size() == 0) {
        const Eigen::MatrixXd R_ee = QR.block(kN, kN, a, a).triangularView<Eigen::Upper>();
        if (!(R_ee.diagonal().array().abs() > 0.0).all()) return false;
        const Eigen::MatrixXd R_ee_inv =
            R_ee.triangularView<Eigen::Upper>().solve(Eigen::MatrixXd::Identity(a, a));
        sigma_ee = R_ee_inv * R_ee_inv.transpose();
      }
    }
    return true;
  };
  Mat sigma_next;
  MatE sigma_next_e;  // Cov(x_k+1, e)
  auto backward = [&](size_t a0, size_t end) {
    for (size_t k = end; k-- > a0;) {
      BackwardStep(P[at(k)], k + 1 < n ? &G[at(k)] : nullptr, a > 0 ? &H[at(k)] : nullptr, sigma_ee,
                   &sigma_next, &sigma_next_e);
      Mat covariance = sigma_next;
      ClearConstantBlocks(estimate_gnss_bias_, &covariance);
      each(k, covariance);
    }
  };
  const size_t newest = (num_segments - 1) * kSegment;
  if (!forward(0, n, newest)) return false;
  if (sigma_ee_out != nullptr) *sigma_ee_out = sigma_ee;
  backward(newest, n);
  for (size_t a0 = newest; a0 > 0;) {
    const size_t end = a0;
    a0 -= kSegment;
    if (!forward(a0, end, a0)) return false;
    backward(a0, end);
  }
  return true;
}

namespace {
// PropagateCovariance's algebra on its rows J = [J_prev J_next] (m of them, kN columns each):
// next's covariance given prev's P. With S = J_prev P J_prev^T + I (prev's uncertainty carried
// into the rows' whitened noise) and L L^T = S, the rows L^-1 J_next x_next = L^-1 r are
// whitened, and next's covariance is (A^T A)^-1 with A = L^-1 J_next, taken from a column-pivoted
// QR of A as R^-1 R^-T permuted back. False when S is not positive definite.
bool PropagateThroughRows(const Eigen::MatrixXd& J, const Mat& P, Mat* next_covariance) {
  const Eigen::MatrixXd Jp = J.leftCols(kN);
  Eigen::MatrixXd S = Jp * P * Jp.transpose();
  S.diagonal().array() += 1.0;
  const Eigen::LLT<Eigen::MatrixXd> llt(S);
  if (llt.info() != Eigen::Success) return false;
  const Eigen::MatrixXd A = llt.matrixL().solve(J.rightCols(kN));
  // No rank test: Eigen's default threshold is relative to the largest pivot, and the columns
  // span ten orders (a navigation-grade gyro bias against a unit placeholder). A singular R has
  // a zero pivot, and the covariance then is not finite (PropagateCovariance checks).
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
  const Mat R = qr.matrixR().topLeftCorner(kN, kN).triangularView<Eigen::Upper>();
  const Mat R_inv = R.triangularView<Eigen::Upper>().solve(Mat::Identity());
  const Mat P_perm = R_inv * R_inv.transpose();
  *next_covariance = qr.colsPermutation() * P_perm * qr.colsPermutation().transpose();
  return true;
}

// The same when there are exactly kN rows, the common case (an IMU factor's 9, its bias walk's
// 6 and the GNSS bias's 3, placeholder or drift): J_next is square, and (A^T A)^-1 =
// J_next^-1 S J_next^-T, the textbook propagation. Taken as B B^T with B = J_next^-1 L, a Gram
// matrix (symmetric, positive semi-definite by construction), J_next^-1 by an LU with partial
// pivoting: its pivots do not depend on the columns' scales (ten orders apart, as above), only on
// the rows', which are whitened. A singular J_next leaves B not finite (PropagateCovariance
// checks). Harbour `run`: 120,000 instructions a keyframe here against 212,000 by the path
// above (7 % of a harbour smooth's).
bool PropagateThroughSquareRows(const Eigen::MatrixXd& J, const Mat& P, Mat* next_covariance) {
  const Mat Jp = J.leftCols(kN);
  Mat S = Jp * P * Jp.transpose();
  S.diagonal().array() += 1.0;
  const Eigen::LLT<Mat> llt(S);
  if (llt.info() != Eigen::Success) return false;
  const Eigen::PartialPivLU<Mat> lu(Mat(J.rightCols(kN)));
  const Mat B = lu.solve(Mat(llt.matrixL()));
  *next_covariance = B * B.transpose();
  return true;
}
}  // namespace

// In covariance form, never through the information of `prev`: the factors between the two
// keyframes, linearised and whitened, say r = J_p dx_p + J_n dx_n + e with e ~ N(0, I) and
// dx_p ~ N(0, P). J_p dx_p is then noise of covariance J_p P J_p^T, so (generalised least
// squares) Cov(dx_n) = (J_n^T S^-1 J_n)^-1 with S = I + J_p P J_p^T >= I, computed as
// R^-1 R^-T from the QR factorisation of L^-1 J_n (S = L L^T): a Gram matrix, symmetric and
// positive semi-definite by construction. The information form (the Schur complement of
// [P^-1 + J_p^T J_p, J_p^T J_n; J_n^T J_p, J_n^T J_n] onto dx_n) subtracts terms of the
// interval's precision (1e8 m^-2 for a 0.1 s IMU interval) to leave the weak information of a
// long outage (1e-4 m^-2): twelve digits cancel, and a consumer-grade IMU 45 s into an outage
// came out with negative variances. With exactly kN rows, as J_n^-1 S J_n^-T
// (PropagateThroughSquareRows).
bool NavGraph::PropagateCovariance(KeyframeId prev,
                                   KeyframeId next,
                                   const GraphCovariance& prev_covariance,
                                   GraphCovariance* next_covariance) const {
  std::vector<const Factor*> linking;  // in id order
  // A constant gb: unit rows on next's (below); prev's is touched by no factor, so its covariance
  // does not matter.
  Eigen::Index m = estimate_gnss_bias_ ? 0 : 3;
  for (const auto& [fid, f] : factors_) {
    bool touches_next = false, only_pair = true;
    for (const BlockRef& b : f->blocks) {
      if (IsSensorBlock(b.slot)) continue;
      if (b.keyframe == next) touches_next = true;
      if (b.keyframe != next && b.keyframe != prev) only_pair = false;
    }
    if (!touches_next || !only_pair) continue;
    linking.push_back(f.get());
    m += f->cost->num_residuals();
  }
  if (m < kN) return false;  // next is not determined by what links it to prev
  // Each factor's rows straight into J (one Linearized and one J_f for all of them).
  Eigen::MatrixXd J(m, 2 * kN);
  Linearized L;
  Eigen::MatrixXd J_f;
  Eigen::Index row = 0;
  for (const Factor* f : linking) {
    if (!LinearizeFactor(*f, false, &L)) return false;
    J_f.setZero(L.lin.residual.size(), 2 * kN);
    ScatterJacobian(*f, L, prev, next, &J_f);
    J.middleRows(row, J_f.rows()) = J_f;
    row += J_f.rows();
  }
  if (!estimate_gnss_bias_) J.middleRows(row, 3) = PlaceholderRows(kN + kGraphGb);
  const Mat P = 0.5 * (prev_covariance + prev_covariance.transpose());
  const bool ok = m == kN ? PropagateThroughSquareRows(J, P, next_covariance)
                          : PropagateThroughRows(J, P, next_covariance);
  if (!ok) return false;
  ClearConstantBlocks(estimate_gnss_bias_, next_covariance);
  return next_covariance->allFinite();
}

std::vector<KeyframeId> NavGraph::keyframe_ids() const {
  std::vector<KeyframeId> ids;
  for (const auto& [id, kf] : keyframes_) ids.push_back(id);
  return ids;
}

Eigen::VectorXd NavGraph::FactorResidual(FactorId id) const {
  const Factor& f = *factors_.at(id);
  std::vector<const double*> ptrs;
  for (const BlockRef& b : f.blocks) ptrs.push_back(BlockValue(b));
  Eigen::VectorXd r(f.cost->num_residuals());
  f.cost->Evaluate(ptrs.data(), r.data(), nullptr);
  return r;
}

FactorKind NavGraph::factor_kind(FactorId id) const { return factors_.at(id)->kind; }

const ceres::CostFunction& NavGraph::cost_function(FactorId id) const {
  return *factors_.at(id)->cost;
}

std::vector<FactorId> NavGraph::factor_ids(FactorKind kind) const {
  std::vector<FactorId> ids;
  for (const auto& [id, f] : factors_) {
    if (f->kind == kind) ids.push_back(id);
  }
  return ids;
}

bool NavGraph::ExtrinsicCovariance(SensorId sensor, Eigen::Matrix<double, 6, 6>* covariance) const {
  const Extrinsic& e = *extrinsics_.at(sensor);
  if (!e.estimated || keyframes_.empty()) return false;
  Eigen::MatrixXd cov;
  if (!ArrowCovariance(ExtrinsicBlocks(sensor), &cov)) return false;
  *covariance = cov;
  return true;
}

bool NavGraph::SensorParameterVariance(SensorId sensor, double* variance) const {
  const SensorParameter& s = *parameters_.at(sensor);
  if (!s.estimated || keyframes_.empty()) return false;
  Eigen::MatrixXd cov;
  if (!ArrowCovariance({SensorParameterBlock(sensor)}, &cov)) return false;
  *variance = cov(0, 0);
  return true;
}

bool NavGraph::ImuCalibrationCovariance(
    Eigen::Matrix<double, kImuCalibrationSize, kImuCalibrationSize>* covariance) const {
  if (!imu_calibration_ || keyframes_.empty()) return false;
  Eigen::MatrixXd cov;
  if (!ArrowCovariance({ImuCalibrationBlock()}, &cov)) return false;
  *covariance = cov;
  return true;
}

bool NavGraph::ArrowCovariance(const std::vector<BlockRef>& arrow,
                               Eigen::MatrixXd* covariance) const {
  // ArrowMarginals' forward elimination (there: S_k, Y_k = L^-1 H_ce and the Schur complement
  // H_ee - sum_k Y_k^T S_k^-1 Y_k), run as the chain is assembled keyframe by keyframe
  // (AssembleChainStep): no keyframe's information is held past its step, where BuildChain holds
  // the whole chain's (6.5 kB a keyframe with the gyro's 9 calibration numbers: 234 MB for an
  // hour at sea). Keyframe k is Jacobi-scaled once its D_k is complete, O_k-1 with it; the
  // arrow's columns are scaled at the end, by diag(E)^-1/2 of the whole E.
  using MatC = Eigen::Matrix<double, kN, Eigen::Dynamic>;
  if (keyframes_.empty()) return false;
  Arrow columns;
  for (const BlockRef& b : arrow) columns.Add(b);
  const int m = columns.dim;
  Eigen::MatrixXd E = Eigen::MatrixXd::Zero(m, m);
  Eigen::VectorXd g_e = Eigen::VectorXd::Zero(m);  // not wanted here
  Linearized L;  // reused: its matrices keep their storage from factor to factor
  CollectOwnFactors(&columns);
  for (const Factor* f : columns.own_factors) {  // priors on sensor blocks alone: the arrow's only
    if (!LinearizeFactor(*f, false, &L)) return false;
    AddArrowInformation(*f, L, SIZE_MAX, columns, nullptr, nullptr, &E, &g_e);
  }
  const ChainIndex chain = IndexChain();
  const size_t n = keyframes_.size();
  Mat D = Mat::Zero(), D_next, O, O_prev, S_inv_prev;
  MatC C = MatC::Zero(kN, m), C_next, Y, Y_prev;
  Eigen::Matrix<double, kN, 1> d_prev;
  Eigen::MatrixXd schur = Eigen::MatrixXd::Zero(m, m);  // sum_k Y_k^T S_k^-1 Y_k, E's columns
  for (size_t k = 0; k < n; ++k) {
    C_next.setZero(kN, m);
    if (!AssembleChainStep(chain, k, &L, &D, &O, &D_next, nullptr, nullptr, &columns, &C, &C_next,
                           &E, &g_e)) {
      return false;
    }
    const Eigen::Matrix<double, kN, 1> d = JacobiScale(D).cwiseInverse();
    Mat S = d.asDiagonal() * D * d.asDiagonal();
    Y = d.asDiagonal() * C;
    if (k > 0) {
      const Mat O_s = d_prev.asDiagonal() * O_prev * d.asDiagonal();
      const Mat A = O_s.transpose() * S_inv_prev;  // O_k-1^T S_k-1^-1
      S -= A * O_s;
      Y.noalias() -= A.lazyProduct(Y_prev);
    }
    S_inv_prev = InverseSpd(S);
    schur.noalias() += Y.transpose().lazyProduct(S_inv_prev.lazyProduct(Y).eval());
    Y_prev = Y;
    d_prev = d;
    O_prev = O;
    D = D_next;
    std::swap(C, C_next);
  }
  const Eigen::VectorXd e_inv = JacobiScale(E).cwiseInverse();
  schur = e_inv.asDiagonal() * (E - schur) * e_inv.asDiagonal();
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(0.5 * (schur + schur.transpose()));
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return false;
  *covariance =
      e_inv.asDiagonal() * ldlt.solve(Eigen::MatrixXd::Identity(m, m)) * e_inv.asDiagonal();
  return covariance->allFinite() && (covariance->diagonal().array() > 0.0).all();
}

bool NavGraph::ArrowMarginals(const std::vector<BlockRef>& arrow,
                              ArrowSpan span,
                              Eigen::MatrixXd* covariance,
                              std::vector<Eigen::Matrix<double, kN, Eigen::Dynamic>>* U) const {
  // The information is block-tridiagonal over the keyframes (BuildChain) with an arrow to the
  // sensor blocks: H = [H_cc H_ce; H_ec H_ee], H_ce one 18 x m block per keyframe. Their marginal
  // covariance is (H_ee - H_ec H_cc^-1 H_ce)^-1; with the block LDL^T of H_cc (pivots S_k,
  // Y = L^-1 H_ce by forward elimination), H_ec H_cc^-1 H_ce = sum_k Y_k^T S_k^-1 Y_k. All in
  // Jacobi-scaled units (see MarginalizeOldest). The sensor blocks not in `arrow` are held fixed.
  // U = H_cc^-1 H_ce by back substitution, X_n-1 = S_n-1^-1 Y_n-1, X_k = S_k^-1 (Y_k - O_k
  // X_k+1) (the newest alone needs no back pass).
  using MatC = Eigen::Matrix<double, kN, Eigen::Dynamic>;
  std::vector<Mat> D, O;
  std::vector<MatC> C;
  Eigen::MatrixXd E;
  Arrow columns;
  for (const BlockRef& b : arrow) columns.Add(b);
  if (keyframes_.empty() || !BuildChain(&D, &O, columns, &C, &E)) return false;
  const size_t n = D.size();
  std::vector<Eigen::Matrix<double, kN, 1>> d_inv = ScaleChain(&D, &O);
  const Eigen::VectorXd e_inv = JacobiScale(E).cwiseInverse();
  E = e_inv.asDiagonal() * E * e_inv.asDiagonal();
  for (size_t k = 0; k < C.size(); ++k) C[k] = d_inv[k].asDiagonal() * C[k] * e_inv.asDiagonal();
  // With ArrowSpan::kAll the back pass needs every S_k^-1 and Y_k: they take D_k's and C_k's
  // places, which the forward pass has consumed by then.
  const bool all = span == ArrowSpan::kAll;
  Mat S = D[0];
  MatC Y = C[0];
  Eigen::MatrixXd schur = E;
  MatC X_newest;
  for (size_t k = 0;; ++k) {
    const Mat S_inv = InverseSpd(S);
    schur -= Y.transpose() * S_inv * Y;
    if (all) {
      D[k] = S_inv;
      C[k] = Y;
    }
    if (k + 1 >= n) {
      X_newest = S_inv * Y;
      break;
    }
    const Mat A = O[k].transpose() * S_inv;  // O_k^T S_k^-1
    S = D[k + 1] - A * O[k];
    Y = C[k + 1] - A * Y;
  }
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(0.5 * (schur + schur.transpose()));
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return false;
  const Eigen::MatrixXd scaled_cov =
      ldlt.solve(Eigen::MatrixXd::Identity(schur.rows(), schur.cols()));
  *covariance = e_inv.asDiagonal() * scaled_cov * e_inv.asDiagonal();
  if (!covariance->allFinite() || !(covariance->diagonal().array() > 0.0).all()) return false;
  if (U == nullptr) return true;
  // In the original units H_cc^-1 H_ce = d^-1 X e (X of the scaled problem); with Sigma_e =
  // e^-1 Sigma_s e^-1 the correction U Sigma_e U^T is d^-1 X Sigma_s X^T d^-1: U is returned as
  // d^-1 X against the scaled covariance's square root, so that a caller adds U_k U_k^T.
  const Eigen::LLT<Eigen::MatrixXd> sqrt_cov(scaled_cov);
  if (sqrt_cov.info() != Eigen::Success) return false;
  const Eigen::MatrixXd L = sqrt_cov.matrixL();
  if (!all) {
    U->assign(1, d_inv[n - 1].asDiagonal() * X_newest * L);
    return true;
  }
  U->assign(n, MatC());
  MatC X = X_newest;
  (*U)[n - 1] = d_inv[n - 1].asDiagonal() * X * L;
  for (size_t k = n - 1; k-- > 0;) {
    X = D[k] * (C[k] - O[k] * X);
    (*U)[k] = d_inv[k].asDiagonal() * X * L;
  }
  return true;
}

}  // namespace skerry
