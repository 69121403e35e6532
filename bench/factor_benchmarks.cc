/// \file
/// Micro-benchmarks of the factors: Evaluate() with Jacobians of every factor, the
/// preintegration step, and LinearizeResidual. Where a peer exists it runs in the same process
/// and the ratio of medians is printed in a table after the Google Benchmark output:
///   - ImuFactor's analytic Jacobians (ImuFactor::Create) vs its autodiff reference
///     (ImuFactor::CreateAutoDiff) and vs numeric differences of the same functor;
///   - each autodiff factor vs ceres::NumericDiffCostFunction (central) of the same functor;
///   - BiasRandomWalkFactor (analytic) vs an autodiff functor of the same model;
///   - ImuPreintegration::Integrate (deltas + covariance + bias Jacobians) vs a naive
///     deltas-only integration of the same samples;
///   - a bias update by first-order correction (ImuDeltas::Corrected) vs re-integrating the raw
///     samples with the new bias (what preintegration saves);
///   - LinearizeResidual vs the plain Evaluate it wraps.
///
/// Defaults to 5 repetitions with aggregates only, so every figure is a median over runs;
/// any --benchmark_* flag given on the command line wins.

#include <benchmark/benchmark.h>
#include <ceres/autodiff_cost_function.h>
#include <ceres/dynamic_numeric_diff_cost_function.h>
#include <ceres/numeric_diff_cost_function.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "skerry/core/nav_state.h"
#include "skerry/core/sensor_config.h"
#include "skerry/core/so3.h"
#include "skerry/factors/bias_random_walk_factor.h"
#include "skerry/factors/factor_linearization.h"
#include "skerry/factors/gnss_heading_factor.h"
#include "skerry/factors/gnss_position_factor.h"
#include "skerry/factors/imu_factor.h"
#include "skerry/factors/imu_preintegration.h"
#include "skerry/factors/linear_prior_factor.h"
#include "skerry/factors/robust_loss.h"
#include "skerry/factors/state_prior_factor.h"

namespace skerry {
namespace {

constexpr double kImuRateHz = 200.0;
constexpr double kKeyframePeriodS = 0.1;  // the default preset's 10 Hz keyframes
constexpr int kSamplesPerInterval = 20;   // 0.1 s at 200 Hz

// ------------------------------------------------------------------------------------------
// Fixtures: a realistic operating point (the harbour scenario's extrinsics, a rolling,
// turning hull), built once.

ImuConfig HarbourImu() {
  ImuConfig imu;
  imu.rate_hz = kImuRateHz;
  imu.q_b_i = Eigen::Quaterniond(0.70710678118654752, 0.0, 0.0, 0.70710678118654752);
  imu.p_b_i = Eigen::Vector3d(1.2, -0.3, 0.5);
  return imu;
}

/// kSamplesPerInterval + 1 samples (both ends of the interval) of a hull turning at 3 deg/s
/// and rolling, with gravity in the specific force.
std::vector<ImuSample> IntervalSamples() {
  std::vector<ImuSample> samples;
  const TimeNs dt_ns = SecondsToNs(1.0 / kImuRateHz);
  for (int k = 0; k <= kSamplesPerInterval; ++k) {
    const double t = k / kImuRateHz;
    ImuSample s;
    s.t_ns = k * dt_ns;
    s.gyro_rad_s = Eigen::Vector3d(0.08 * std::sin(1.3 * t), 0.03 * std::cos(0.9 * t), 0.052);
    s.accel_m_s2 = Eigen::Vector3d(0.4 * std::sin(0.7 * t), 0.2, 9.80665 + 0.3 * std::cos(t));
    samples.push_back(s);
  }
  return samples;
}

struct ImuFixture {
  ImuConfig imu = HarbourImu();
  std::vector<ImuSample> samples = IntervalSamples();
  std::shared_ptr<ImuPreintegration> pim;
  NavState xi, xj;
  ImuEarthTerms earth;  ///< the harbour's WGS84 Earth at xi

  ImuFixture() {
    xi.q_w_b = Eigen::Quaterniond(Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) *
                                  Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitX()));
    xi.p_w_b = Eigen::Vector3d(120.0, -45.0, 0.3);
    xi.v_w = Eigen::Vector3d(3.1, 2.4, 0.05);
    xi.bg = Eigen::Vector3d(2e-4, -1e-4, 3e-4);
    xi.ba = Eigen::Vector3d(0.01, -0.02, 0.015);
    earth = EarthTermsNear(EarthModel(GeoOrigin{47.60, 9.45, 440.0}), xi.p_w_b);
    pim = std::make_shared<ImuPreintegration>(imu.noise, xi.bg, xi.ba);
    for (size_t k = 1; k < samples.size(); ++k)
      IntegrateBetween(samples[k - 1], samples[k], pim.get());
    xj = xi;
    PredictBodyState(*pim, imu, earth, samples.front().gyro_rad_s, samples.back().gyro_rad_s,
                     xi.q_w_b, xi.p_w_b, xi.v_w, xi.bg, xi.ba, &xj.q_w_b, &xj.p_w_b, &xj.v_w);
    // Off the prediction, so the residual and the robust losses are not at a special point.
    xj.p_w_b += Eigen::Vector3d(0.02, -0.01, 0.005);
    xj.q_w_b = (xj.q_w_b * ExpQ(Eigen::Vector3d(1e-3, -2e-3, 5e-4))).normalized();
  }

  ImuFactor MakeFunctor() const {
    return ImuFactor(*pim, imu, samples.front().gyro_rad_s, samples.back().gyro_rad_s, earth);
  }
};

const ImuFixture& Imu() {
  static const ImuFixture fixture;
  return fixture;
}

/// Parameter blocks of one state, ambient, in the order q, p, v, bg, ba.
struct StateBlocks {
  double q[4], p[3], v[3], bg[3], ba[3];
  explicit StateBlocks(const NavState& s) {
    Eigen::Map<Eigen::Vector4d>{q} = s.q_w_b.coeffs();  // [x,y,z,w]
    Eigen::Map<Eigen::Vector3d>{p} = s.p_w_b;
    Eigen::Map<Eigen::Vector3d>{v} = s.v_w;
    Eigen::Map<Eigen::Vector3d>{bg} = s.bg;
    Eigen::Map<Eigen::Vector3d>{ba} = s.ba;
  }
};

const StateBlocks& BlocksI() {
  static const StateBlocks blocks(Imu().xi);
  return blocks;
}
const StateBlocks& BlocksJ() {
  static const StateBlocks blocks(Imu().xj);
  return blocks;
}

std::vector<const double*> ImuFactorParams() {
  const StateBlocks& i = BlocksI();
  const StateBlocks& j = BlocksJ();
  return {i.q, i.p, i.v, i.bg, i.ba, j.q, j.p, j.v};
}
std::vector<const double*> StateParams() {
  const StateBlocks& i = BlocksI();
  return {i.q, i.p, i.v, i.bg, i.ba};
}
std::vector<const double*> GnssParams() {
  const StateBlocks& i = BlocksI();
  return {i.q, i.p, i.v};
}
std::vector<const double*> BiasParams() {
  const StateBlocks& i = BlocksI();
  const StateBlocks& j = BlocksJ();
  return {i.bg, i.ba, j.bg, j.ba};
}

StateCovariance PriorCovariance() {
  Eigen::Matrix<double, 15, 1> sigma;
  sigma << 0.05, 0.05, 0.09, 0.7, 0.7, 1.2, 1.0, 1.0, 1.0, 1e-3, 1e-3, 1e-3, 0.05, 0.05, 0.05;
  return sigma.array().square().matrix().asDiagonal();
}

/// A marginalisation prior as NavGraph leaves it: 15 tangent columns over the next keyframe's
/// five blocks, from a dense SPD information matrix.
std::unique_ptr<LinearPriorFactor> MakeLinearPrior() {
  const Eigen::Matrix<double, 15, 15> A = Eigen::Matrix<double, 15, 15>::Random();
  const Eigen::MatrixXd H = A * A.transpose() + 15.0 * Eigen::MatrixXd::Identity(15, 15);
  const Eigen::VectorXd g = Eigen::VectorXd::Random(15);
  const NavState& x0 = Imu().xi;
  std::vector<Eigen::VectorXd> x0_blocks = {Eigen::Vector4d(x0.q_w_b.coeffs()), x0.p_w_b, x0.v_w,
                                            x0.bg, x0.ba};
  return LinearPriorFactor::FromInformation({4, 3, 3, 3, 3}, std::move(x0_blocks), H, g);
}

/// The documented model of BiasRandomWalkFactor as an autodiff functor (peer of the analytic
/// Jacobians).
struct BiasRandomWalkModel {
  double sqrt_info_g, sqrt_info_a;
  template <typename T>
  bool operator()(const T* bg_i, const T* ba_i, const T* bg_j, const T* ba_j, T* r) const {
    for (int k = 0; k < 3; ++k) {
      r[k] = T(sqrt_info_g) * (bg_j[k] - bg_i[k]);
      r[3 + k] = T(sqrt_info_a) * (ba_j[k] - ba_i[k]);
    }
    return true;
  }
};

BiasRandomWalkModel MakeBiasModel() {
  const ImuNoise noise;
  return {1.0 / (noise.gyro_bias_random_walk_rad_s2_sqrt_hz * std::sqrt(kKeyframePeriodS)),
          1.0 / (noise.accel_bias_random_walk_m_s3_sqrt_hz * std::sqrt(kKeyframePeriodS))};
}

// ------------------------------------------------------------------------------------------
// The measured loop.

/// Evaluate() with residuals and every Jacobian, as the Ceres evaluator calls it.
void EvaluateLoop(benchmark::State& state,
                  const ceres::CostFunction& cost,
                  const std::vector<const double*>& params) {
  const std::vector<int32_t>& sizes = cost.parameter_block_sizes();
  if (sizes.size() != params.size()) {
    state.SkipWithError("parameter block count mismatch");
    return;
  }
  std::vector<double> residuals(cost.num_residuals());
  std::vector<std::vector<double>> jacobians(sizes.size());
  std::vector<double*> jacobian_ptrs(sizes.size());
  for (size_t k = 0; k < sizes.size(); ++k) {
    jacobians[k].resize(static_cast<size_t>(cost.num_residuals()) * sizes[k]);
    jacobian_ptrs[k] = jacobians[k].data();
  }
  bool ok = true;
  for (auto _ : state) {
    ok &= cost.Evaluate(params.data(), residuals.data(), jacobian_ptrs.data());
    benchmark::DoNotOptimize(residuals.data());
    benchmark::DoNotOptimize(jacobian_ptrs.data());
    benchmark::ClobberMemory();
  }
  if (!ok) state.SkipWithError("Evaluate returned false");
}

// ------------------------------------------------------------------------------------------
// Factors: autodiff as skerry builds them (each factor's Create), and numeric-diff peers.
//
// The numeric peer of every factor is generic: ceres::DynamicNumericDiffCostFunction (central)
// over the factor's own residual-only Evaluate (for an AutoDiffCostFunction that is the functor
// on doubles), so it follows the factor's parameter blocks when they change. Its dynamic
// bookkeeping makes it a little slower than a static NumericDiffCostFunction; the ImuFactor
// has both so that the difference is measured, not guessed.

/// Residual-only evaluation of a cost function, as a DynamicNumericDiffCostFunction functor.
class ResidualOnly {
 public:
  explicit ResidualOnly(const ceres::CostFunction* cost) : cost_(cost) {}
  bool operator()(double const* const* parameters, double* residuals) const {
    return cost_->Evaluate(parameters, residuals, nullptr);
  }

 private:
  const ceres::CostFunction* cost_;
};

std::unique_ptr<ceres::CostFunction> NumericPeer(const ceres::CostFunction* cost) {
  auto peer = std::make_unique<ceres::DynamicNumericDiffCostFunction<ResidualOnly, ceres::CENTRAL>>(
      new ResidualOnly(cost));
  for (const int32_t size : cost->parameter_block_sizes()) peer->AddParameterBlock(size);
  peer->SetNumResiduals(cost->num_residuals());
  return peer;
}

/// `known` for the leading blocks; any further block the factor declares (e.g. a bias block
/// added later) gets zeros. Empty if the factor has fewer blocks than `known`.
std::vector<const double*> Params(const ceres::CostFunction& cost,
                                  std::vector<const double*> known) {
  static const double kZeros[64] = {};
  const std::vector<int32_t>& sizes = cost.parameter_block_sizes();
  if (sizes.size() < known.size()) return {};
  for (size_t k = known.size(); k < sizes.size(); ++k) {
    if (sizes[k] > 64) return {};
    known.push_back(kZeros);
  }
  return known;
}

std::unique_ptr<ceres::CostFunction> ImuCost() {
  return ImuFactor::Create(*Imu().pim, Imu().imu, Imu().samples.front().gyro_rad_s,
                           Imu().samples.back().gyro_rad_s, Imu().earth);
}
std::unique_ptr<ceres::CostFunction> ImuCostAutoDiff() {
  return ImuFactor::CreateAutoDiff(*Imu().pim, Imu().imu, Imu().samples.front().gyro_rad_s,
                                   Imu().samples.back().gyro_rad_s, Imu().earth);
}
std::unique_ptr<ceres::CostFunction> GnssPositionCost() {
  const Eigen::Vector3d lever_arm_b(-1.5, 0.0, 2.8);
  const Eigen::Vector3d z_w =
      Imu().xi.p_w_b + Imu().xi.q_w_b * lever_arm_b + Eigen::Vector3d(0.4, -0.3, 0.2);
  return GnssPositionFactor::Create(z_w, Eigen::Vector3d(0.35, 0.35, 0.6), lever_arm_b, 0.03);
}
std::unique_ptr<ceres::CostFunction> GnssHeadingCost() {
  return GnssHeadingFactor::Create(0.87, 0.2 * EIGEN_PI / 180.0, Eigen::Vector3d::UnitX(),
                                   Eigen::Matrix3d::Identity());
}
std::unique_ptr<ceres::CostFunction> StatePriorCost() {
  return StatePriorFactor::Create(Imu().xj, PriorCovariance());
}

void FactorAutoDiff(benchmark::State& state,
                    std::unique_ptr<ceres::CostFunction> (*make)(),
                    std::vector<const double*> (*params)()) {
  const auto cost = make();
  EvaluateLoop(state, *cost, Params(*cost, params()));
}

/// A factor whose Create gives Jacobians written by hand.
void FactorAnalytic(benchmark::State& state,
                    std::unique_ptr<ceres::CostFunction> (*make)(),
                    std::vector<const double*> (*params)()) {
  FactorAutoDiff(state, make, params);
}

void FactorNumericDynamic(benchmark::State& state,
                          std::unique_ptr<ceres::CostFunction> (*make)(),
                          std::vector<const double*> (*params)()) {
  const auto cost = make();
  const auto peer = NumericPeer(cost.get());
  EvaluateLoop(state, *peer, Params(*peer, params()));
}

std::vector<const double*> HeadingParams() { return {BlocksI().q}; }

BENCHMARK_CAPTURE(FactorAnalytic, ImuFactor, ImuCost, ImuFactorParams);
BENCHMARK_CAPTURE(FactorAutoDiff, ImuFactor, ImuCostAutoDiff, ImuFactorParams);
BENCHMARK_CAPTURE(FactorNumericDynamic, ImuFactor, ImuCost, ImuFactorParams);

/// The static peer named in ceres' docs: NumericDiffCostFunction of the same functor.
void BM_ImuFactor_NumericDiffStatic(benchmark::State& state) {
  const ceres::NumericDiffCostFunction<ImuFactor, ceres::CENTRAL, 9, 4, 3, 3, 3, 3, 4, 3, 3> cost(
      new ImuFactor(Imu().MakeFunctor()));
  EvaluateLoop(state, cost, ImuFactorParams());
}
BENCHMARK(BM_ImuFactor_NumericDiffStatic);

BENCHMARK_CAPTURE(FactorAutoDiff, GnssPosition, GnssPositionCost, GnssParams);
BENCHMARK_CAPTURE(FactorNumericDynamic, GnssPosition, GnssPositionCost, GnssParams);
BENCHMARK_CAPTURE(FactorAutoDiff, GnssHeading, GnssHeadingCost, HeadingParams);
BENCHMARK_CAPTURE(FactorNumericDynamic, GnssHeading, GnssHeadingCost, HeadingParams);
BENCHMARK_CAPTURE(FactorAutoDiff, StatePrior, StatePriorCost, StateParams);
BENCHMARK_CAPTURE(FactorNumericDynamic, StatePrior, StatePriorCost, StateParams);

void BM_BiasRandomWalk_Analytic(benchmark::State& state) {
  const BiasRandomWalkFactor cost(ImuNoise{}, kKeyframePeriodS);
  EvaluateLoop(state, cost, BiasParams());
}
BENCHMARK(BM_BiasRandomWalk_Analytic);

/// Peer: the documented model as an autodiff functor.
void BM_BiasRandomWalk_AutoDiff(benchmark::State& state) {
  const ceres::AutoDiffCostFunction<BiasRandomWalkModel, 6, 3, 3, 3, 3> cost(
      new BiasRandomWalkModel(MakeBiasModel()));
  EvaluateLoop(state, cost, BiasParams());
}
BENCHMARK(BM_BiasRandomWalk_AutoDiff);

void BM_LinearPrior_15(benchmark::State& state) {
  const std::unique_ptr<LinearPriorFactor> cost = MakeLinearPrior();
  if (cost == nullptr) {
    state.SkipWithError("FromInformation returned nullptr");
    return;
  }
  state.counters["rows"] = static_cast<double>(cost->num_residuals());
  EvaluateLoop(state, *cost, StateParams());
}
BENCHMARK(BM_LinearPrior_15);

// ------------------------------------------------------------------------------------------
// Preintegration. One iteration = one 0.1 s keyframe interval (20 steps at 200 Hz); the
// "per_step" counter is the time of one step.

benchmark::Counter PerStep() {
  return benchmark::Counter(kSamplesPerInterval, benchmark::Counter::kIsIterationInvariantRate |
                                                     benchmark::Counter::kInvert);
}

void BM_Preintegrate_Interval(benchmark::State& state) {
  const ImuFixture& f = Imu();
  for (auto _ : state) {
    ImuPreintegration pim(f.imu.noise, f.xi.bg, f.xi.ba);
    for (size_t k = 1; k < f.samples.size(); ++k)
      IntegrateBetween(f.samples[k - 1], f.samples[k], &pim);
    benchmark::DoNotOptimize(pim);
  }
  state.counters["per_step"] = PerStep();
}
BENCHMARK(BM_Preintegrate_Interval);

// The same with the gyro calibration Jacobians (estimate_gyro_calibration).
void BM_Preintegrate_Interval_GyroCalibration(benchmark::State& state) {
  const ImuFixture& f = Imu();
  for (auto _ : state) {
    ImuPreintegration pim(f.imu.noise, f.xi.bg, f.xi.ba, /*gyro_calibration=*/true);
    for (size_t k = 1; k < f.samples.size(); ++k)
      IntegrateBetween(f.samples[k - 1], f.samples[k], &pim);
    benchmark::DoNotOptimize(pim);
  }
  state.counters["per_step"] = PerStep();
}
BENCHMARK(BM_Preintegrate_Interval_GyroCalibration);

/// Deltas only (no covariance, no bias Jacobians), same trapezoidal rule and update order as
/// ImuPreintegration::Integrate.
struct NaiveDeltas {
  Eigen::Quaterniond dq = Eigen::Quaterniond::Identity();
  Eigen::Vector3d dv = Eigen::Vector3d::Zero();
  Eigen::Vector3d dp = Eigen::Vector3d::Zero();
};

NaiveDeltas IntegrateNaive(const std::vector<ImuSample>& samples,
                           const Eigen::Vector3d& bg,
                           const Eigen::Vector3d& ba) {
  NaiveDeltas d;
  for (size_t k = 1; k < samples.size(); ++k) {
    const double dt = NsToSeconds(samples[k].t_ns - samples[k - 1].t_ns);
    const Eigen::Vector3d w = 0.5 * (samples[k - 1].gyro_rad_s + samples[k].gyro_rad_s) - bg;
    const Eigen::Vector3d a = 0.5 * (samples[k - 1].accel_m_s2 + samples[k].accel_m_s2) - ba;
    const Eigen::Vector3d dR_a = d.dq * a;
    d.dp += d.dv * dt + 0.5 * dR_a * dt * dt;
    d.dv += dR_a * dt;
    d.dq = (d.dq * ExpQ(Eigen::Vector3d(w * dt))).normalized();
  }
  return d;
}

void BM_NaiveIntegrate_Interval(benchmark::State& state) {
  const ImuFixture& f = Imu();
  for (auto _ : state) {
    NaiveDeltas d = IntegrateNaive(f.samples, f.xi.bg, f.xi.ba);
    benchmark::DoNotOptimize(d);
  }
  state.counters["per_step"] = PerStep();
}
BENCHMARK(BM_NaiveIntegrate_Interval);

/// The solver moved the bias: first-order correction of the stored deltas (Forster eq. 44).
void BM_BiasUpdate_FirstOrder(benchmark::State& state) {
  const ImuFixture& f = Imu();
  Eigen::Vector3d bg = f.xi.bg + Eigen::Vector3d(1e-4, -2e-4, 5e-5);
  const Eigen::Vector3d ba = f.xi.ba + Eigen::Vector3d(0.003, 0.001, -0.002);
  Eigen::Quaterniond dq;
  Eigen::Vector3d dv, dp;
  for (auto _ : state) {
    benchmark::DoNotOptimize(bg);
    f.pim->deltas().Corrected<double>(bg, ba, &dq, &dv, &dp);
    benchmark::DoNotOptimize(dq);
    benchmark::DoNotOptimize(dv);
    benchmark::DoNotOptimize(dp);
  }
}
BENCHMARK(BM_BiasUpdate_FirstOrder);

/// The same bias update by re-integrating the interval's raw samples (deltas only: the
/// cheapest re-integration there is).
void BM_BiasUpdate_Reintegrate(benchmark::State& state) {
  const ImuFixture& f = Imu();
  Eigen::Vector3d bg = f.xi.bg + Eigen::Vector3d(1e-4, -2e-4, 5e-5);
  const Eigen::Vector3d ba = f.xi.ba + Eigen::Vector3d(0.003, 0.001, -0.002);
  for (auto _ : state) {
    benchmark::DoNotOptimize(bg);
    NaiveDeltas d = IntegrateNaive(f.samples, bg, ba);
    benchmark::DoNotOptimize(d);
  }
}
BENCHMARK(BM_BiasUpdate_Reintegrate);

// ------------------------------------------------------------------------------------------
// LinearizeResidual (marginalisation and covariance path) vs the Evaluate it wraps.

void LinearizeLoop(benchmark::State& state,
                   const ceres::CostFunction& cost,
                   const ceres::LossFunction* loss,
                   const std::vector<const double*>& params) {
  LinearizedResidual out;
  bool ok = true;
  for (auto _ : state) {
    ok &= LinearizeResidual(cost, loss, params, params, &out);
    benchmark::DoNotOptimize(out.residual.data());
    benchmark::ClobberMemory();
  }
  if (!ok) state.SkipWithError("LinearizeResidual returned false");
}

void BM_LinearizeResidual_ImuFactor(benchmark::State& state) {
  const auto cost = ImuCost();
  LinearizeLoop(state, *cost, nullptr, Params(*cost, ImuFactorParams()));
}
BENCHMARK(BM_LinearizeResidual_ImuFactor);

void BM_LinearizeResidual_GnssPositionHuber(benchmark::State& state) {
  const auto cost = GnssPositionCost();
  const std::unique_ptr<ceres::LossFunction> loss = MakeLoss({LossType::kHuber, 3.0});
  LinearizeLoop(state, *cost, loss.get(), Params(*cost, GnssParams()));
}
BENCHMARK(BM_LinearizeResidual_GnssPositionHuber);

// ------------------------------------------------------------------------------------------
// Ratio table.

struct Pair {
  const char* subject;
  const char* peer;
  const char* meaning;
};

constexpr Pair kPairs[] = {
    {"FactorAnalytic/ImuFactor", "FactorAutoDiff/ImuFactor", "analytic / autodiff"},
    {"FactorAnalytic/ImuFactor", "BM_ImuFactor_NumericDiffStatic",
     "analytic / static numeric (central)"},
    {"FactorAutoDiff/ImuFactor", "BM_ImuFactor_NumericDiffStatic",
     "autodiff / static numeric (central)"},
    {"FactorAutoDiff/ImuFactor", "FactorNumericDynamic/ImuFactor",
     "autodiff / dynamic numeric (central)"},
    {"BM_ImuFactor_NumericDiffStatic", "FactorNumericDynamic/ImuFactor",
     "static / dynamic numeric: the generic peer's overhead"},
    {"FactorAutoDiff/GnssPosition", "FactorNumericDynamic/GnssPosition",
     "autodiff / dynamic numeric (central)"},
    {"FactorAutoDiff/GnssHeading", "FactorNumericDynamic/GnssHeading",
     "autodiff / dynamic numeric (central)"},
    {"FactorAutoDiff/StatePrior", "FactorNumericDynamic/StatePrior",
     "autodiff / dynamic numeric (central)"},
    {"BM_BiasRandomWalk_Analytic", "BM_BiasRandomWalk_AutoDiff", "analytic / autodiff"},
    {"BM_Preintegrate_Interval", "BM_NaiveIntegrate_Interval",
     "full Integrate / deltas-only (cost of covariance + bias Jacobians)"},
    {"BM_Preintegrate_Interval_GyroCalibration", "BM_Preintegrate_Interval",
     "with the gyro calibration Jacobians / without"},
    {"BM_BiasUpdate_FirstOrder", "BM_BiasUpdate_Reintegrate",
     "first-order bias correction / re-integration"},
    {"BM_LinearizeResidual_ImuFactor", "FactorAnalytic/ImuFactor",
     "LinearizeResidual / bare Evaluate"},
    {"BM_LinearizeResidual_GnssPositionHuber", "FactorAutoDiff/GnssPosition",
     "LinearizeResidual (+Huber) / bare Evaluate"},
};

double ToNs(double value, benchmark::TimeUnit unit) {
  switch (unit) {
    case benchmark::kNanosecond:
      return value;
    case benchmark::kMicrosecond:
      return value * 1e3;
    case benchmark::kMillisecond:
      return value * 1e6;
    case benchmark::kSecond:
      return value * 1e9;
  }
  return value;
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// The console output, plus the time of every run kept for the ratio table: the "median"
/// aggregate when repetitions > 1, else the median of the single runs. Ratios use CPU time:
/// every benchmark here is single-threaded, and on a shared machine CPU time is the figure that
/// does not move with the neighbours' load (real time is in the console output above).
class RatioReporter : public benchmark::ConsoleReporter {
 public:
  RatioReporter() : benchmark::ConsoleReporter(OO_Tabular) {}

  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& run : runs) {
      if (run.error_occurred) continue;
      const std::string name = run.run_name.str();
      const double ns = ToNs(run.GetAdjustedCPUTime(), run.time_unit);
      if (run.run_type == Run::RT_Aggregate) {
        if (run.aggregate_name == "median") median_ns_[name] = ns;
      } else {
        single_ns_[name].push_back(ns);
      }
    }
    benchmark::ConsoleReporter::ReportRuns(runs);
  }

  void PrintRatios() const {
    std::printf("\nRatios of median CPU times, measured in this run (< 1: subject faster)\n");
    std::printf("%-40s %-32s %10s %10s %8s  %s\n", "subject", "peer", "subj_ns", "peer_ns", "ratio",
                "meaning");
    for (const Pair& pair : kPairs) {
      const double s = Lookup(pair.subject), p = Lookup(pair.peer);
      if (!(s > 0.0) || !(p > 0.0)) continue;  // filtered out or failed
      std::printf("%-40s %-32s %10.1f %10.1f %8.3f  %s\n", pair.subject, pair.peer, s, p, s / p,
                  pair.meaning);
    }
  }

 private:
  double Lookup(const std::string& name) const {
    const auto m = median_ns_.find(name);
    if (m != median_ns_.end()) return m->second;
    const auto s = single_ns_.find(name);
    if (s != single_ns_.end() && !s->second.empty()) return Median(s->second);
    return -1.0;
  }

  std::map<std::string, double> median_ns_;
  std::map<std::string, std::vector<double>> single_ns_;
};

bool HasFlag(int argc, char** argv, const std::string& prefix) {
  for (int k = 1; k < argc; ++k) {
    if (std::string(argv[k]).rfind(prefix, 0) == 0) return true;
  }
  return false;
}

}  // namespace
}  // namespace skerry

int main(int argc, char** argv) {
  // Medians over runs by default; the user's flags come later and win.
  std::vector<std::string> storage(argv, argv + argc);
  if (!skerry::HasFlag(argc, argv, "--benchmark_repetitions")) {
    storage.insert(storage.begin() + 1, "--benchmark_repetitions=5");
  }
  if (!skerry::HasFlag(argc, argv, "--benchmark_report_aggregates_only") &&
      !skerry::HasFlag(argc, argv, "--benchmark_display_aggregates_only")) {
    storage.insert(storage.begin() + 1, "--benchmark_display_aggregates_only=true");
  }
  std::vector<char*> args;
  for (std::string& s : storage) args.push_back(s.data());
  int n = static_cast<int>(args.size());
  benchmark::Initialize(&n, args.data());
  if (benchmark::ReportUnrecognizedArguments(n, args.data())) return 1;
  skerry::RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  reporter.PrintRatios();
  benchmark::Shutdown();
  return 0;
}
