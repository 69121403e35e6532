// Prints skerry's figures on the real EuRoC V1_01_easy recording: IMU preintegration over 1 s
// against the ground truth, and the attitude recovered by fusing the real IMU with position fixes
// made from the ground truth. See README.md.
//
// Usage: euroc_report [EUROC_DIR] [PRESET]
//   EUROC_DIR  folder with imu0_data.csv, imu0_sensor.yaml, V1_01_easy.csv
//              (default: the shared data folder the build was configured with)
//   PRESET     estimator preset name or YAML file (default: "default")

#include <cstdio>
#include <exception>
#include <string>

#include "euroc_figures.h"
#include "skerry/io/importers.h"

#ifndef SKERRY_SHARED_DATA_DIR
#define SKERRY_SHARED_DATA_DIR "../shared/data"
#endif

namespace {

using skerry::euroc::FusionFigures;
using skerry::euroc::FusionOptions;
using skerry::euroc::Quantile;

void PrintFusionRow(const char* label, const FusionFigures& f) {
  std::printf(
      "| %-34s | %7.3f | %7.3f | %7.3f | %7.3f | %7.3f | %6.1f | %7.3f | %6.2f | %4d/%-4d | %6.2f "
      "|\n",
      label, f.rms_rot_deg, f.rms_tilt_deg, f.rms_yaw_deg, f.max_rot_deg, f.rms_pos_m, f.anees_pose,
      f.rms_yaw_sigma_deg, f.anees_yaw, f.gnss.accepted, f.fixes, f.wall_s);
}

void PrintBatchRow(const char* label, const FusionFigures& f) {
  std::printf("| %-34s | %7.3f | %7.3f | %7.3f | %s |\n", label, f.batch_rms_tilt_deg,
              f.batch_rms_yaw_deg, f.batch_rms_yaw_sigma_deg, f.batch_usable ? "yes   " : "no    ");
}

}  // namespace

int main(int argc, char** argv) {
  const std::string dir = argc > 1 ? argv[1] : std::string(SKERRY_SHARED_DATA_DIR) + "/euroc_v1_01";
  const std::string preset = argc > 2 ? argv[2] : "default";
  try {
    const skerry::Dataset data = skerry::ImportEuroc(dir);
    std::printf("EuRoC V1_01_easy: %zu IMU samples (%.1f s), %zu ground-truth states\n\n",
                data.imu_samples.size(),
                skerry::NsToSeconds(data.imu_samples.back().t_ns - data.imu_samples.front().t_ns),
                data.truth_states.size());

    const auto vcheck = skerry::euroc::CheckTruthVelocityFrame(data.truth_states);
    std::printf(
        "Ground-truth velocity vs central difference of positions: RMS %.4f m/s taken as world "
        "frame, %.4f m/s taken as body frame -> %s frame\n\n",
        vcheck.rms_world_m_s, vcheck.rms_body_m_s,
        vcheck.rms_world_m_s < vcheck.rms_body_m_s ? "world" : "body");

    const skerry::euroc::PreintegrationFigures pre = skerry::euroc::MeasurePreintegration(data);
    std::printf("1) Preintegration over 1 s, truth biases, %zu intervals (one per truth sample)\n",
                pre.rot_err_deg.size());
    std::printf("| error                | median  | 90th pct | max     |\n");
    std::printf("|----------------------|---------|----------|---------|\n");
    auto row = [](const char* name, const std::vector<double>& v) {
      std::printf("| %-20s | %7.4f | %8.4f | %7.4f |\n", name, Quantile(v, 0.5), Quantile(v, 0.9),
                  Quantile(v, 1.0));
    };
    row("rotation (deg)", pre.rot_err_deg);
    row("velocity (m/s)", pre.vel_err_m_s);
    row("position (m)", pre.pos_err_m);
    std::printf("mean signed velocity error (world E,N,U): %.4f %.4f %.4f m/s\n\n",
                pre.mean_vel_err_w.x(), pre.mean_vel_err_w.y(), pre.mean_vel_err_w.z());

    const skerry::EstimatorConfig config = skerry::LoadPreset(preset);
    std::printf(
        "2) Fusion: real IMU + truth position fixes (2 Hz, 0.5 m white noise), preset \"%s\", "
        "init.mode=given,\n   start attitude off by (E, N, U) = (2, -2, 5) deg, rotation prior "
        "sigma 10 deg; scored after 10 s\n",
        config.name.c_str());
    std::printf(
        "| window                             | rot RMS | tilt    | yaw     | rot max | pos RMS | "
        "ANEES6 | yaw sig | ANEES1 | fixes     | wall s |\n");
    std::printf(
        "|------------------------------------|---------|---------|---------|---------|---------|"
        "--------|---------|--------|-----------|--------|\n");
    FusionOptions truth_biases;
    const FusionFigures with_truth = skerry::euroc::MeasureFusion(data, config, truth_biases);
    PrintFusionRow("truth biases, dataset prior sigmas", with_truth);
    FusionOptions zero_biases;
    zero_biases.truth_biases = false;
    const FusionFigures with_zero = skerry::euroc::MeasureFusion(data, config, zero_biases);
    PrintFusionRow("zero biases, loose sigmas", with_zero);
    FusionOptions align;
    align.align_static_s = 4.0;
    const FusionFigures with_align = skerry::euroc::MeasureFusion(data, config, align);
    PrintFusionRow("align: 4 s at rest, yaw/bg unknown", with_align);
    std::printf(
        "(deg except pos RMS in m; tilt = east/north part of the world rotation error, "
        "yaw = up part, yaw sig = RMS of the estimator's yaw 1-sigma; ANEES6 of rotation+position, "
        "6 if consistent; ANEES1 of yaw, 1 if consistent)\n\n");
    std::printf(
        "| batch smoother, same data          | tilt    | yaw     | yaw sig | usable |\n"
        "|------------------------------------|---------|---------|---------|--------|\n");
    PrintBatchRow("truth biases, dataset prior sigmas", with_truth);
    PrintBatchRow("zero biases, loose sigmas", with_zero);
    PrintBatchRow("align: 4 s at rest, yaw/bg unknown", with_align);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "euroc_report: %s\n", e.what());
    return 1;
  }
  return 0;
}
