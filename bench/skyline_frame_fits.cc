/// \file
/// Each frame of a dataset on its own, at the ground truth: is what one frame claims about the
/// camera's position what its cost holds? Per frame, its skyline is extracted as the frontend
/// does and refined alone (RefineFrame: the full pose with the frame locator's tilt and height
/// priors, no horizontal prior) from the true camera pose. Printed per frame:
///   - the solution's horizontal offset from the truth (east, north, m) and the covariance it
///     claims (sigma east, north, m; correlation), and the offset's NEES (2 on average when the
///     claim is right);
///   - the frame's cost at the solution and with the position held at the truth (orientation
///     refined): LM stops where the gradient of its Jacobians vanishes, so a cost at the truth
///     below the solution's says the Jacobians point elsewhere than the cost;
///   - the position Jacobian against the residuals re-evaluated 1 m along the offset (the
///     whitened residuals' change against J dp: ratio of norms, and cosine; 1 and 1 when the
///     Jacobian is the cost's).
/// A last line gives the means. This found the horizon's position derivatives 34 % off on a DEM's
/// bilinear surface (stop 66, docs/results.md).
/// Usage: skerry_skyline_frame_fits DATASET_DIR [T0 T1 [EVERY]] [--set KEY=VALUE]...
///   e.g. skerry_skyline_frame_fits D 900 1200 5   (every 5th frame between 900 and 1200 s)
///   --set as `skerry run`'s, on the default preset (e.g. --set skyline.dem_spacing_m=30)

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <optional>
#include <string>
#include <vector>

#include "skerry/io/dataset.h"
#include "skerry/io/trajectory.h"
#include "skerry/skyline/camera_model.h"
#include "skerry/skyline/frame_locator.h"
#include "skerry/skyline/skyline_extraction.h"
#include "skerry/skyline/skyline_residual.h"
#include "skerry/solvers/estimator_config.h"
#include "skyline_truth.h"

using namespace skerry;

int main(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "--help") {
    std::fprintf(argc < 2 ? stderr : stdout,
                 "usage: skerry_skyline_frame_fits DATASET_DIR [T0 T1 [EVERY]] "
                 "[--set KEY=VALUE]...\n");
    return argc < 2 ? 2 : 0;
  }
  std::vector<std::string> positional, overrides;
  for (int i = 1; i < argc; ++i) {
    if (std::string(argv[i]) == "--set" && i + 1 < argc) {
      overrides.emplace_back(argv[++i]);
    } else {
      positional.emplace_back(argv[i]);
    }
  }
  const std::string dir = positional[0];
  const size_t np = positional.size();
  const double t0 = np > 2 ? std::atof(positional[1].c_str()) : -1e18;
  const double t1 = np > 2 ? std::atof(positional[2].c_str()) : 1e18;
  const int every = np > 3 ? std::max(1, std::atoi(positional[3].c_str())) : 1;
  try {
    const EstimatorConfig config = LoadPreset("default", overrides);
    const SkylineConfig& sc = config.skyline;
    const std::optional<bench::SkylineTruthData> loaded = bench::LoadSkylineTruthData(dir, sc, 0);
    if (!loaded) return 2;
    const Dataset& data = loaded->data;
    const auto& horizon = loaded->horizon;
    const CameraConfig& camera_config = data.cameras[0];
    const skyline::CameraModel camera(camera_config);
    skyline::FrameLocatorOptions options;
    options.residual.sigma_px = sc.sigma_px;
    options.residual.correlation_px = sc.correlation_px;
    options.residual.huber_sigmas = sc.huber_sigmas;
    options.residual.max_chain_gap_px = 5.0 * sc.column_stride_px;
    skyline::FrameLocatorOptions held = options;
    held.horizontal_sigma_m = 0.01;

    std::printf(
        "t_s east_m north_m sigma_east_m sigma_north_m correlation nees2 cost cost_at_truth "
        "jacobian_norm_ratio jacobian_cos\n");
    int k = 0, n = 0;
    double sum_e = 0, sum_n = 0, sum_nees = 0, sum_ratio = 0, sum_cos = 0;
    int truth_lower = 0;
    for (const SensorFrame& f : data.camera_frames[0]) {
      const double t = NsToSeconds(f.t_ns);
      if (t < t0 || t > t1 || k++ % every != 0) continue;
      StampedPose truth;
      if (!InterpolatePose(data.groundtruth, f.t_ns, &truth)) continue;
      const std::string path = (std::filesystem::path(camera_config.image_dir) / f.file).string();
      const cv::Mat image = cv::imread(path, cv::IMREAD_UNCHANGED);
      if (image.empty()) throw std::runtime_error(path + ": cannot be read as an image");
      const auto samples =
          skyline::FrameSamples(image, camera, sc.source, sc.column_stride_px, sc.min_confidence);
      if (static_cast<int>(samples.size()) < sc.min_samples) continue;
      const Eigen::Quaterniond q_w_c = truth.q_w_b * camera_config.T_b_c.q_b_s;
      const Eigen::Vector3d p_w_c = truth.p_w_b + truth.q_w_b * camera_config.T_b_c.p_b_s;
      const Eigen::Matrix3d r_w_c = q_w_c.toRotationMatrix();
      const skyline::FrameLocation fit =
          skyline::RefineFrame(horizon, camera, samples, q_w_c, p_w_c, r_w_c, p_w_c, options);
      const skyline::FrameLocation at_truth =
          skyline::RefineFrame(horizon, camera, samples, q_w_c, p_w_c, r_w_c, p_w_c, held);
      if (!fit.ok) continue;
      const Eigen::Vector2d offset = (fit.p_w_c - p_w_c).head<2>();
      const Eigen::Matrix2d cov = fit.covariance.block<2, 2>(3, 3);
      const double nees = offset.dot(cov.ldlt().solve(offset));

      // The Jacobian against the residuals' change over 1 m along the offset (or east when the
      // fit did not move), at the true pose.
      const skyline::SkylineResidualModel model(horizon, camera, samples, options.residual);
      Eigen::Vector3d dir = Eigen::Vector3d::UnitX();
      if (offset.norm() > 1e-6) dir.head<2>() = offset.normalized();
      std::vector<double> r0(static_cast<size_t>(model.size())), r1(r0.size());
      Eigen::Matrix<double, Eigen::Dynamic, 3> j_rot, j_pos;
      model.Evaluate(r_w_c, p_w_c, r0.data(), &j_rot, &j_pos);
      model.Evaluate(r_w_c, p_w_c + dir, r1.data(), nullptr, nullptr);
      double numeric2 = 0, linear2 = 0, dot = 0;
      for (int i = 0; i < model.size(); ++i) {
        const double a = r1[static_cast<size_t>(i)] - r0[static_cast<size_t>(i)];
        const double b = j_pos.row(i).dot(dir);
        numeric2 += a * a;
        linear2 += b * b;
        dot += a * b;
      }
      const double ratio = std::sqrt(linear2 / numeric2);
      const double cosine = dot / std::sqrt(numeric2 * linear2);

      std::printf("%.2f %.2f %.2f %.2f %.2f %.3f %.2f %.3f %.3f %.3f %.3f\n", t, offset.x(),
                  offset.y(), std::sqrt(cov(0, 0)), std::sqrt(cov(1, 1)),
                  cov(0, 1) / std::sqrt(cov(0, 0) * cov(1, 1)), nees, fit.cost, at_truth.cost,
                  ratio, cosine);
      ++n;
      sum_e += offset.x();
      sum_n += offset.y();
      sum_nees += nees;
      sum_ratio += ratio;
      sum_cos += cosine;
      truth_lower += at_truth.cost < fit.cost;
    }
    if (n == 0) {
      std::fprintf(stderr, "%s: no frame with a skyline in the span\n", dir.c_str());
      return 1;
    }
    std::printf(
        "# %d frames: mean offset east %.2f north %.2f m; mean NEES %.2f (2 if the covariance is "
        "right); cost at the truth below the fit's on %d; Jacobian norm ratio %.3f, cosine %.3f "
        "(means)\n",
        n, sum_e / n, sum_n / n, sum_nees / n, truth_lower, sum_ratio / n, sum_cos / n);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
  return 0;
}
