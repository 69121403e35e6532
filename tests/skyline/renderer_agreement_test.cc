// The estimator's horizon model (frontends/skyline) against the simulator's independent
// renderer (sim/terrain_renderer.h) on the real Côte d'Azur and Lake Constance DEMs: frames
// rendered at known poses, their masks' skylines extracted, and the residual evaluated at the
// true pose. What is left is the two implementations' disagreement (march step, refinement,
// interpolation of the profile, mask quantisation): it must stay well below the frontend's
// default sigma of 1 px, and it must not be biased.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "skerry/geo/dem.h"
#include "skerry/sim/terrain_renderer.h"
#include "skerry/skyline/skyline_extraction.h"
#include "skerry/skyline/skyline_residual.h"

namespace skerry::skyline {
namespace {

struct Case {
  const char* tile;
  double lat, lon, h;
  double heading_deg;
};

TEST(RendererAgreement, PredictedHorizonMatchesTheRenderedMask) {
  for (const Case& c :
       {Case{"N43E007.hgt", 43.62, 7.25, 48.23, 20.0}, Case{"N43E007.hgt", 43.64, 7.30, 48.3, 70.0},
        Case{"N47E009.hgt", 47.60, 9.40, 438.42, 160.0}}) {
    const std::string path = std::string(SKERRY_SHARED_DATA_DIR) + "/dem/" + c.tile;
    if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " missing";
    const LocalFrame frame({c.lat, c.lon, c.h});
    const geo::Dem dem(path, frame, geo::DemOptions(geo::VerticalDatum::kEgm96));
    const Eigen::AlignedBox2d box =
        Eigen::AlignedBox2d(Eigen::Vector2d(-60000, -60000), Eigen::Vector2d(60000, 60000))
            .intersection(dem.footprint_enu());
    // The same DEM on two differently placed grids: the renderer's and the predictor's.
    const sim::TerrainRenderer renderer(dem.ResampleToEnu(box, 90.0));
    const Eigen::AlignedBox2d shifted(box.min() + Eigen::Vector2d(37.0, 61.0), box.max());
    auto horizon = std::make_shared<HorizonPredictor>(dem.ResampleToEnu(shifted, 90.0));
    CameraConfig config = PinholeFromFov("camera", 1920, 1080, 70.0);
    config.distortion = {-0.05, 0.01, 0.0, 0.0};
    const CameraModel camera(config);
    const Eigen::Quaterniond q_w_b =
        Eigen::AngleAxisd(M_PI / 2 - c.heading_deg * M_PI / 180, Eigen::Vector3d::UnitZ()) *
        Eigen::AngleAxisd(2.0 * M_PI / 180, Eigen::Vector3d::UnitX());
    const Eigen::Quaterniond q_w_c = q_w_b * LevelCameraRotation(0.0);
    const Eigen::Vector3d p_w_c(150.0, -80.0, 4.0);
    const sim::RenderedFrame f = renderer.Render(config, q_w_c, p_w_c, false, 1);
    const Skyline sky = ExtractSkylineFromMask(f.mask);
    const auto samples = SkylineSamples(sky, 4, 0.5);
    ASSERT_GT(samples.size(), 300u);
    const SkylineResidualModel model(horizon, camera, samples, SkylineResidualOptions{});
    std::vector<double> e = model.PixelErrors(q_w_c.toRotationMatrix(), p_w_c);
    e.erase(std::remove_if(e.begin(), e.end(), [](double x) { return std::isnan(x); }), e.end());
    ASSERT_GT(e.size(), 100u);
    double mean = 0.0;
    for (double x : e) mean += x;
    mean /= e.size();
    std::vector<double> a;
    for (double x : e) a.push_back(std::abs(x));
    std::sort(a.begin(), a.end());
    const double median = a[a.size() / 2], p95 = a[a.size() * 95 / 100];
    std::printf("%s heading %.0f: %zu samples, mean %.3f px, median |e| %.3f px, p95 %.3f px\n",
                c.tile, c.heading_deg, e.size(), mean, median, p95);
    EXPECT_LT(std::abs(mean), 0.2);
    EXPECT_LT(median, 0.4);
    EXPECT_LT(p95, 1.25);
  }
}

}  // namespace
}  // namespace skerry::skyline
