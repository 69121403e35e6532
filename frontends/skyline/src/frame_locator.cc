#include "skerry/skyline/frame_locator.h"

#include <ceres/ceres.h>

#include <algorithm>
#include <chrono>
#include <cmath>

#include "skerry/core/parallel_for.h"

namespace skerry::skyline {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

// The camera's world up in its own frame against the IMU's: the tilt prior (2 informative
// components of 3).
struct TiltPrior {
  TiltPrior(const Eigen::Vector3d& up_c, double sigma) : up_c(up_c), sigma(sigma) {}
  template <typename T>
  bool operator()(const T* q, T* r) const {
    const Eigen::Map<const Eigen::Quaternion<T>> q_w_c(q);
    const Eigen::Matrix<T, 3, 1> up = q_w_c.conjugate() * Eigen::Matrix<T, 3, 1>(T(0), T(0), T(1));
    for (int i = 0; i < 3; ++i) r[i] = (up[i] - T(up_c[i])) / T(sigma);
    return true;
  }
  Eigen::Vector3d up_c;
  double sigma;
};

struct PositionPrior {
  PositionPrior(const Eigen::Vector3d& p0, const Eigen::Vector3d& inv_sigma)
      : p0(p0), inv_sigma(inv_sigma) {}
  template <typename T>
  bool operator()(const T* p, T* r) const {
    for (int i = 0; i < 3; ++i) r[i] = (p[i] - T(p0[i])) * T(inv_sigma[i]);
    return true;
  }
  Eigen::Vector3d p0, inv_sigma;
};

double SecondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

// The map with every n-th node in each direction, for the coarse profiles; the map itself for
// n <= 1 or a map too small to thin.
std::shared_ptr<const HorizonPredictor> CoarseMap(
    const std::shared_ptr<const HorizonPredictor>& horizon, int n) {
  const geo::EnuHeightGrid& g = horizon->grid();
  if (n <= 1 || (g.cols - 1) / n + 1 < 2 || (g.rows - 1) / n + 1 < 2) return horizon;
  return std::make_shared<const HorizonPredictor>(
      geo::Resampled(g, g.origin_w, n * g.spacing_m, (g.cols - 1) / n + 1, (g.rows - 1) / n + 1),
      horizon->options());
}

struct Candidate {
  double cost = 0.0;
  Eigen::Vector2d xy = Eigen::Vector2d::Zero();
  double heading_rad = 0.0;
};

}  // namespace

FrameLocation RefineFrame(std::shared_ptr<const HorizonPredictor> horizon,
                          const CameraModel& camera,
                          const std::vector<SkylineSample>& samples,
                          const Eigen::Quaterniond& q_w_c0,
                          const Eigen::Vector3d& p_w_c0,
                          const Eigen::Matrix3d& r_level_c,
                          const Eigen::Vector3d& prior_p_w_c,
                          const FrameLocatorOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  FrameLocation out;
  std::shared_ptr<const SkylineResidualModel> model;
  try {
    auto m = std::make_shared<SkylineResidualModel>(horizon, camera, samples, options.residual);
    // 0 leaves the model as it is; a negative or non-finite sigma or length throws (reason).
    m->AddMapError(q_w_c0.normalized().toRotationMatrix(), p_w_c0, options.dem_sigma_m,
                   options.map_correlation_m);
    model = std::move(m);
  } catch (const std::invalid_argument& e) {
    out.reason = e.what();
    return out;
  }
  Eigen::Quaterniond q = q_w_c0.normalized();
  Eigen::Vector3d p = p_w_c0;
  Eigen::Quaterniond q_b_c = Eigen::Quaterniond::Identity();
  Eigen::Vector3d p_b_c = Eigen::Vector3d::Zero();
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  problem.AddResidualBlock(new SkylineCost(model), nullptr, q.coeffs().data(), p.data(),
                           q_b_c.coeffs().data(), p_b_c.data());
  problem.SetManifold(q.coeffs().data(), new ceres::EigenQuaternionManifold);
  problem.SetParameterBlockConstant(q_b_c.coeffs().data());
  problem.SetParameterBlockConstant(p_b_c.data());
  // Planar: tilt and height held by stiff priors (prior work's 2-DOF position plus heading).
  const double tilt_sigma = options.planar ? 1e-5 : options.tilt_sigma_rad;
  const double height_sigma = options.planar ? 1e-4 : options.height_sigma_m;
  const Eigen::Vector3d up_c = r_level_c.transpose() * Eigen::Vector3d::UnitZ();
  problem.AddResidualBlock(
      new ceres::AutoDiffCostFunction<TiltPrior, 3, 4>(new TiltPrior(up_c, tilt_sigma)), nullptr,
      q.coeffs().data());
  const double inv_h = options.horizontal_sigma_m > 0 ? 1.0 / options.horizontal_sigma_m : 0.0;
  problem.AddResidualBlock(new ceres::AutoDiffCostFunction<PositionPrior, 3, 3>(new PositionPrior(
                               prior_p_w_c, Eigen::Vector3d(inv_h, inv_h, 1.0 / height_sigma))),
                           nullptr, p.data());
  ceres::Solver::Options solver;
  solver.max_num_iterations = 50;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.num_threads = 1;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &problem, &summary);
  out.q_w_c = q;
  out.p_w_c = p;
  const std::vector<double> errors = model->PixelErrors(q.toRotationMatrix(), p);
  double sum2 = 0.0;
  for (double e : errors) {
    if (std::isnan(e)) continue;
    sum2 += e * e;
    ++out.active_samples;
  }
  out.rms_px = out.active_samples > 0 ? std::sqrt(sum2 / out.active_samples) : 0.0;
  out.candidates_refined = 1;
  out.cost = summary.final_cost;
  ceres::Covariance::Options cov_options;
  cov_options.algorithm_type = ceres::DENSE_SVD;
  // Never a pseudo-inverse: dropping the weakest direction of J'J (Ceres' null_space_rank -1 drops
  // those below 1e-14 of the strongest) reports it as known exactly, and one frame's weakest
  // direction, its range to the ridges, is real information a few orders below the stiff tilt
  // and height priors of the planar mode. The SVD of J resolves singular values 1e-10 of the
  // largest; a direction weaker than that is no information, and the covariance fails (NaN).
  cov_options.null_space_rank = 0;
  cov_options.min_reciprocal_condition_number = 1e-20;
  ceres::Covariance covariance(cov_options);
  std::vector<const double*> blocks = {q.coeffs().data(), p.data()};
  if (covariance.Compute(blocks, &problem)) {
    covariance.GetCovarianceMatrixInTangentSpace(blocks, out.covariance.data());
  } else {
    out.covariance.setConstant(std::nan(""));
  }
  if (out.active_samples < options.min_samples) {
    out.reason = "only " + std::to_string(out.active_samples) + " samples with a horizon";
  } else if (out.rms_px > options.max_rms_px) {
    out.reason = "skyline does not fit (RMS " + std::to_string(out.rms_px) + " px)";
  } else if (!summary.IsSolutionUsable()) {
    out.reason = "solver failed: " + summary.message;
  } else {
    out.ok = true;
  }
  out.seconds = SecondsSince(t0);
  return out;
}

FrameLocation LocateFrame(std::shared_ptr<const HorizonPredictor> horizon,
                          const CameraModel& camera,
                          const std::vector<SkylineSample>& samples,
                          const Eigen::Matrix3d& r_level_c,
                          const Eigen::Vector3d& prior_p_w_c,
                          const FrameLocatorOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  FrameLocation out;
  if (static_cast<int>(samples.size()) < options.min_samples) {
    out.reason = "only " + std::to_string(samples.size()) + " skyline samples";
    return out;
  }
  // The samples levelled: azimuth at heading 0 and elevation (independent of heading).
  std::vector<double> alpha, elev, scale;
  for (const SkylineSample& s : samples) {
    const auto ray = camera.Ray(s.pixel);
    if (!ray) continue;
    const Eigen::Vector3d w = r_level_c * *ray;
    alpha.push_back(std::atan2(w.x(), w.y()));
    elev.push_back(std::atan2(w.z(), std::hypot(w.x(), w.y())));
    scale.push_back(camera.fy() / options.residual.sigma_px * std::sqrt(s.weight));
  }
  // Azimuths relative to the samples' middle: the regressor of the tilt.
  std::vector<double> alpha_rel(alpha.size());
  if (!alpha.empty()) {
    const double mid = alpha[alpha.size() / 2];
    for (size_t i = 0; i < alpha.size(); ++i)
      alpha_rel[i] = std::remainder(alpha[i] - mid, 2 * kPi);
  }
  const double step = options.azimuth_step_deg * kDeg;
  const int n_az = static_cast<int>(std::lround(2 * kPi / step));
  const double grid = options.grid_step_m > 0 ? options.grid_step_m : options.search_radius_m / 10;
  const int half = std::max(0, static_cast<int>(std::floor(options.search_radius_m / grid)));
  const double cap2 = std::pow(options.coarse_cap_px / options.residual.sigma_px, 2);
  int h_lo = 0, h_hi = n_az - 1;
  if (options.heading_window_deg < 180.0) {
    const int c = static_cast<int>(std::lround(options.prior_heading_deg * kDeg / step));
    const int w = static_cast<int>(std::ceil(options.heading_window_deg * kDeg / step));
    h_lo = c - w;
    h_hi = c + w;
  }
  // The profile azimuths the sweep reads: sample i at heading step hh reads indices
  // floor(alpha_i / step + hh) and the next, so the samples' span (about their middle, in case
  // it straddles +-180 deg) widened by the heading window, with a step of margin on either side.
  std::vector<char> needed(n_az, 1);
  if (!options.full_profiles && !alpha.empty() && h_hi - h_lo < n_az) {
    const auto [lo, hi] = std::minmax_element(alpha_rel.begin(), alpha_rel.end());
    const double mid = alpha[alpha.size() / 2];
    const int first = static_cast<int>(std::floor((mid + *lo) / step)) + h_lo - 2;
    const int last = static_cast<int>(std::floor((mid + *hi) / step)) + h_hi + 3;
    if (last - first < n_az) {
      std::fill(needed.begin(), needed.end(), 0);
      for (int k = first; k <= last; ++k) needed[((k % n_az) + n_az) % n_az] = 1;
    }
  }
  const long traced_per_node = std::count(needed.begin(), needed.end(), 1);
  const std::shared_ptr<const HorizonPredictor> coarse_map =
      CoarseMap(horizon, options.coarse_decimation);
  // Every grid node's best heading, each node on whichever of options.residual.threads threads
  // and written to its own slot: the same candidates in the same order on any number.
  const int side = 2 * half + 1;
  std::vector<Candidate> candidates(static_cast<size_t>(side) * side);
  ParallelFor(candidates.size(), options.residual.threads, [&](size_t node) {
    const int gy = static_cast<int>(node) / side - half;
    const int gx = static_cast<int>(node) % side - half;
    std::vector<double> profile(n_az, 0.0);
    std::vector<char> valid(n_az, 0);
    const Eigen::Vector3d p = prior_p_w_c + Eigen::Vector3d(gx * grid, gy * grid, 0.0);
    for (int k = 0; k < n_az; ++k) {
      if (!needed[k]) continue;
      const HorizonSample h = coarse_map->Trace(p, k * step, coarse_map->options().refraction_k,
                                                /*derivatives=*/false);
      valid[k] = h.valid && !h.truncated;
      profile[k] = h.elevation_rad;
    }
    Candidate best{1e300, p.head<2>(), 0.0};
    // Per heading: the samples' errors against the profile, less the line in azimuth that
    // fits them best (what an error of the IMU's pitch and roll does to a levelled skyline:
    // an offset and a tilt), capped and summed.
    std::vector<double> err(alpha.size());
    std::vector<char> ok(alpha.size());
    for (int hh = h_lo; hh <= h_hi; ++hh) {
      double sw = 0, sx = 0, sy = 0, sxx = 0, sxy = 0;
      int invalid = 0;
      for (size_t i = 0; i < alpha.size(); ++i) {
        double f = alpha[i] / step + hh;
        f -= n_az * std::floor(f / n_az);
        const int k0 = static_cast<int>(f) % n_az;
        const int k1 = (k0 + 1) % n_az;
        ok[i] = valid[k0] && valid[k1];
        if (!ok[i]) {
          ++invalid;
          continue;
        }
        const double t = f - std::floor(f);
        err[i] = scale[i] * (elev[i] - ((1 - t) * profile[k0] + t * profile[k1]));
        const double x = alpha_rel[i];
        sw += 1;
        sx += x;
        sy += err[i];
        sxx += x * x;
        sxy += x * err[i];
      }
      double a = 0, b = 0;
      const double det = sw * sxx - sx * sx;
      if (sw > 2 && std::abs(det) > 1e-12) {
        b = (sw * sxy - sx * sy) / det;
        a = (sy - b * sx) / sw;
      } else if (sw > 0) {
        a = sy / sw;
      }
      double cost = 0.5 * cap2 * invalid;
      for (size_t i = 0; i < alpha.size(); ++i) {
        if (!ok[i]) continue;
        const double e = err[i] - a - b * alpha_rel[i];
        cost += std::min(e * e, cap2);
      }
      if (cost < best.cost) {
        best.cost = cost;
        best.heading_rad = hh * step;
      }
    }
    candidates[node] = best;
    return true;
  });
  std::sort(candidates.begin(), candidates.end(),
            [](const Candidate& a, const Candidate& b) { return a.cost < b.cost; });
  const double coarse_score = candidates.empty() ? 0.0 : candidates.front().cost;
  const long coarse_traces = traced_per_node * static_cast<long>(candidates.size());
  const double coarse_seconds = SecondsSince(t0);
  // Distinct candidates: apart by more than 1.5 grid steps or 3 deg of heading.
  std::vector<Candidate> chosen;
  for (const Candidate& c : candidates) {
    bool distinct = true;
    for (const Candidate& o : chosen) {
      const double dh = std::remainder(c.heading_rad - o.heading_rad, 2 * kPi);
      if ((c.xy - o.xy).norm() <= 1.5 * grid && std::abs(dh) <= 3 * kDeg) distinct = false;
    }
    if (distinct) chosen.push_back(c);
    if (static_cast<int>(chosen.size()) >= options.refine_candidates) break;
  }
  // The candidates refined, each on one of the threads (its own traces then on that thread).
  std::vector<FrameLocation> refined(chosen.size());
  ParallelFor(chosen.size(), options.residual.threads, [&](size_t i) {
    const Candidate& c = chosen[i];
    // World azimuth = levelled azimuth + heading: R_w_c = Rz(-heading) r_level_c.
    const Eigen::Quaterniond q0(Eigen::AngleAxisd(-c.heading_rad, Eigen::Vector3d::UnitZ()) *
                                r_level_c);
    const Eigen::Vector3d p0(c.xy.x(), c.xy.y(), prior_p_w_c.z());
    refined[i] = RefineFrame(horizon, camera, samples, q0, p0, r_level_c, prior_p_w_c, options);
    return true;
  });
  if (refined.empty()) {
    out.reason = "no candidate";
    out.coarse_score = coarse_score;
    out.coarse_traces = coarse_traces;
    out.coarse_seconds = coarse_seconds;
    out.seconds = SecondsSince(t0);
    return out;
  }
  // The winner: the lowest final cost among the usable ones.
  std::sort(refined.begin(), refined.end(), [](const FrameLocation& a, const FrameLocation& b) {
    if (a.ok != b.ok) return a.ok;
    return a.cost < b.cost;
  });
  out = refined.front();
  // Another minimum is distinct when it lies outside the winner's own uncertainty: its heading
  // more than 3 sigma (at least 0.05 deg) away, or its position beyond the 99.9 % ellipse.
  double second = 0.0;
  const double sigma_psi = std::sqrt(std::max(out.covariance(2, 2), 0.0));
  const Eigen::Matrix2d cp = out.covariance.block<2, 2>(3, 3) + Eigen::Matrix2d::Identity();
  for (size_t i = 1; i < refined.size(); ++i) {
    const FrameLocation& o = refined[i];
    const Eigen::Vector2d dp = (o.p_w_c - out.p_w_c).head<2>();
    const double dq = o.q_w_c.angularDistance(out.q_w_c);
    const bool apart = !out.covariance.allFinite() || dq > std::max(3.0 * sigma_psi, 0.05 * kDeg) ||
                       dp.dot(cp.ldlt().solve(dp)) > 13.8;
    if (apart) {
      second = o.cost;
      break;
    }
  }
  out.ambiguity = second > 0 ? out.cost / second : 0.0;
  out.candidates_refined = static_cast<int>(refined.size());
  out.coarse_score = coarse_score;
  out.coarse_traces = coarse_traces;
  out.coarse_seconds = coarse_seconds;
  out.seconds = SecondsSince(t0);
  return out;
}

}  // namespace skerry::skyline
