// The real Engabreen photo (../shared/data/engabreen, docs/results.md "Skyline: a real photo"):
// the camera's orientation from the 28 ground control points (checks the camera model, UTM ->
// ENU and the DEM reader on real data), the skyline extracted from the photo automatically, and
// the horizon predicted from the 3 m DEM, which covers only about 2 km around the camera: per
// column, whether the predicted maximum sits on the map's edge (truncated: never a residual),
// the photo-vs-DEM difference where the DEM's own ridges make the skyline, and the orientation
// recovered from those columns from a start 5 deg off. Figures printed; an overlay PNG written.

#include <ceres/ceres.h>
#include <gtest/gtest.h>

#include <GeographicLib/UTMUPS.hpp>
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "skerry/core/input_error.h"
#include "skerry/geo/dem.h"
#include "skerry/skyline/gcp_pose.h"
#include "skerry/skyline/skyline_extraction.h"
#include "skerry/skyline/skyline_residual.h"

namespace skerry::skyline {
namespace {

constexpr double kDeg = M_PI / 180.0;
const std::string kDir = std::string(SKERRY_SHARED_DATA_DIR) + "/engabreen/";

Eigen::Vector2d LatLon(double e, double n) {
  double lat, lon;
  GeographicLib::UTMUPS::Reverse(33, true, e, n, lat, lon);
  return {lat, lon};
}

TEST(Engabreen, GcpPoseTruncationGuardAndOrientationFromTheSkyline) {
  if (!std::filesystem::exists(kDir + "IMG_8902.jpg")) GTEST_SKIP() << kDir << " missing";
  // The camera centre (UTM 33N, orthometric height) and a local frame at it.
  const Eigen::Vector2d c_ll = LatLon(446722.0, 7396671.0);
  geo::DemOptions options(geo::VerticalDatum::kEgm96);
  options.crs = "EPSG:32633";
  const std::string dem_path = kDir + "engabreen_dem_3m_utm33n.asc";
  const double undulation = *geo::Dem(dem_path, LocalFrame({c_ll.x(), c_ll.y(), 0.0}), options)
                                 .GeoidUndulation(c_ll.x(), c_ll.y());
  const LocalFrame frame({c_ll.x(), c_ll.y(), 770.0 + undulation});
  const geo::Dem dem(dem_path, frame, options);

  // 1. The orientation from the 28 GCPs, centre fixed, focal length fitted.
  const std::vector<GcpRow> gcps = ReadGcpFile(kDir + "gcp8902.txt");
  ASSERT_EQ(gcps.size(), 28u);
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector2d> pixels;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const GcpRow& g : gcps) {
    const Eigen::Vector2d ll = LatLon(g.xyz.x(), g.xyz.y());
    points.push_back(frame.ToEnu(ll.x(), ll.y(), g.xyz.z() + *dem.GeoidUndulation(ll.x(), ll.y())));
    pixels.push_back(g.pixel - Eigen::Vector2d(1, 1));  // ImGRAFT's pixels are 1-based
    mean += points.back().normalized();
  }
  CameraConfig config = PinholeFromFov("canon", 4290, 2856, 2 * std::atan(11.0 / 30.0) / kDeg);
  const CameraModel nominal(config);
  // Start: level, looking along the mean direction of the points.
  const Eigen::Vector3d z = Eigen::Vector3d(mean.x(), mean.y(), 0).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  Eigen::Matrix3d r0;
  r0 << x, z.cross(x) * -1.0, z;
  r0.col(1) = r0.col(2).cross(r0.col(0));
  // Focal length and one radial term fitted: a pinhole alone leaves 8.2 px (the lens's barrel).
  const CameraRotationFit fit = FitCameraRotation(nominal, Eigen::Vector3d::Zero(), points, pixels,
                                                  Eigen::Quaterniond(r0), true, true);
  std::printf(
      "GCP pose: reprojection RMS %.2f px over %zu points, focal %.0f px (nominal %.0f), "
      "k1 %.3f\n",
      fit.rms_px, points.size(), fit.focal_px, nominal.fx(), fit.k1);
  EXPECT_LT(fit.rms_px, 4.0);
  EXPECT_NEAR(fit.focal_px, nominal.fx(), 0.05 * nominal.fx());
  config.fx = config.fy = fit.focal_px;
  config.distortion = {fit.k1, 0.0, 0.0, 0.0};
  const CameraModel camera(config);

  // 2. The photo's skyline, extracted automatically.
  const cv::Mat photo = cv::imread(kDir + "IMG_8902.jpg", cv::IMREAD_COLOR);
  const Skyline sky = ExtractSkylineFromImage(photo);
  const std::vector<SkylineSample> samples = SkylineSamples(sky, 8, 0.25);
  // 3. The DEM's horizon per sample column: usable, truncated at the map's edge, or none.
  HorizonOptions ho;
  ho.max_range_m = 20000.0;
  auto horizon =
      std::make_shared<HorizonPredictor>(dem.ResampleToEnu(dem.footprint_enu(), 3.0), ho);
  const Eigen::Matrix3d r_w_c = fit.q_w_c.toRotationMatrix();
  std::vector<SkylineSample> usable;
  int truncated = 0, none = 0;
  std::vector<double> truncated_gap_px;
  cv::Mat overlay = photo.clone();
  for (const SkylineSample& s : samples) {
    const Eigen::Vector3d r = r_w_c * *camera.Ray(s.pixel);
    const double az = std::atan2(r.x(), r.y());
    const HorizonSample h = horizon->Trace(Eigen::Vector3d::Zero(), az);
    cv::circle(overlay, cv::Point(s.pixel.x(), s.pixel.y()), 6, cv::Scalar(0, 0, 255), -1);
    if (!h.valid) {
      ++none;
      continue;
    }
    // Where the DEM's horizon would put this column's skyline.
    const Eigen::Vector3d d_w(std::sin(az) * std::cos(h.elevation_rad),
                              std::cos(az) * std::cos(h.elevation_rad), std::sin(h.elevation_rad));
    const auto px = camera.Project(r_w_c.transpose() * d_w);
    if (h.truncated) {
      ++truncated;
      if (px) truncated_gap_px.push_back(px->y() - s.pixel.y());
      if (px) cv::circle(overlay, cv::Point(px->x(), px->y()), 6, cv::Scalar(0, 220, 255), -1);
      continue;
    }
    usable.push_back(s);
    if (px) cv::circle(overlay, cv::Point(px->x(), px->y()), 6, cv::Scalar(0, 200, 0), -1);
  }
  std::sort(truncated_gap_px.begin(), truncated_gap_px.end());
  std::printf(
      "skyline: %d of %d columns extracted; of %zu samples (every 8th column) %zu usable, "
      "%d truncated at the DEM's edge (the map's horizon %.0f px below the photo's, "
      "median), %d without terrain in the map\n",
      sky.valid_columns(), sky.width, samples.size(), usable.size(), truncated,
      truncated_gap_px.empty() ? 0.0 : truncated_gap_px[truncated_gap_px.size() / 2], none);
  std::filesystem::create_directories(SKERRY_TEST_TMP_DIR);
  cv::imwrite(std::string(SKERRY_TEST_TMP_DIR) + "/engabreen_horizon.png", overlay);
  // The guard: the map ends short of the photo's skyline along most azimuths, and those
  // columns are recognised (their map horizon lies far below the photo's skyline).
  EXPECT_GT(truncated, 0);
  if (!truncated_gap_px.empty()) {
    EXPECT_GT(truncated_gap_px[truncated_gap_px.size() / 2], 20.0);
  }

  // 4. Where the DEM's own ridges make the skyline: the photo against the DEM, and the
  //    orientation recovered from those columns alone from a start 5 deg off.
  constexpr size_t kMinColumns = 20;
  if (usable.size() < kMinColumns) {
    std::printf(
        "only %zu usable columns (< %zu): no orientation from the skyline; the truncation "
        "guard kept the other %d out\n",
        usable.size(), kMinColumns, truncated);
    return;
  }
  SkylineResidualOptions ro;
  ro.sigma_px = 2.0;
  auto model = std::make_shared<SkylineResidualModel>(horizon, camera, usable, ro);
  std::vector<double> e = model->PixelErrors(r_w_c, Eigen::Vector3d::Zero());
  std::vector<double> a;
  for (double v : e) {
    if (!std::isnan(v)) a.push_back(std::abs(v));
  }
  std::sort(a.begin(), a.end());
  const double median_px = a.empty() ? NAN : a[a.size() / 2];
  Eigen::Quaterniond q = fit.q_w_c * Eigen::Quaterniond(Eigen::AngleAxisd(
                                         5.0 * kDeg, Eigen::Vector3d(0.3, -1.0, 0.5).normalized()));
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_b_c = Eigen::Quaterniond::Identity();
  Eigen::Vector3d p_b_c = Eigen::Vector3d::Zero();
  ceres::Problem problem;
  problem.AddResidualBlock(new SkylineCost(model), nullptr, q.coeffs().data(), p.data(),
                           q_b_c.coeffs().data(), p_b_c.data());
  problem.SetManifold(q.coeffs().data(), new ceres::EigenQuaternionManifold);
  for (double* b : {p.data(), q_b_c.coeffs().data(), p_b_c.data()}) {
    problem.SetParameterBlockConstant(b);
  }
  ceres::Solver::Options so;
  so.max_num_iterations = 100;
  ceres::Solver::Summary summary;
  ceres::Solve(so, &problem, &summary);
  const double off_deg = q.angularDistance(fit.q_w_c) / kDeg;
  std::printf(
      "DEM ridges vs photo: median |difference| %.1f px over %zu columns; orientation "
      "from the skyline, start 5 deg off: %.2f deg from the GCP solution\n",
      median_px, a.size(), off_deg);
  EXPECT_LT(off_deg, 0.5);
}

TEST(Engabreen, GcpFileErrorsNameTheLineAndField) {
  const std::string dir = std::string(SKERRY_TEST_TMP_DIR) + "/gcp";
  std::filesystem::create_directories(dir);
  const std::string bad = dir + "/bad.txt";
  {
    std::ofstream out(bad);
    out << "% comment\n445562 7395662 596.4 1951+9 1490+4\n445629 7395649 nan 1732+9 1563\n";
  }
  try {
    ReadGcpFile(bad);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(":3"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("Z"), std::string::npos) << e.what();
  }
  {
    std::ofstream out(bad);
    out << "1 2 3 4+\n";
  }
  EXPECT_THROW(ReadGcpFile(bad), InputError);
  EXPECT_THROW(ReadGcpFile(dir + "/missing.txt"), InputError);
}

}  // namespace
}  // namespace skerry::skyline
