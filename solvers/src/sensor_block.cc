#include "skerry/solvers/sensor_block.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "skerry/factors/linear_prior_factor.h"
#include "skerry/io/csv_reader.h"

namespace skerry {

std::vector<BlockRef> SensorBlocks(const SensorSpec& spec,
                                   const SensorMeasurement& m,
                                   KeyframeId keyframe) {
  std::vector<BlockRef> blocks;
  for (Slot s : m.slots) blocks.push_back({keyframe, s});
  if (spec.has_extrinsic) {
    for (const BlockRef& b : ExtrinsicBlocks(m.sensor)) blocks.push_back(b);
  }
  if (spec.has_parameter) blocks.push_back(SensorParameterBlock(m.sensor));
  return blocks;
}

namespace {

std::string Who(const SensorSpec& spec, const SensorMeasurement& m) {
  return "sensor '" + spec.name + "' at t=" + FormatSeconds(m.t_ns) + ": ";
}

void CheckCost(const SensorSpec& spec, const SensorMeasurement& m) {
  const std::string who = Who(spec, m);
  const std::vector<int32_t>& sizes = m.cost->parameter_block_sizes();
  const size_t expected =
      m.slots.size() + (spec.has_extrinsic ? 2 : 0) + (spec.has_parameter ? 1 : 0);
  if (sizes.size() != expected) {
    throw std::invalid_argument(who + "the cost takes " + std::to_string(sizes.size()) +
                                " parameter blocks, the slots (and extrinsic, parameter) make " +
                                std::to_string(expected));
  }
  for (size_t k = 0; k < m.slots.size(); ++k) {
    if (IsSensorBlock(m.slots[k])) {
      throw std::invalid_argument(who + "a sensor's slots come from the sensor, not the block");
    }
    if (sizes[k] != SlotSize(m.slots[k])) {
      throw std::invalid_argument(who + "parameter block " + std::to_string(k) +
                                  " has the wrong size for its slot");
    }
  }
  if (spec.has_extrinsic && (sizes[m.slots.size()] != 4 || sizes[m.slots.size() + 1] != 3)) {
    throw std::invalid_argument(who + "the extrinsic blocks must be q_b_s (4) and p_b_s (3)");
  }
  if (spec.has_parameter && sizes.back() != 1) {
    throw std::invalid_argument(who + "the sensor's parameter block must be of size 1");
  }
  if (m.cost->num_residuals() <= 0) throw std::invalid_argument(who + "no residuals");
}

}  // namespace

void CheckMeasurement(const SensorSpec& spec, const SensorMeasurement& m, TimeNs* last_t_ns) {
  const std::string who = Who(spec, m);
  if (!m.cost && !m.prepare) {
    throw std::invalid_argument(who + "measurement without a cost function");
  }
  if (m.slots.empty()) throw std::invalid_argument(who + "measurement on no keyframe block");
  if (!(m.gate_scale > 0.0 && m.gate_scale <= 1.0)) {
    throw std::invalid_argument(who + "gate_scale must be in (0, 1], is " +
                                std::to_string(m.gate_scale));
  }
  if (m.cost) CheckCost(spec, m);
  if (m.t_ns <= *last_t_ns) throw std::invalid_argument(who + "time does not increase");
  *last_t_ns = m.t_ns;
}

bool PrepareMeasurement(const SensorSpec& spec,
                        SensorMeasurement* m,
                        const NavState& at,
                        const Eigen::Vector3d& gyro_rad_s,
                        BlockConsumer consumer) {
  if (m->cost) return true;
  if (!m->prepare) throw std::invalid_argument(Who(spec, *m) + "neither a cost nor a prepare");
  const PreparedBlock prepared = m->prepare(at, gyro_rad_s, consumer);
  if (!prepared.cost) return false;
  if (prepared.gate_scale != 0.0) {
    if (!(prepared.gate_scale > 0.0 && prepared.gate_scale <= 1.0)) {
      throw std::invalid_argument(Who(spec, *m) + "prepared gate_scale must be in (0, 1], is " +
                                  std::to_string(prepared.gate_scale));
    }
    m->gate_scale = prepared.gate_scale;
  }
  m->cost = prepared.cost;
  CheckCost(spec, *m);
  return true;
}

std::vector<const SensorMeasurement*> InTimeOrder(const SensorLog& log, TimeNs t_end_ns) {
  std::vector<const SensorMeasurement*> blocks;
  for (const SensorMeasurement& m : log.measurements) {
    if (m.t_ns <= t_end_ns) blocks.push_back(&m);
  }
  std::stable_sort(
      blocks.begin(), blocks.end(),
      [](const SensorMeasurement* a, const SensorMeasurement* b) { return a->t_ns < b->t_ns; });
  return blocks;
}

void AddSensorExtrinsic(NavGraph* graph,
                        SensorId id,
                        const SensorSpec& spec,
                        const Extrinsic* current,
                        const Eigen::Matrix<double, 6, 6>* covariance) {
  if (!spec.has_extrinsic) return;
  const bool estimated = spec.calibrate;
  const Eigen::Quaterniond q = current ? current->q_b_s() : spec.q_b_s;
  const Eigen::Vector3d p = current ? current->p_b_s() : spec.p_b_s;
  graph->AddExtrinsic(id, q, p, estimated);
  if (!estimated) return;
  if (!(spec.extrinsic_prior_sigma_rad > 0.0) || !(spec.extrinsic_prior_sigma_m > 0.0)) {
    throw std::invalid_argument("sensor '" + spec.name +
                                "': calibrate needs positive extrinsic prior sigmas");
  }
  // A Gaussian prior r = L^-1 (x (-) x0) on (q_b_s, p_b_s), L L^T its covariance.
  Eigen::Matrix<double, 6, 6> C = Eigen::Matrix<double, 6, 6>::Zero();
  C.diagonal() << Eigen::Vector3d::Constant(std::pow(spec.extrinsic_prior_sigma_rad, 2)),
      Eigen::Vector3d::Constant(std::pow(spec.extrinsic_prior_sigma_m, 2));
  if (covariance != nullptr) C = *covariance;
  std::unique_ptr<LinearPriorFactor> prior =
      LinearPriorFactor::FromCovariance({4, 3}, {Eigen::Vector4d(q.normalized().coeffs()), p}, C);
  if (prior == nullptr) {
    throw std::invalid_argument("sensor '" + spec.name +
                                "': extrinsic prior not positive definite");
  }
  graph->AddFactor(FactorKind::kExtrinsicPrior, std::move(prior), nullptr, ExtrinsicBlocks(id));
}

void AddSensorParameter(NavGraph* graph,
                        SensorId id,
                        const SensorSpec& spec,
                        const double* current,
                        const double* variance) {
  if (!spec.has_parameter) return;
  if (!std::isfinite(spec.parameter) || !(spec.parameter_prior_sigma >= 0.0) ||
      !std::isfinite(spec.parameter_prior_sigma)) {
    throw std::invalid_argument("sensor '" + spec.name +
                                "': its parameter and the prior's sigma must be finite, the "
                                "sigma >= 0");
  }
  const bool estimated = spec.parameter_prior_sigma > 0.0;
  const double value = current != nullptr ? *current : spec.parameter;
  graph->AddSensorParameter(id, value, estimated);
  if (!estimated) return;
  const double prior_variance = variance != nullptr && *variance > 0.0 && std::isfinite(*variance)
                                    ? *variance
                                    : spec.parameter_prior_sigma * spec.parameter_prior_sigma;
  std::unique_ptr<LinearPriorFactor> prior = LinearPriorFactor::FromCovariance(
      {1}, {Eigen::VectorXd::Constant(1, value)}, Eigen::MatrixXd::Constant(1, 1, prior_variance));
  if (prior == nullptr) {
    throw std::invalid_argument("sensor '" + spec.name + "': parameter prior's sigma too small");
  }
  graph->AddFactor(FactorKind::kExtrinsicPrior, std::move(prior), nullptr,
                   {SensorParameterBlock(id)});
}

}  // namespace skerry
