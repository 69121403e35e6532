#include "skerry/solvers/sensor_block.h"

#include <stdexcept>

#include "skerry/factors/linear_prior_factor.h"
#include "skerry/io/csv_reader.h"

namespace skerry {

namespace {
int SlotAmbientSize(Slot s) { return s == Slot::kQ || s == Slot::kExtrinsicQ ? 4 : 3; }
}  // namespace

std::vector<BlockRef> SensorBlocks(const SensorSpec& spec,
                                   const SensorMeasurement& m,
                                   KeyframeId keyframe) {
  std::vector<BlockRef> blocks;
  for (Slot s : m.slots) blocks.push_back({keyframe, s});
  if (spec.has_extrinsic) {
    for (const BlockRef& b : ExtrinsicBlocks(m.sensor)) blocks.push_back(b);
  }
  return blocks;
}

void CheckMeasurement(const SensorSpec& spec, const SensorMeasurement& m) {
  const std::string who = "sensor '" + spec.name + "' at t=" + FormatSeconds(m.t_ns) + ": ";
  if (!m.cost) throw std::invalid_argument(who + "measurement without a cost function");
  if (m.slots.empty()) throw std::invalid_argument(who + "measurement on no keyframe block");
  const std::vector<int32_t>& sizes = m.cost->parameter_block_sizes();
  const size_t expected = m.slots.size() + (spec.has_extrinsic ? 2 : 0);
  if (sizes.size() != expected) {
    throw std::invalid_argument(who + "the cost takes " + std::to_string(sizes.size()) +
                                " parameter blocks, the slots (and extrinsic) make " +
                                std::to_string(expected));
  }
  for (size_t k = 0; k < m.slots.size(); ++k) {
    if (IsExtrinsic(m.slots[k])) {
      throw std::invalid_argument(who + "extrinsic slots come from the sensor, not the block");
    }
    if (sizes[k] != SlotAmbientSize(m.slots[k])) {
      throw std::invalid_argument(who + "parameter block " + std::to_string(k) +
                                  " has the wrong size for its slot");
    }
  }
  if (spec.has_extrinsic && (sizes[m.slots.size()] != 4 || sizes[m.slots.size() + 1] != 3)) {
    throw std::invalid_argument(who + "the extrinsic blocks must be q_b_s (4) and p_b_s (3)");
  }
  if (m.cost->num_residuals() <= 0) throw std::invalid_argument(who + "no residuals");
}

void AddSensorExtrinsic(NavGraph* graph, SensorId id, const SensorSpec& spec) {
  if (!spec.has_extrinsic) return;
  const bool estimated = spec.calibrate;
  graph->AddExtrinsic(id, spec.q_b_s, spec.p_b_s, estimated);
  if (!estimated) return;
  if (!(spec.extrinsic_prior_sigma_rad > 0.0) || !(spec.extrinsic_prior_sigma_m > 0.0)) {
    throw std::invalid_argument("sensor '" + spec.name +
                                "': calibrate needs positive extrinsic prior sigmas");
  }
  // A Gaussian prior at the given mounting: r = diag(1/sigma) (x (-) x0) on (q_b_s, p_b_s).
  Eigen::Matrix<double, 6, 1> sqrt_info;
  sqrt_info << Eigen::Vector3d::Constant(1.0 / spec.extrinsic_prior_sigma_rad),
      Eigen::Vector3d::Constant(1.0 / spec.extrinsic_prior_sigma_m);
  std::vector<Eigen::VectorXd> x0 = {Eigen::Vector4d(spec.q_b_s.normalized().coeffs()), spec.p_b_s};
  graph->AddFactor(FactorKind::kExtrinsicPrior,
                   std::make_unique<LinearPriorFactor>(std::vector<int>{4, 3}, std::move(x0),
                                                       Eigen::MatrixXd(sqrt_info.asDiagonal()),
                                                       Eigen::VectorXd::Zero(6)),
                   nullptr, ExtrinsicBlocks(id));
}

}  // namespace skerry
