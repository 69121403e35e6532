/// \file
/// How the skyline's errors are correlated from frame to frame, measured at the ground truth: the
/// figures the frame weights of the skyline frontend model (skyline_frontend.h,
/// crest_correlation.h).
///
/// For a dataset with cameras, a DEM and a ground truth: each frame's skyline is extracted as the
/// frontend does, the true camera pose is interpolated from the ground truth, and each sample's
/// error in pixels against the horizon predicted there (SkylineResidualModel::PixelErrors) is
/// split by what makes its horizon: water (HorizonOnWater) or land. Per class, per frame, the
/// mean error over the frame's samples of that class (what moves the pose; the whitening along
/// the skyline takes out what varies across it), then over frame pairs j apart
///   r(j) = sum_k m_k m_{k+j} / sqrt(sum_k m_k^2 sum_k m_{k+j}^2)
/// (not centred: a lasting bias is a correlation the weights must carry) and the same centred on
/// the class's mean. The frames' own weights model r(1) as exp(-dt / tau) (time) times the
/// ground term (land) or 0 (water).
/// Usage: skerry_skyline_error_correlation DATASET_DIR [--config FILE] [--camera K]

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
#include "skerry/skyline/crest_correlation.h"
#include "skerry/skyline/skyline_extraction.h"
#include "skerry/skyline/skyline_residual.h"
#include "skerry/solvers/estimator_config.h"
#include "skyline_truth.h"

using namespace skerry;

namespace {

struct FrameMeans {
  double t_s = 0.0;
  double mean[2] = {NAN, NAN};  ///< water, land: mean error, px (NaN: fewer than kMinSamples)
  int count[2] = {0, 0};
  double spread[2] = {NAN, NAN};  ///< RMS about the frame's mean, px
  /// Per class: J^T r of the whitened residuals (the config's sigma and correlation along the
  /// skyline) for yaw, east and north: the pull the frame's error puts on the pose.
  double pull[2][3] = {{NAN, NAN, NAN}, {NAN, NAN, NAN}};
};

constexpr int kMinSamples = 10;

template <typename Get>
double Correlation(const std::vector<FrameMeans>& frames, Get get, int lag, double centre) {
  double sxy = 0, sxx = 0, syy = 0;
  for (size_t k = 0; k + lag < frames.size(); ++k) {
    const double x = get(frames[k]) - centre, y = get(frames[k + lag]) - centre;
    if (!std::isfinite(x) || !std::isfinite(y)) continue;
    sxy += x * y;
    sxx += x * x;
    syy += y * y;
  }
  return sxx > 0 && syy > 0 ? sxy / std::sqrt(sxx * syy) : NAN;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "--help") {
    std::fprintf(argc < 2 ? stderr : stdout,
                 "usage: skerry_skyline_error_correlation DATASET_DIR [--config FILE] "
                 "[--camera K]\n");
    return argc < 2 ? 2 : 0;
  }
  const std::string dir = argv[1];
  std::string config_path = "default";
  size_t camera_index = 0;
  for (int i = 2; i + 1 < argc; i += 2) {
    const std::string key = argv[i];
    if (key == "--config") {
      config_path = argv[i + 1];
    } else if (key == "--camera") {
      camera_index = static_cast<size_t>(std::atoi(argv[i + 1]));
    } else {
      std::fprintf(stderr, "unknown option %s\n", key.c_str());
      return 2;
    }
  }
  try {
    const EstimatorConfig config = LoadPreset(config_path);
    const SkylineConfig& sc = config.skyline;
    const std::optional<bench::SkylineTruthData> loaded =
        bench::LoadSkylineTruthData(dir, sc, camera_index);
    if (!loaded) return 2;
    const Dataset& data = loaded->data;
    const auto& horizon = loaded->horizon;
    const CameraConfig& camera_config = data.cameras[camera_index];
    const skyline::CameraModel camera(camera_config);
    skyline::SkylineResidualOptions options;
    options.sigma_px = sc.sigma_px;
    options.correlation_px = sc.correlation_px;
    options.huber_sigmas = 0.0;
    options.max_chain_gap_px = 5.0 * sc.column_stride_px;
    double chi2 = 0.0;
    long whitened = 0;
    std::vector<FrameMeans> frames;
    for (const SensorFrame& f : data.camera_frames[camera_index]) {
      StampedPose truth;
      if (!InterpolatePose(data.groundtruth, f.t_ns, &truth)) continue;
      const std::string path = (std::filesystem::path(camera_config.image_dir) / f.file).string();
      const cv::Mat image = cv::imread(path, cv::IMREAD_UNCHANGED);
      if (image.empty()) throw std::runtime_error(path + ": cannot be read as an image");
      const auto samples =
          skyline::FrameSamples(image, camera, sc.source, sc.column_stride_px, sc.min_confidence);
      if (static_cast<int>(samples.size()) < sc.min_samples) continue;
      const skyline::SkylineResidualModel model(horizon, camera, samples, options);
      const Eigen::Matrix3d r_w_c = (truth.q_w_b * camera_config.T_b_c.q_b_s).toRotationMatrix();
      const Eigen::Vector3d p_w_c = truth.p_w_b + truth.q_w_b * camera_config.T_b_c.p_b_s;
      const std::vector<double> errors = model.PixelErrors(r_w_c, p_w_c);
      std::vector<double> r(static_cast<size_t>(model.size()));
      Eigen::Matrix<double, Eigen::Dynamic, 3> j_rot, j_pos;
      model.Evaluate(r_w_c, p_w_c, r.data(), &j_rot, &j_pos);
      double sum[2] = {0, 0}, sum2[2] = {0, 0};
      double pull[2][3] = {{0, 0, 0}, {0, 0, 0}};
      FrameMeans m;
      m.t_s = NsToSeconds(f.t_ns);
      for (size_t i = 0; i < errors.size(); ++i) {
        if (!std::isfinite(errors[i])) continue;
        const Eigen::Vector3d r_w = r_w_c * model.rays_c()[i];
        const skyline::HorizonSample h = horizon->Trace(p_w_c, std::atan2(r_w.x(), r_w.y()));
        if (!h.valid || h.truncated) continue;
        const int cls = skyline::HorizonOnWater(*horizon, h.point_w) ? 0 : 1;
        sum[cls] += errors[i];
        sum2[cls] += errors[i] * errors[i];
        ++m.count[cls];
        pull[cls][0] += j_rot(static_cast<long>(i), 2) * r[i];
        pull[cls][1] += j_pos(static_cast<long>(i), 0) * r[i];
        pull[cls][2] += j_pos(static_cast<long>(i), 1) * r[i];
        chi2 += r[i] * r[i];
        ++whitened;
      }
      for (int c = 0; c < 2; ++c) {
        if (m.count[c] < kMinSamples) continue;
        for (int a = 0; a < 3; ++a) m.pull[c][a] = pull[c][a];
        m.mean[c] = sum[c] / m.count[c];
        m.spread[c] = std::sqrt(std::max(0.0, sum2[c] / m.count[c] - m.mean[c] * m.mean[c]));
      }
      frames.push_back(m);
    }
    const double dt =
        frames.size() > 1 ? (frames.back().t_s - frames.front().t_s) / (frames.size() - 1) : 0.0;
    std::printf(
        "%s, camera %s: %zu frames, %.2f s apart on average; whitened residual at the "
        "truth: mean square %.3f per sample (1 when sigma_px = %.2f is the samples' "
        "noise)\n\n",
        dir.c_str(), camera_config.name.c_str(), frames.size(), dt,
        whitened > 0 ? chi2 / whitened : NAN, sc.sigma_px);
    std::printf(
        "| horizon | frames | samples per frame | frame mean, px (mean / RMS) | "
        "spread in a frame, px | r(1) | r(2) | r(5) | r(10) | r(30) | r(60) | centred "
        "r(1) | r(10) |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    const char* names[2] = {"water", "land"};
    for (int c = 0; c < 2; ++c) {
      int n = 0;
      double s = 0, s2 = 0, spread = 0, count = 0;
      for (const FrameMeans& f : frames) {
        if (!std::isfinite(f.mean[c])) continue;
        ++n;
        s += f.mean[c];
        s2 += f.mean[c] * f.mean[c];
        spread += f.spread[c];
        count += f.count[c];
      }
      if (n == 0) {
        std::printf("| %s | 0 | | | | | | | | | | | |\n", names[c]);
        continue;
      }
      const double mean = s / n;
      std::printf("| %s | %d | %.0f | %+.3f / %.3f | %.3f |", names[c], n, count / n, mean,
                  std::sqrt(s2 / n), spread / n);
      const auto get = [c](const FrameMeans& f) { return f.mean[c]; };
      for (int lag : {1, 2, 5, 10, 30, 60})
        std::printf(" %.2f |", Correlation(frames, get, lag, 0));
      std::printf(" %.2f | %.2f |\n", Correlation(frames, get, 1, mean),
                  Correlation(frames, get, 10, mean));
    }
    std::printf(
        "\nThe pull J^T r on the pose (whitened), correlation over frames j apart:\n\n"
        "| horizon | axis | r(1) | r(2) | r(5) | r(10) | r(30) | r(60) |\n"
        "|---|---|---|---|---|---|---|---|\n");
    const char* axes[3] = {"yaw", "east", "north"};
    for (int c = 0; c < 2; ++c) {
      for (int a = 0; a < 3; ++a) {
        const auto get = [c, a](const FrameMeans& f) { return f.pull[c][a]; };
        std::printf("| %s | %s |", names[c], axes[a]);
        for (int lag : {1, 2, 5, 10, 30, 60}) {
          std::printf(" %.2f |", Correlation(frames, get, lag, 0));
        }
        std::printf("\n");
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
  return 0;
}
