/// \file
/// LiDAR-to-aerial alignment on real data: the Autzen airborne LiDAR cloud against the
/// orthophoto of the same place (../shared/data/autzen, co-registered in their CRS, so the
/// registration is known). The cloud, centred on its own middle, is a "scan" whose true planar
/// pose is (its centre, yaw 0); it is registered from perturbed starts and the error of the
/// result measured:
///   - starts 10 m and 5 degrees off (random direction and sign): error median / max, and the
///     share within 0.5 m and 0.5 degrees;
///   - starts uniform up to 30 m and 20 degrees off: the share that converges (same bounds);
///   - the fine step alone from the true registration: where it settles (the map's own bias);
///   - time: map build, scan preparation, and per registration the coarse search and the fine
///     step, medians.
/// --figure PATH writes the map with its edges (red) and the scan's structure points at the
/// true registration (green) as a PNG.

#include <chrono>
#include <cmath>
#include <cstdio>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>
#include <vector>

#include "bench_util.h"
#include "skerry/core/geodesy.h"
#include "skerry/geo/point_cloud.h"
#include "skerry/lidar_aerial/baseline_pso_matcher.h"
#include "skerry/lidar_aerial/scan_preparation.h"
#include "skerry/lidar_aerial/scan_registration.h"

namespace skerry::bench {
namespace {

using lidar_aerial::PlanarPose;

double Seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

struct Trial {
  bool valid = false;
  double to_ref_m = 0.0, to_ref_deg = 0.0;  // from the alignment started at the CRS registration
  double to_crs_m = 0.0, to_crs_deg = 0.0;  // from the CRS registration
  double total_s = 0.0;
};

int Main(const Flags& flags) {
  if (flags.Int("cpu", -1) >= 0) PinToCpu(static_cast<int>(flags.Int("cpu", -1)));
  const std::string dir = flags.String("data") + "/autzen";
  const int trials = static_cast<int>(flags.Int("trials", 1));
  std::mt19937 rng(static_cast<unsigned>(flags.Int("seed", 0)));

  // ENU origin at the image centre (a first load finds it).
  const geo::Orthophoto rough(dir + "/autzen.jpg", LocalFrame({44.05, -123.07, 100.0}));
  const Eigen::Vector3d centre = rough.frame().ToGeodetic(
      rough.PixelToEnu(0.5 * (rough.width() - 1), 0.5 * (rough.height() - 1), 100.0));
  const LocalFrame frame({centre.x(), centre.y(), 100.0});
  const geo::Orthophoto ortho(dir + "/autzen.jpg", frame);
  const geo::PointCloud cloud =
      geo::PointCloudToEnu(geo::LoadPointCloud(dir + "/autzen_trim.las"), frame,
                           geo::CloudToEnuOptions(geo::VerticalDatum::kEgm96));

  // The scan: the cloud around its middle (levelled: ENU axes).
  Eigen::AlignedBox2d box;
  for (const Eigen::Vector3d& p : cloud.points) box.extend(p.head<2>().eval());
  const Eigen::Vector2d c = box.center();
  std::vector<Eigen::Vector3d> scan(cloud.points.size());
  for (size_t i = 0; i < scan.size(); ++i) {
    scan[i] = cloud.points[i] - Eigen::Vector3d(c.x(), c.y(), 0.0);
  }
  lidar_aerial::ScanPreparationOptions prep;
  prep.cell_m = flags.Double("cell", 0.01);
  prep.min_vertical_extent_m = flags.Double("min-extent", 0.0);
  prep.max_points = static_cast<int>(flags.Int("max-points", 0));
  prep.intensity_blur_m = flags.Double("scan-blur", 0.0);
  prep.canny_high_quantile = flags.Double("scan-high", 0.0);
  prep.canny_low_quantile = flags.Double("scan-low", 0.0);
  auto t0 = std::chrono::steady_clock::now();
  const lidar_aerial::PreparedScan prepared =
      lidar_aerial::PrepareScan(scan, cloud.intensity, Eigen::Quaterniond::Identity(), prep);
  const double prep_s = Seconds(t0);

  lidar_aerial::AerialMapOptions mo;
  mo.resolution_m = flags.Double("resolution", 0.01);
  mo.max_distance_m = flags.Double("max-distance", 0.01);
  mo.blur_m = flags.Double("map-blur", 0.0);
  mo.canny_high_quantile = flags.Double("map-high", 0.0);
  mo.canny_low_quantile = flags.Double("map-low", 0.0);
  const double margin = flags.Double("margin", 0.0);
  Eigen::AlignedBox2d map_box(box.min() - Eigen::Vector2d::Constant(margin),
                              box.max() + Eigen::Vector2d::Constant(margin));
  t0 = std::chrono::steady_clock::now();
  const lidar_aerial::AerialMap map(ortho, map_box, mo);
  auto field = std::make_shared<lidar_aerial::EdgeDistanceField>(map);
  const double map_s = Seconds(t0);

  std::printf(
      "aerial_alignment: %s, %zu points, %.0f x %.0f m; %d columns, %d walls, %d rims, %d "
      "intensity edges, %d too high, %zu kept "
      "(%.1f ms); map %d x %d at %.2f m (%.0f ms, lattice error %.1e px); load %s\n",
      cloud.path.c_str(), cloud.points.size(), box.sizes().x(), box.sizes().y(), prepared.columns,
      prepared.wall_columns, prepared.rim_columns, prepared.intensity_columns,
      prepared.dropped_high, prepared.points_s.size(), 1e3 * prep_s, map.cols(), map.rows(),
      map.resolution_m(), 1e3 * map_s, map.lattice_error_px(), LoadAverage().c_str());

  lidar_aerial::RegistrationOptions ro;
  ro.coarse.search_radius_m = flags.Double("search-radius", 0.0);
  ro.coarse.heading_range_deg = flags.Double("heading-range", 0.0);
  ro.coarse.resolution_m = flags.Double("coarse-resolution", 0.01);
  ro.fine.loss = lidar_aerial::ParseDistanceLoss(flags.String("loss"));
  ro.fine.loss_sigmas = flags.Double("loss-sigmas", 0.0);
  // Two references: the CRS registration ("truth": the cloud where the files put it), and the
  // alignment started there (coarse search and fine step: where the data agree best). Recovery
  // is measured against the latter: the same answer from a worse start.
  const PlanarPose truth{c, 0.0};
  const lidar_aerial::Registration ref =
      lidar_aerial::RegisterScan(map, field, prepared.points_s, truth, ro);
  if (!ref.valid) throw std::runtime_error("the alignment from the CRS registration failed");
  const auto describe = [&](const char* what, const lidar_aerial::Registration& r) {
    std::printf(
        "%s: %.2f m (E %+.2f, N %+.2f) and %+.2f deg from the CRS registration; sd x %.2f "
        "m y %.2f m yaw %.2f deg; constraint ratio %.2f; rms distance %.2f m, %.0f %% of "
        "points within the loss scale\n",
        what, (r.pose.t - c).norm(), r.pose.t.x() - c.x(), r.pose.t.y() - c.y(),
        r.pose.yaw * 180 / M_PI, std::sqrt(r.covariance(0, 0)), std::sqrt(r.covariance(1, 1)),
        std::sqrt(r.covariance(2, 2)) * 180 / M_PI, r.constraint_ratio, r.rms_distance_m,
        100 * r.inlier_share);
  };
  describe("alignment started at the CRS registration", ref);
  std::printf(
      "  its coarse search: %.2f m, %+.2f deg from the CRS registration; score %.3f, "
      "ambiguity %.2f; sd x %.2f m y %.2f m yaw %.2f deg\n",
      (ref.coarse.pose.t - c).norm(), ref.coarse.pose.yaw * 180 / M_PI, ref.coarse.score,
      ref.coarse.ambiguity, std::sqrt(ref.coarse.covariance(0, 0)),
      std::sqrt(ref.coarse.covariance(1, 1)), std::sqrt(ref.coarse.covariance(2, 2)) * 180 / M_PI);
  lidar_aerial::RegistrationOptions fine_only = ro;
  fine_only.coarse_first = false;
  describe("fine step alone from the CRS registration",
           lidar_aerial::RegisterScan(map, field, prepared.points_s, truth, fine_only));
  if (!flags.String("figure").empty()) {
    cv::Mat img;
    cv::cvtColor(map.grey(), img, cv::COLOR_GRAY2BGR);
    img.setTo(cv::Scalar(0, 0, 255), map.edges());
    for (const auto& [pose, colour] :
         {std::pair(truth, cv::Scalar(0, 255, 0)), std::pair(ref.pose, cv::Scalar(255, 0, 0))}) {
      for (const Eigen::Vector3d& p : prepared.points_s) {
        const Eigen::Vector2d g = map.ToGrid(pose.Apply(p.head<2>()));
        cv::circle(img, cv::Point(static_cast<int>(g.x()), static_cast<int>(g.y())), 1, colour,
                   cv::FILLED);
      }
    }
    const std::string crop = flags.String("figure-crop");
    if (!crop.empty()) {
      cv::Rect rect;
      if (std::sscanf(crop.c_str(), "%d,%d,%d,%d", &rect.x, &rect.y, &rect.width, &rect.height) !=
          4) {
        throw UsageError("--figure-crop: x,y,width,height in map cells");
      }
      img = img(rect & cv::Rect(0, 0, img.cols, img.rows)).clone();
    }
    cv::imwrite(flags.String("figure"), img);
  }

  const auto run = [&](const PlanarPose& start, bool coarse) {
    Trial t;
    lidar_aerial::RegistrationOptions o = ro;
    o.coarse_first = coarse;
    const auto ts = std::chrono::steady_clock::now();
    const lidar_aerial::Registration r =
        lidar_aerial::RegisterScan(map, field, prepared.points_s, start, o);
    t.total_s = Seconds(ts);
    t.valid = r.valid;
    if (r.valid) {
      t.to_ref_m = (r.pose.t - ref.pose.t).norm();
      t.to_ref_deg = std::abs(lidar_aerial::WrapAngle(r.pose.yaw - ref.pose.yaw)) * 180 / M_PI;
      t.to_crs_m = (r.pose.t - truth.t).norm();
      t.to_crs_deg = std::abs(lidar_aerial::WrapAngle(r.pose.yaw)) * 180 / M_PI;
    }
    return t;
  };
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::printf("\n%-40s %16s %21s %21s %8s\n", "starts", "within 0.5 m/0.5°",
              "to alignment: med/max", "to CRS: med/max", "time");
  std::printf("%-40s %16s %21s %21s %8s\n", "", "of the alignment", "(m, deg)", "(m, deg)", "(ms)");
  const auto report = [&](const std::string& what, const std::vector<Trial>& ts) {
    std::vector<double> rm, rd, cm, cd, tt;
    int ok = 0;
    for (const Trial& t : ts) {
      rm.push_back(t.valid ? t.to_ref_m : HUGE_VAL);
      rd.push_back(t.valid ? t.to_ref_deg : HUGE_VAL);
      cm.push_back(t.valid ? t.to_crs_m : HUGE_VAL);
      cd.push_back(t.valid ? t.to_crs_deg : HUGE_VAL);
      tt.push_back(t.total_s);
      ok += t.valid && t.to_ref_m <= 0.5 && t.to_ref_deg <= 0.5;
    }
    std::printf("%-40s %9d of %3zu  %5.2f %4.2f/%5.1f %4.1f  %5.2f %4.2f/%5.1f %4.1f %8.0f\n",
                what.c_str(), ok, ts.size(), Median(rm), Median(rd), Max(rm), Max(rd), Median(cm),
                Median(cd), Max(cm), Max(cd), 1e3 * Median(tt));
  };
  // Starts around the CRS registration; the same seeds whatever the options.
  for (const bool coarse : {true, false}) {
    std::vector<Trial> near;
    for (int k = 0; k < trials; ++k) {
      const double a = 2 * M_PI * unit(rng);
      const double s = unit(rng) < 0.5 ? -1.0 : 1.0;
      near.push_back(
          run({c + 10.0 * Eigen::Vector2d(std::cos(a), std::sin(a)), s * 5 * M_PI / 180}, coarse));
    }
    report(coarse ? "10 m, 5° off: coarse search + fine" : "10 m, 5° off: fine step alone", near);
  }
  for (const auto& [radius, yaw] : {std::pair(15.0, 10.0), std::pair(30.0, 20.0)}) {
    std::vector<Trial> far;
    for (int k = 0; k < trials; ++k) {
      const double a = 2 * M_PI * unit(rng);
      const double r = radius * std::sqrt(unit(rng));
      const double y = (2 * unit(rng) - 1) * yaw * M_PI / 180;
      far.push_back(run({c + r * Eigen::Vector2d(std::cos(a), std::sin(a)), y}, true));
    }
    char what[64];
    std::snprintf(what, sizeof what, "up to %.0f m, %.0f° off: coarse + fine", radius, yaw);
    report(what, far);
  }

  // Prior work's matcher beside skerry on the same starts (fewer: 70 tile correlations each).
  const int baseline_trials = static_cast<int>(flags.Int("baseline-trials", 0));
  if (baseline_trials > 0) {
    lidar_aerial::AerialMapOptions mo16 = mo;
    mo16.resolution_m = 0.16;  // prior work's tile pixel
    const lidar_aerial::AerialMap map16(ortho, map_box, mo16);
    std::printf(
        "\nprior work's matcher (stacked cells, RANSAC lines, unpadded FFT correlation on a "
        "150 m tile, 10-particle swarm over +-5 deg, 2 m gate) beside skerry, same starts; "
        "errors to the alignment from the CRS registration (and to the CRS registration)\n");
    std::printf("%-22s %-30s %10s %22s %22s %9s\n", "starts", "method", "within", "error med/max",
                "to CRS, med", "time");
    std::printf("%-22s %-30s %10s %22s %22s %9s\n", "", "", "0.5m/0.5°", "(m, deg)", "(m)", "(ms)");
    std::mt19937 brng(static_cast<unsigned>(flags.Int("seed", 0)) + 17);
    for (const auto& [radius, yaw_deg] : {std::pair(1.0, 2.0), std::pair(10.0, 5.0)}) {
      std::vector<PlanarPose> starts;
      for (int k = 0; k < baseline_trials; ++k) {
        const double a = 2 * M_PI * unit(brng);
        starts.push_back({c + radius * Eigen::Vector2d(std::cos(a), std::sin(a)),
                          (unit(brng) < 0.5 ? -1.0 : 1.0) * yaw_deg * M_PI / 180});
      }
      struct Column {
        std::string name;
        std::vector<PlanarPose> poses;
        std::vector<double> times;
      };
      std::vector<Column> columns = {{"prior work (its output)", {}, {}},
                                     {"prior work, gate ignored", {}, {}},
                                     {"skerry (coarse + fine)", {}, {}}};
      int gated = 0;
      for (const PlanarPose& start : starts) {
        auto t0 = std::chrono::steady_clock::now();
        const lidar_aerial::baseline::BaselineMatch m =
            lidar_aerial::baseline::MatchBaseline(map16, scan, start);
        const double tb = Seconds(t0);
        gated += m.gated;
        columns[0].poses.push_back(m.pose);
        columns[0].times.push_back(tb);
        columns[1].poses.push_back(m.matched);
        columns[1].times.push_back(tb);
        t0 = std::chrono::steady_clock::now();
        const lidar_aerial::Registration r =
            lidar_aerial::RegisterScan(map, field, prepared.points_s, start, ro);
        columns[2].poses.push_back(r.valid ? r.pose : start);
        columns[2].times.push_back(Seconds(t0));
      }
      char what[64];
      std::snprintf(what, sizeof what, "%.0f m, %.0f° off", radius, yaw_deg);
      for (const Column& col : columns) {
        std::vector<double> em, ed, cm;
        int ok = 0;
        for (const PlanarPose& p : col.poses) {
          em.push_back((p.t - ref.pose.t).norm());
          ed.push_back(std::abs(lidar_aerial::WrapAngle(p.yaw - ref.pose.yaw)) * 180 / M_PI);
          cm.push_back((p.t - truth.t).norm());
          ok += em.back() <= 0.5 && ed.back() <= 0.5;
        }
        std::printf("%-22s %-30s %4d of %3zu  %5.2f %4.2f/%5.1f %4.1f  %10.2f %9.0f\n", what,
                    col.name.c_str(), ok, col.poses.size(), Median(em), Median(ed), Max(em),
                    Max(ed), Median(cm), 1e3 * Median(col.times));
      }
      std::printf("%-22s %d of %d baseline matches refused by its 2 m gate\n", "", gated,
                  baseline_trials);
    }
  }

  // Per scan, as the window would use it: a scan-sized crop of the cloud (its points within
  // --scan-radius of a place), prepared, searched around a prior 3 m and 2 degrees off (+- 10 m,
  // +- 5 degrees) and refined; each stage timed, medians over the places (the same crop several
  // times, --scan-runs). Places every 20 m along the cloud where a crop holds 2000 returns.
  const double scan_radius = flags.Double("scan-radius", 1.0);
  const int scan_runs = static_cast<int>(flags.Int("scan-runs", 1));
  lidar_aerial::RegistrationOptions per_scan = ro;
  per_scan.coarse.search_radius_m = 10.0;
  per_scan.coarse.heading_range_deg = 5.0;
  lidar_aerial::RegistrationOptions refine = per_scan;
  refine.coarse_first = false;
  std::vector<double> t_prep, t_coarse, t_fine, t_total, crop_to_ref, crop_points;
  int places = 0, agree = 0, unflagged = 0, unflagged_agree = 0;
  std::vector<double> crop_yaw_err;
  for (double x = box.min().x() + scan_radius; x <= box.max().x() - 0.5 * scan_radius; x += 20.0) {
    for (double y = box.min().y() + 0.5 * scan_radius; y <= box.max().y(); y += 20.0) {
      const Eigen::Vector2d centre(x, y);
      std::vector<Eigen::Vector3d> crop;
      std::vector<float> crop_i;
      for (size_t i = 0; i < cloud.points.size(); ++i) {
        const Eigen::Vector2d d = cloud.points[i].head<2>() - centre;
        if (d.norm() > scan_radius) continue;
        crop.emplace_back(d.x(), d.y(), cloud.points[i].z());
        crop_i.push_back(cloud.intensity[i]);
      }
      if (crop.size() < 2000) continue;
      ++places;
      // The crop's true pose under the whole cloud's alignment: the scan frame at `centre`.
      const PlanarPose crop_ref{ref.pose.Apply(centre - c), ref.pose.yaw};
      const PlanarPose start{
          centre + Eigen::Vector2d(3.0 * std::cos(places), 3.0 * std::sin(places)),
          (places % 2 ? 2.0 : -2.0) * M_PI / 180};
      for (int run = 0; run < scan_runs; ++run) {
        auto t0 = std::chrono::steady_clock::now();
        const lidar_aerial::PreparedScan ps =
            lidar_aerial::PrepareScan(crop, crop_i, Eigen::Quaterniond::Identity(), prep);
        t_prep.push_back(Seconds(t0));
        t0 = std::chrono::steady_clock::now();
        const lidar_aerial::CoarseMatch cm =
            lidar_aerial::CoarseSearch(map, ps.points_s, start, per_scan.coarse);
        t_coarse.push_back(Seconds(t0));
        t0 = std::chrono::steady_clock::now();
        const lidar_aerial::Registration r =
            lidar_aerial::RegisterScan(map, field, ps.points_s, cm.valid ? cm.pose : start, refine);
        t_fine.push_back(Seconds(t0));
        t_total.push_back(t_prep.back() + t_coarse.back() + t_fine.back());
        if (run > 0) continue;
        crop_points.push_back(static_cast<double>(ps.points_s.size()));
        const double d = r.valid ? (r.pose.t - crop_ref.t).norm() : HUGE_VAL;
        crop_to_ref.push_back(d);
        const double yaw_err =
            r.valid ? std::abs(lidar_aerial::WrapAngle(r.pose.yaw - crop_ref.yaw)) * 180 / M_PI
                    : HUGE_VAL;
        crop_yaw_err.push_back(yaw_err);
        const bool ok = d <= 1.0 && yaw_err <= 1.0;
        agree += ok;
        if (cm.valid && !cm.ambiguous) {
          ++unflagged;
          unflagged_agree += ok;
        }
      }
    }
  }
  if (places > 0) {
    std::printf(
        "\nper scan (crops of %.0f m radius at %d places, %d run(s) each, on %s): "
        "edge points median %.0f; time median prepare %.1f ms, coarse search (+-10 m, "
        "+-5 deg) %.1f ms, fine %.1f ms, total %.1f ms (p90 %.1f ms)\n  against the whole "
        "cloud's alignment: %d of %d crops within 1 m / 1 deg (error median %.2f m, %.2f "
        "deg); of the %d the coarse search did not flag ambiguous, %d\n",
        scan_radius, places, scan_runs, flags.Int("cpu", -1) >= 0 ? "one pinned core" : "any core",
        Median(crop_points), 1e3 * Median(t_prep), 1e3 * Median(t_coarse), 1e3 * Median(t_fine),
        1e3 * Median(t_total), 1e3 * Percentile(t_total, 90.0), agree, places, Median(crop_to_ref),
        Median(crop_yaw_err), unflagged, unflagged_agree);
  }
  return 0;
}

}  // namespace
}  // namespace skerry::bench

int main(int argc, char** argv) {
  skerry::bench::Flags flags;
  flags.Declare("data", SKERRY_SHARED_DATA_DIR, "the shared data folder");
  flags.Declare("trials", "50", "starts per protocol");
  flags.Declare("seed", "1", "random starts' seed");
  flags.Declare("cell", "0.5", "structure column size (m)");
  flags.Declare("min-extent", "1.5", "a column's vertical extent that makes it structure (m)");
  flags.Declare("max-points", "3000", "structure points kept");
  flags.Declare("resolution", "0.25", "map cell (m)");
  flags.Declare("margin", "60", "map beyond the cloud (m)");
  flags.Declare("max-distance", "5", "distance field clip (m)");
  flags.Declare("map-blur", "0.5", "the image's blur before its edges (m)");
  flags.Declare("map-high", "0.9", "the image's Canny high threshold (quantile)");
  flags.Declare("map-low", "0.75", "the image's Canny low threshold (quantile)");
  flags.Declare("scan-blur", "1.0", "the scan intensity's blur before its edges (m)");
  flags.Declare("scan-high", "0.9", "the scan intensity's Canny high threshold (quantile)");
  flags.Declare("scan-low", "0.75", "the scan intensity's Canny low threshold (quantile)");
  flags.Declare("loss", "huber", "the fine step's robust loss (huber, geman_mcclure)");
  flags.Declare("loss-sigmas", "2", "its scale (sigmas of 0.5 m; 0: least squares)");
  flags.Declare("search-radius", "35", "coarse search half-width (m)");
  flags.Declare("heading-range", "25", "coarse heading sweep +- (deg)");
  flags.Declare("coarse-resolution", "1.0", "coarse search cell (m)");
  flags.Declare("baseline-trials", "20", "starts per protocol for prior work's matcher (0: none)");
  flags.Declare("scan-radius", "50", "per-scan timing: crop radius (m)");
  flags.Declare("scan-runs", "5", "per-scan timing: runs per crop");
  flags.Declare("cpu", "-1", "pin the process to this CPU (-1: no pinning)");
  flags.Declare("figure", "",
                "write the map, its edges (red) and the scan's points at the true registration "
                "(green) and where the fine step settles from it (blue) here (PNG)");
  flags.Declare("figure-crop", "", "x,y,width,height: only this part of the map (cells)");
  return skerry::bench::RunMain(flags, argc, argv,
                                "LiDAR-to-aerial alignment on the Autzen cloud and orthophoto",
                                [&] { return skerry::bench::Main(flags); });
}
