// What one LiDAR scan alone says about the pose, against the simulator's truth: for every scan of
// a simulated dataset with a LiDAR and an orthophoto (the harbour scenarios), the scan's block is
// prepared at the *true* state (levelled, deskewed and cut as the window would at a perfect
// prediction), then the planar pose (x, y, yaw) alone is moved to the minimum of the scan's
// map-alignment cost, from the truth and from a start 1.5 m / 1.5 deg off. The offset of that
// minimum from the truth is the frontend's own error (map, edges, model), which no estimator
// behind it can remove; the share of perturbed starts that come back says how wide its basin is.
//   skerry_harbour_scan_fixes --dataset DIR [--config PRESET] [--csv FILE]
// Prints medians and RMS over the scans, along and across the vessel's heading. The CSV adds,
// per scan, its cost along its weakest horizontal direction at the truth: the best rival minimum
// within 6 m, the truth's cost over the minimum's, and the cost's rise over 0.5, 1 and 2 m against
// its local curvature (with a preset's information_scale_m > 0 the block is already the one that
// keeps only what that rise bears out: information_at_scale.h; set it to 0 to see the raw block).

#include <ceres/ceres.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <memory>
#include <numeric>
#include <optional>
#include <string>
#include <vector>

#include "bench_util.h"
#include "skerry/core/input_error.h"
#include "skerry/frontends/dataset_sensors.h"
#include "skerry/io/dataset.h"
#include "skerry/lidar_aerial/information_at_scale.h"
#include "skerry/lidar_aerial/lidar_aerial_frontend.h"
#include "skerry/solvers/estimator_config.h"
#include "skerry/solvers/sensor_block.h"

namespace skerry::bench {
namespace {

// The truth at t (linear in position and velocity, slerp in attitude) and the body rate there.
bool TruthAt(const std::vector<NavState>& truth, TimeNs t, NavState* x, Eigen::Vector3d* w_b) {
  const auto it = std::lower_bound(truth.begin(), truth.end(), t,
                                   [](const NavState& s, TimeNs v) { return s.t_ns < v; });
  if (it == truth.begin() || it == truth.end()) return false;
  const NavState& a = *(it - 1);
  const NavState& b = *it;
  const double dt = NsToSeconds(b.t_ns - a.t_ns);
  const double s = NsToSeconds(t - a.t_ns) / dt;
  *x = a;
  x->t_ns = t;
  x->p_w_b = (1 - s) * a.p_w_b + s * b.p_w_b;
  x->v_w = (1 - s) * a.v_w + s * b.v_w;
  x->q_w_b = a.q_w_b.slerp(s, b.q_w_b);
  const Eigen::AngleAxisd d(a.q_w_b.conjugate() * b.q_w_b);
  *w_b = d.axis() * d.angle() / dt;
  return true;
}

// The scan's cost on (q, p, v) seen as a function of a planar offset (dx, dy, dyaw) of the pose.
struct PlanarOffset {
  const ceres::CostFunction* cost;
  NavState at;
  bool operator()(const double* const* offset, double* residuals) const {
    const double* o = offset[0];
    const Eigen::Quaterniond q =
        (Eigen::AngleAxisd(o[2], Eigen::Vector3d::UnitZ()) * at.q_w_b).normalized();
    const Eigen::Vector3d p = at.p_w_b + Eigen::Vector3d(o[0], o[1], 0.0);
    const double* values[] = {q.coeffs().data(), p.data(), at.v_w.data()};
    return cost->Evaluate(values, residuals, nullptr);
  }
};

Eigen::Vector3d Minimise(const std::shared_ptr<ceres::CostFunction>& cost,
                         const NavState& at,
                         const Eigen::Vector3d& start) {
  auto* f = new ceres::DynamicNumericDiffCostFunction<PlanarOffset, ceres::CENTRAL>(
      new PlanarOffset{cost.get(), at});
  f->AddParameterBlock(3);
  f->SetNumResiduals(cost->num_residuals());
  Eigen::Vector3d x = start;
  ceres::Problem problem;
  problem.AddResidualBlock(f, nullptr, x.data());
  ceres::Solver::Options o;
  o.max_num_iterations = 50;
  o.linear_solver_type = ceres::DENSE_QR;
  ceres::Solver::Summary summary;
  ceres::Solve(o, &problem, &summary);
  return x;
}

// The cost ||r||^2 at the planar offset o (dx, dy, dyaw) of `at`; infinity where not evaluable.
double CostAt(const ceres::CostFunction& cost, const NavState& at, const Eigen::Vector3d& o) {
  std::vector<double> r(static_cast<size_t>(cost.num_residuals()));
  const double* offset[] = {o.data()};
  if (!PlanarOffset{&cost, at}(offset, r.data())) return std::numeric_limits<double>::infinity();
  return Eigen::Map<const Eigen::VectorXd>(r.data(), static_cast<Eigen::Index>(r.size()))
      .squaredNorm();
}

// The best rival of the minimum x along the scan's weak horizontal direction w: the cost profile
// f(s) = cost(x + s w) over |s| <= 6 m in 0.1 m steps, and of its local minima other than the
// one at s = 0 the lowest; (s, f(s) - f(0)), or (0, inf) when there is none.
Eigen::Vector2d Rival(const ceres::CostFunction& cost,
                      const NavState& at,
                      const Eigen::Vector3d& x,
                      const Eigen::Vector2d& w) {
  constexpr int kSteps = 60;
  constexpr double kStep = 0.1;
  std::vector<double> f(2 * kSteps + 1);
  for (int i = -kSteps; i <= kSteps; ++i) {
    f[i + kSteps] = CostAt(cost, at, x + Eigen::Vector3d(i * kStep * w.x(), i * kStep * w.y(), 0));
  }
  Eigen::Vector2d best(0.0, std::numeric_limits<double>::infinity());
  // The basin of s = 0: climb from it both ways to the hills that bound it; a rival lies beyond.
  int lo = kSteps, hi = kSteps;
  while (lo > 0 && f[lo - 1] >= f[lo]) --lo;
  while (hi < 2 * kSteps && f[hi + 1] >= f[hi]) ++hi;
  for (int i = 1; i < 2 * kSteps; ++i) {
    if (i >= lo && i <= hi) continue;
    if (f[i] <= f[i - 1] && f[i] <= f[i + 1] && f[i] - f[kSteps] < best.y()) {
      best = Eigen::Vector2d((i - kSteps) * kStep, f[i] - f[kSteps]);
    }
  }
  return best;
}

struct Stats {
  std::vector<double> along, across, yaw_deg, horizontal;
  int recovered = 0, perturbed = 0;
};

void Print(const char* name, const Stats& s) {
  auto rms = [](const std::vector<double>& v) {
    double a = 0.0;
    for (double x : v) a += x * x;
    return v.empty() ? 0.0 : std::sqrt(a / v.size());
  };
  std::vector<double> abs_yaw;
  for (double y : s.yaw_deg) abs_yaw.push_back(std::abs(y));
  std::printf(
      "%-18s scans %4zu  horizontal median %.3f m RMS %.3f m | along mean %+.3f RMS %.3f | across "
      "mean %+.3f RMS %.3f | yaw median |%.3f| RMS %.3f deg",
      name, s.horizontal.size(), Median(s.horizontal), rms(s.horizontal),
      s.along.empty() ? 0.0 : std::accumulate(s.along.begin(), s.along.end(), 0.0) / s.along.size(),
      rms(s.along),
      s.across.empty() ? 0.0
                       : std::accumulate(s.across.begin(), s.across.end(), 0.0) / s.across.size(),
      rms(s.across), Median(abs_yaw), rms(s.yaw_deg));
  if (s.perturbed > 0) std::printf(" | back within 0.5 m: %d/%d", s.recovered, s.perturbed);
  std::printf("\n");
}

int Main(const Flags& flags) {
  const std::string dataset = flags.String("dataset");
  if (dataset.empty()) throw UsageError("--dataset is required");
  const std::string preset = flags.String("config"), csv = flags.String("csv");
  const std::string consumer = flags.String("blocks");
  if (consumer != "window" && consumer != "batch") {
    throw UsageError("--blocks must be window or batch, not '" + consumer + "'");
  }
  const bool batch = consumer == "batch";
  const Dataset data = LoadDataset(dataset);
  if (data.truth_states.empty()) throw UsageError(dataset + ": no truth_states.csv (simulated)");
  const EstimatorConfig config = LoadPreset(preset);
  const SensorLog log = DatasetSensors(data, config);
  std::ofstream out;
  if (!csv.empty()) {
    out.open(csv);
    out << "t_s,dx_m,dy_m,dyaw_deg,along_m,across_m,pdx_m,pdy_m,pdyaw_deg,constraint_ratio,"
           "weak_x,weak_y,rival_s_m,rival_dcost,truth_s_m,truth_dcost,min_cost,residuals,weak_info,"
           "secant_05,secant_1,secant_2\n";
  }
  Stats from_truth, from_off;
  int flagged_off = 0, unflagged_off = 0, flagged_on = 0;
  int k = 0;
  for (const SensorMeasurement& m : log.measurements) {
    if (!m.prepare) continue;
    NavState at;
    Eigen::Vector3d w_b;
    if (!TruthAt(data.truth_states, m.t_ns, &at, &w_b)) continue;
    const std::shared_ptr<ceres::CostFunction> cost =
        m.prepare(at, w_b, batch ? BlockConsumer::kBatch : BlockConsumer::kWindow).cost;
    if (!cost) continue;
    const double yaw =
        std::atan2(at.q_w_b.toRotationMatrix()(1, 0), at.q_w_b.toRotationMatrix()(0, 0));
    const Eigen::Vector2d fwd(std::cos(yaw), std::sin(yaw)), left(-fwd.y(), fwd.x());
    const Eigen::Vector3d x = Minimise(cost, at, Eigen::Vector3d::Zero());
    // The scan's degeneracy at the truth, as the frontend measures it (information_at_scale.h,
    // here on the local curvature): the ratio of the eigenvalues of its horizontal information.
    const std::optional<lidar_aerial::WeakDirection> local =
        lidar_aerial::MeasureWeakDirection(*cost, at, 0.0);
    const double ratio = local ? local->constraint_ratio : 0.0;
    const double weak_info = local ? local->local : 0.0;
    const Eigen::Vector2d weak = local ? local->direction : Eigen::Vector2d::UnitX().eval();
    // Is the scan's cost multimodal along its weak direction, and where does the truth sit?
    const Eigen::Vector2d rival = Rival(*cost, at, x, weak);
    const double truth_s = -weak.dot(x.head<2>());
    const double truth_dcost = CostAt(*cost, at, Eigen::Vector3d::Zero()) - CostAt(*cost, at, x);
    const bool degenerate = ratio < lidar_aerial::kDegenerateConstraintRatio;
    const bool off = x.head<2>().norm() > 1.0;
    flagged_off += degenerate && off;
    unflagged_off += !degenerate && off;
    flagged_on += degenerate && !off;
    from_truth.along.push_back(fwd.dot(x.head<2>()));
    from_truth.across.push_back(left.dot(x.head<2>()));
    from_truth.horizontal.push_back(x.head<2>().norm());
    from_truth.yaw_deg.push_back(x.z() * 180.0 / M_PI);
    // A start off by 1.5 m in a direction and 1.5 deg that turn with the scan's index.
    const double a = 2.399963 * k++;  // the golden angle: directions spread evenly
    const Eigen::Vector3d start(1.5 * std::cos(a), 1.5 * std::sin(a),
                                (k % 2 ? 1.5 : -1.5) * M_PI / 180.0);
    const Eigen::Vector3d y = Minimise(cost, at, start);
    ++from_off.perturbed;
    from_off.recovered += (y.head<2>() - x.head<2>()).norm() < 0.5;
    from_off.horizontal.push_back(y.head<2>().norm());
    from_off.along.push_back(fwd.dot(y.head<2>()));
    from_off.across.push_back(left.dot(y.head<2>()));
    from_off.yaw_deg.push_back(y.z() * 180.0 / M_PI);
    if (out) {
      out << NsToSeconds(m.t_ns) << ',' << x.x() << ',' << x.y() << ',' << x.z() * 180.0 / M_PI
          << ',' << from_truth.along.back() << ',' << from_truth.across.back() << ',' << y.x()
          << ',' << y.y() << ',' << y.z() * 180.0 / M_PI << ',' << ratio << ',' << weak.x() << ','
          << weak.y() << ',' << rival.x() << ',' << rival.y() << ',' << truth_s << ','
          << truth_dcost << ',' << CostAt(*cost, at, x) << ',' << cost->num_residuals() << ','
          << weak_info;
      // The cost's rise along the weak direction from the truth, over s^2: the information the
      // cost itself has along it at the scale s (f(s) - f(0) = s^2 w^T J^T J w if quadratic).
      for (double step : {0.5, 1.0, 2.0}) {
        const auto at_scale = lidar_aerial::MeasureWeakDirection(*cost, at, step);
        out << ',' << (at_scale ? at_scale->at_scale : 0.0);
      }
      out << '\n';
    }
  }
  std::printf("%s (%s): each scan's own minimum, prepared at the truth\n", data.name.c_str(),
              preset.c_str());
  Print("from the truth", from_truth);
  Print("from 1.5 m/1.5 deg", from_off);
  std::printf(
      "degeneracy flag (constraint ratio < %.2f): %d of the %d scans whose own minimum is more "
      "than 1 m off; %d of the others\n",
      lidar_aerial::kDegenerateConstraintRatio, flagged_off, flagged_off + unflagged_off,
      flagged_on);
  return 0;
}

}  // namespace
}  // namespace skerry::bench

int main(int argc, char** argv) {
  skerry::bench::Flags flags;
  flags.Declare("dataset", "",
                "a simulated dataset with a LiDAR, an orthophoto and truth_states.csv");
  flags.Declare("config", "lidar-harbour", "estimator preset or YAML file");
  flags.Declare("csv", "", "write one row per scan here");
  flags.Declare("blocks", "window",
                "whose blocks: the window's or the batch's (their losses differ: "
                "lidar_aerial.loss, batch_loss)");
  return skerry::bench::RunMain(flags, argc, argv,
                                "Each scan's own pose minimum against the simulator's truth",
                                [&flags]() { return skerry::bench::Main(flags); });
}
