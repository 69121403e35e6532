#include "skerry/solvers/nav_graph.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <stdexcept>

#include "skerry/core/so3.h"
#include "skerry/factors/factor_linearization.h"
#include "skerry/factors/linear_prior_factor.h"

namespace skerry {

namespace {
constexpr int kSlotSize[5] = {4, 3, 3, 3, 3};
constexpr int kSlotOffset[5] = {0, 4, 7, 10, 13};  // in Keyframe::fe
constexpr int kSlotTangent[5] = {0, 3, 6, 9, 12};  // in the 15-D tangent
using Mat15 = Eigen::Matrix<double, 15, 15>;

// x (-) x0 for one slot in skerry's tangent convention.
Eigen::VectorXd SlotMinus(Slot slot, const double* x, const double* x0) {
  if (slot == Slot::kQ) {
    const Eigen::Map<const Eigen::Quaterniond> q(x), q0(x0);
    return LogQ<double>(q * q0.conjugate());
  }
  return Eigen::Map<const Eigen::Vector3d>(x) - Eigen::Map<const Eigen::Vector3d>(x0);
}

// Regularised inverse of a symmetric positive (semi-)definite block.
Mat15 InverseSpd(const Mat15& A) {
  Mat15 S = 0.5 * (A + A.transpose());
  Eigen::LDLT<Mat15> ldlt(S);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) {
    S.diagonal().array() += 1e-12 * std::max(1.0, S.diagonal().maxCoeff());
    ldlt.compute(S);
  }
  return ldlt.solve(Mat15::Identity());
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
  std::unique_ptr<ceres::CostFunction> cost;
  std::unique_ptr<ceres::LossFunction> loss;
  std::vector<BlockRef> blocks;
  ceres::ResidualBlockId residual_id = nullptr;
};

struct NavGraph::Linearized {
  LinearizedResidual lin;
};

NavGraph::NavGraph() : quaternion_manifold_(std::make_unique<ceres::EigenQuaternionManifold>()) {
  ceres::Problem::Options options;
  options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  options.enable_fast_removal = true;
  problem_ = std::make_unique<ceres::Problem>(options);
}

NavGraph::~NavGraph() = default;

Keyframe& NavGraph::AddKeyframe(const NavState& initial, const Eigen::Vector3d& gyro_rad_s) {
  if (!keyframes_.empty() && initial.t_ns <= newest().t_ns) {
    throw std::logic_error("NavGraph::AddKeyframe: time must increase");
  }
  auto kf = std::make_unique<Keyframe>();
  kf->id = next_keyframe_id_++;
  kf->set_state(initial);
  kf->gyro_rad_s = gyro_rad_s;
  problem_->AddParameterBlock(kf->q, 4, quaternion_manifold_.get());
  problem_->AddParameterBlock(kf->p, 3);
  problem_->AddParameterBlock(kf->v, 3);
  problem_->AddParameterBlock(kf->bg, 3);
  problem_->AddParameterBlock(kf->ba, 3);
  Keyframe& ref = *kf;
  keyframes_.emplace(kf->id, std::move(kf));
  return ref;
}

double* NavGraph::BlockPtr(const BlockRef& ref) { return keyframes_.at(ref.keyframe)->block(ref.slot); }

FactorId NavGraph::AddFactor(FactorKind kind,
                             std::unique_ptr<ceres::CostFunction> cost,
                             std::unique_ptr<ceres::LossFunction> loss,
                             const std::vector<BlockRef>& blocks) {
  auto f = std::make_unique<Factor>();
  f->kind = kind;
  f->cost = std::move(cost);
  f->loss = std::move(loss);
  f->blocks = blocks;
  std::vector<double*> ptrs;
  for (const BlockRef& b : blocks) ptrs.push_back(BlockPtr(b));
  f->residual_id = problem_->AddResidualBlock(f->cost.get(), f->loss.get(), ptrs);
  const FactorId id = next_factor_id_++;
  factors_.emplace(id, std::move(f));
  return id;
}

void NavGraph::RemoveFactor(FactorId id) {
  auto it = factors_.find(id);
  if (it == factors_.end()) return;
  problem_->RemoveResidualBlock(it->second->residual_id);
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
  if (!ceres::StringToLinearSolverType(
          [&] {
            std::string s = c.linear_solver;
            std::transform(s.begin(), s.end(), s.begin(), ::toupper);
            return s;
          }(),
          &o.linear_solver_type)) {
    throw std::invalid_argument("unknown linear_solver '" + c.linear_solver + "'");
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

ceres::Solver::Summary NavGraph::Solve(const CeresConfig& config) {
  ceres::Solver::Options options = MakeSolverOptions(config);
  ceres::Solver::Summary summary;
  ceres::Solve(options, problem_.get(), &summary);
  return summary;
}

bool NavGraph::LinearizeFactor(const Factor& f, bool fej, Linearized* out) const {
  std::vector<const double*> current, at_jacobian;
  for (const BlockRef& b : f.blocks) {
    const Keyframe& kf = *keyframes_.at(b.keyframe);
    current.push_back(kf.block(b.slot));
    if (fej && kf.has_first_estimate) {
      at_jacobian.push_back(kf.fe + kSlotOffset[static_cast<int>(b.slot)]);
    } else {
      at_jacobian.push_back(kf.block(b.slot));
    }
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

void NavGraph::MarginalizeOldest(bool first_estimate_jacobians) {
  if (keyframes_.size() < 2) throw std::logic_error("MarginalizeOldest needs two keyframes");
  const KeyframeId id0 = keyframes_.begin()->first;
  const KeyframeId id1 = std::next(keyframes_.begin())->first;
  Keyframe& kf1 = *keyframes_.at(id1);
  // Linearisation point of the kept keyframe: with FEJ its first estimate (fixed from now on).
  if (!kf1.has_first_estimate) {
    for (int s = 0; s < 5; ++s) {
      std::copy_n(kf1.block(static_cast<Slot>(s)), kSlotSize[s], kf1.fe + kSlotOffset[s]);
    }
    kf1.has_first_estimate = true;
  }

  Eigen::Matrix<double, 30, 30> H = Eigen::Matrix<double, 30, 30>::Zero();
  Eigen::Matrix<double, 30, 1> g = Eigen::Matrix<double, 30, 1>::Zero();
  std::vector<FactorId> to_remove;
  for (const auto& [fid, f] : factors_) {
    const bool touches0 = std::any_of(f->blocks.begin(), f->blocks.end(),
                                      [&](const BlockRef& b) { return b.keyframe == id0; });
    if (!touches0) continue;
    Linearized L;
    if (!LinearizeFactor(*f, first_estimate_jacobians, &L)) {
      throw std::runtime_error("marginalisation: a factor failed to evaluate");
    }
    const int m = static_cast<int>(L.lin.residual.size());
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(m, 30);
    for (size_t k = 0; k < f->blocks.size(); ++k) {
      const BlockRef& b = f->blocks[k];
      int col = kSlotTangent[static_cast<int>(b.slot)];
      if (b.keyframe == id1) {
        col += 15;
      } else if (b.keyframe != id0) {
        throw std::logic_error("marginalisation: factor spans non-consecutive keyframes");
      }
      J.middleCols(col, TangentSize(kSlotSize[static_cast<int>(b.slot)])) += L.lin.jacobians[k];
    }
    H.noalias() += J.transpose() * J;
    g.noalias() += J.transpose() * L.lin.residual;
    to_remove.push_back(fid);
  }
  // Schur complement onto keyframe 1 (Sibley et al. 2010, eq. 9).
  const Mat15 H00_inv = InverseSpd(H.topLeftCorner<15, 15>());
  const Mat15 H10 = H.bottomLeftCorner<15, 15>();
  Mat15 H_star = H.bottomRightCorner<15, 15>() - H10 * H00_inv * H10.transpose();
  const Eigen::Matrix<double, 15, 1> g_star = g.tail<15>() - H10 * H00_inv * g.head<15>();

  for (FactorId fid : to_remove) RemoveFactor(fid);
  const Keyframe& kf0 = *keyframes_.at(id0);
  problem_->RemoveParameterBlock(const_cast<double*>(kf0.q));
  problem_->RemoveParameterBlock(const_cast<double*>(kf0.p));
  problem_->RemoveParameterBlock(const_cast<double*>(kf0.v));
  problem_->RemoveParameterBlock(const_cast<double*>(kf0.bg));
  problem_->RemoveParameterBlock(const_cast<double*>(kf0.ba));
  keyframes_.erase(id0);

  // The prior's linearisation point: the first estimate of keyframe 1 (with FEJ), else now.
  std::vector<Eigen::VectorXd> x0(5);
  std::vector<int> sizes(5);
  for (int s = 0; s < 5; ++s) {
    sizes[s] = kSlotSize[s];
    const double* src = first_estimate_jacobians ? kf1.fe + kSlotOffset[s]
                                                 : kf1.block(static_cast<Slot>(s));
    x0[s] = Eigen::Map<const Eigen::VectorXd>(src, kSlotSize[s]);
  }
  const Eigen::VectorXd g_lin = g_star;
  auto prior = LinearPriorFactor::FromInformation(sizes, x0, H_star, g_lin);
  if (prior) {
    std::vector<BlockRef> blocks;
    for (int s = 0; s < 5; ++s) blocks.push_back({id1, static_cast<Slot>(s)});
    AddFactor(FactorKind::kMarginalPrior, std::move(prior), nullptr, blocks);
  }
}

bool NavGraph::BuildChain(std::vector<Mat15>* D, std::vector<Mat15>* O) const {
  const size_t n = keyframes_.size();
  std::map<KeyframeId, size_t> index;
  for (const auto& [id, kf] : keyframes_) index.emplace(id, index.size());
  D->assign(n, Mat15::Zero());
  O->assign(n > 0 ? n - 1 : 0, Mat15::Zero());
  for (const auto& [fid, f] : factors_) {
    Linearized L;
    if (!LinearizeFactor(*f, false, &L)) return false;
    // Columns: at most two consecutive keyframes.
    size_t lo = SIZE_MAX, hi = 0;
    for (const BlockRef& b : f->blocks) {
      lo = std::min(lo, index.at(b.keyframe));
      hi = std::max(hi, index.at(b.keyframe));
    }
    if (hi > lo + 1) throw std::logic_error("NavGraph: factor spans non-consecutive keyframes");
    const int m = static_cast<int>(L.lin.residual.size());
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(m, 30);
    for (size_t k = 0; k < f->blocks.size(); ++k) {
      const BlockRef& b = f->blocks[k];
      const int col = kSlotTangent[static_cast<int>(b.slot)] + (index.at(b.keyframe) == lo ? 0 : 15);
      J.middleCols(col, TangentSize(kSlotSize[static_cast<int>(b.slot)])) += L.lin.jacobians[k];
    }
    const Eigen::MatrixXd H = J.transpose() * J;
    (*D)[lo] += H.topLeftCorner(15, 15);
    if (hi > lo) {
      (*D)[hi] += H.bottomRightCorner(15, 15);
      (*O)[lo] += H.topRightCorner(15, 15);
    }
  }
  return true;
}

bool NavGraph::NewestCovariance(StateCovariance* covariance) const {
  std::vector<Mat15> D, O;
  if (keyframes_.empty() || !BuildChain(&D, &O)) return false;
  // Forward elimination: S_{k+1} = D_{k+1} - O_k^T S_k^-1 O_k; Cov(newest) = S_n^-1.
  Mat15 S = D[0];
  for (size_t k = 0; k + 1 < D.size(); ++k) {
    S = D[k + 1] - O[k].transpose() * InverseSpd(S) * O[k];
  }
  *covariance = InverseSpd(S);
  return covariance->allFinite();
}

bool NavGraph::AllCovariances(std::vector<StateCovariance>* covariances) const {
  std::vector<Mat15> D, O;
  if (keyframes_.empty() || !BuildChain(&D, &O)) return false;
  const size_t n = D.size();
  std::vector<Mat15> S_inv(n);
  Mat15 S = D[0];
  for (size_t k = 0; k < n; ++k) {
    S_inv[k] = InverseSpd(S);
    if (k + 1 < n) S = D[k + 1] - O[k].transpose() * S_inv[k] * O[k];
  }
  // Backward pass: Sigma_k = S_k^-1 + S_k^-1 O_k Sigma_{k+1} O_k^T S_k^-1 (the RTS smoother in
  // information form for a block-tridiagonal H).
  covariances->assign(n, Mat15::Zero());
  (*covariances)[n - 1] = S_inv[n - 1];
  for (size_t k = n - 1; k-- > 0;) {
    const Mat15 A = S_inv[k] * O[k];
    (*covariances)[k] = S_inv[k] + A * (*covariances)[k + 1] * A.transpose();
  }
  return true;
}

bool NavGraph::PropagateCovariance(KeyframeId prev,
                                   KeyframeId next,
                                   const StateCovariance& prev_covariance,
                                   StateCovariance* next_covariance) const {
  Eigen::Matrix<double, 30, 30> H = Eigen::Matrix<double, 30, 30>::Zero();
  H.topLeftCorner<15, 15>() = InverseSpd(prev_covariance);
  for (const auto& [fid, f] : factors_) {
    bool touches_next = false, only_pair = true;
    for (const BlockRef& b : f->blocks) {
      if (b.keyframe == next) touches_next = true;
      if (b.keyframe != next && b.keyframe != prev) only_pair = false;
    }
    if (!touches_next || !only_pair) continue;
    Linearized L;
    if (!LinearizeFactor(*f, false, &L)) return false;
    const int m = static_cast<int>(L.lin.residual.size());
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(m, 30);
    for (size_t k = 0; k < f->blocks.size(); ++k) {
      const BlockRef& b = f->blocks[k];
      const int col = kSlotTangent[static_cast<int>(b.slot)] + (b.keyframe == next ? 15 : 0);
      J.middleCols(col, TangentSize(kSlotSize[static_cast<int>(b.slot)])) += L.lin.jacobians[k];
    }
    H.noalias() += J.transpose() * J;
  }
  const Mat15 S = H.bottomRightCorner<15, 15>() - H.bottomLeftCorner<15, 15>() *
                                                      InverseSpd(H.topLeftCorner<15, 15>()) *
                                                      H.topRightCorner<15, 15>();
  *next_covariance = InverseSpd(S);
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
  for (const BlockRef& b : f.blocks) ptrs.push_back(keyframes_.at(b.keyframe)->block(b.slot));
  Eigen::VectorXd r(f.cost->num_residuals());
  f.cost->Evaluate(ptrs.data(), r.data(), nullptr);
  return r;
}

FactorKind NavGraph::factor_kind(FactorId id) const { return factors_.at(id)->kind; }

std::vector<FactorId> NavGraph::factor_ids(FactorKind kind) const {
  std::vector<FactorId> ids;
  for (const auto& [id, f] : factors_) {
    if (f->kind == kind) ids.push_back(id);
  }
  return ids;
}

}  // namespace skerry
