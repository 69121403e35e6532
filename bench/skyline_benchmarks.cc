/// \file
/// The skyline frontend's cost per 1920 x 1080 frame on one core (issue budget: extraction +
/// horizon prediction + residuals <= 50 ms), and prior work's baseline on the same frame beside
/// it. The frame: a vessel off Nice looking at the Maritime Alps (SRTM N43E007), rendered by the
/// simulator. Defaults to 5 repetitions with aggregates only: every figure is a median over runs.
///   BM_ReadFrame/R/I      a frame read from its PNG file (I 0: the mask, 1: the grey image) by
///                         cv::imread alone (R 0, the reader before camera_frame.h) or by
///                         ReadCameraFrame (R 1: its header checked by GDAL first)
///   BM_ExtractMask        skyline of a segmentation mask
///   BM_ExtractImage       skyline of the shaded grey image (the photo path)
///   BM_HorizonProfile     the horizon at all 1920 columns, with its derivatives
///   BM_HorizonElevations  the same without them (what the global search's coarse profiles trace):
///                         the difference is the two maxima re-found per column for the skyline's
///                         slope
///   BM_FrameResidual      one frame's residual with Jacobians (240 samples, every 8th column)
///   BM_FrameTotal         read-to-block: mask extraction + samples + residual with Jacobians
///   BM_FramePrepared      a frame as the frontend hands it to the window with its defaults: the
///                         model, the crest's motion from the frame 10 m back, the map's error
///                         (4 m, 90 m), and the gate's residual with Jacobians at that pose
///   BM_BaselineFrame      prior work's whole single-frame method (its grid search included)
///   BM_HorizonCircle      the horizon all round at 0.5 deg, elevations only (one node of the
///                         global search's coarse stage with the heading unknown)
///   BM_SkerryFrameSearch/F  skerry's single-frame search within 105 m (3 sigma at sigma 35 m),
///                         its coarse profiles traced where its heading window reads them (F 0) or
///                         all round (F 1, FrameLocatorOptions::full_profiles: the same result)
///   BM_GlobalStart/N      the search that starts a run without GNSS (1 km, every heading) on N
///                         threads (skyline.threads), wall time
/// The map is skerry's default (HorizonForTrack: half the raster's cell) and the frame is rendered
/// from the simulator's world; `--grid_m=90` resamples both at 90 m instead (the figures up to
/// stop 69).
/// OpenCV runs its functions on one thread here (`--cv_threads=1`, the default), as "one core"
/// says: its own pool (TBB on Debian) would otherwise spread a frame's morphology and decoding
/// over every core. `--cv_threads=N` gives it N, `--cv_threads=-1` OpenCV's default.

#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>

#include "skerry/geo/dem.h"
#include "skerry/sim/terrain_renderer.h"
#include "skerry/sim/world_terrain.h"
#include "skerry/skyline/baseline_grid_search.h"
#include "skerry/skyline/camera_frame.h"
#include "skerry/skyline/crest_correlation.h"
#include "skerry/skyline/frame_locator.h"
#include "skerry/skyline/horizon_for_track.h"
#include "skerry/skyline/skyline_extraction.h"

using namespace skerry;

namespace {

// --grid_m: 0 (the default) gives the estimators skerry's default map (HorizonForTrack: half the
// raster's cell) and renders the frame from the simulator's world; G > 0 resamples the DEM at G m
// for both (90: every figure up to stop 69).
double g_grid_m = 0.0;

struct Scene {
  Scene() {
    const LocalFrame frame({43.62, 7.25, 48.23});
    const geo::Dem dem(std::string(SKERRY_SHARED_DATA_DIR) + "/dem/N43E007.hgt", frame,
                       geo::DemOptions(geo::VerticalDatum::kEgm96));
    p_w_c = Eigen::Vector3d(1500, 800, 4.0);
    geo::EnuHeightGrid world;
    if (g_grid_m > 0) {
      const Eigen::AlignedBox2d box =
          Eigen::AlignedBox2d(Eigen::Vector2d(-60000, -60000), Eigen::Vector2d(62000, 62000))
              .intersection(dem.footprint_enu());
      horizon = std::make_shared<skyline::HorizonPredictor>(dem.ResampleToEnu(box, g_grid_m));
      world = horizon->grid();
    } else {
      // The searches below look up to 1.4 km from the camera.
      const std::vector<Eigen::Vector3d> area = {p_w_c - Eigen::Vector3d(1500, 1500, 0),
                                                 p_w_c + Eigen::Vector3d(1500, 1500, 0)};
      const SkylineConfig config;
      horizon = skyline::HorizonForTrack(dem, area, config);
      world = sim::WorldTerrain(
          dem, skyline::HorizonBox(area, config.max_range_m).intersection(dem.footprint_enu()));
    }
    config = skyline::PinholeFromFov("camera", 1920, 1080, 70.0);
    config.distortion = {-0.05, 0.01, 0.0, 0.0};
    camera = std::make_unique<skyline::CameraModel>(config);
    r_level = (Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitZ()) *
               Eigen::AngleAxisd(1.5 * M_PI / 180, Eigen::Vector3d::UnitX()))
                  .toRotationMatrix() *
              skyline::LevelCameraRotation(0.0).toRotationMatrix();
    r_w_c =
        Eigen::AngleAxisd(-20 * M_PI / 180, Eigen::Vector3d::UnitZ()).toRotationMatrix() * r_level;
    const sim::TerrainRenderer renderer(world);
    const sim::RenderedFrame f = renderer.Render(config, Eigen::Quaterniond(r_w_c), p_w_c, true, 1);
    mask = f.mask;
    grey = f.grey;
  }
  std::shared_ptr<const skyline::HorizonPredictor> horizon;  ///< the map
  CameraConfig config;
  std::unique_ptr<skyline::CameraModel> camera;
  Eigen::Matrix3d r_level, r_w_c;
  Eigen::Vector3d p_w_c;
  cv::Mat mask, grey;
};

const Scene& TheScene() {
  static const Scene scene;
  return scene;
}

void BM_ReadFrame(benchmark::State& state) {
  const Scene& s = TheScene();
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / "skerry_bench_read_frame";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / (state.range(1) == 0 ? "mask.png" : "grey.png")).string();
  if (!cv::imwrite(path, state.range(1) == 0 ? s.mask : s.grey)) {
    state.SkipWithError("cannot write the frame");
    return;
  }
  for (auto _ : state) {
    if (state.range(0) == 0) {
      benchmark::DoNotOptimize(cv::imread(path, cv::IMREAD_UNCHANGED));
    } else {
      benchmark::DoNotOptimize(skyline::ReadCameraFrame(path, *s.camera));
    }
  }
}
BENCHMARK(BM_ReadFrame)->ArgsProduct({{0, 1}, {0, 1}})->Unit(benchmark::kMillisecond);

void BM_ExtractMask(benchmark::State& state) {
  const Scene& s = TheScene();
  for (auto _ : state) benchmark::DoNotOptimize(skyline::ExtractSkylineFromMask(s.mask));
}
BENCHMARK(BM_ExtractMask)->Unit(benchmark::kMillisecond);

void BM_ExtractImage(benchmark::State& state) {
  const Scene& s = TheScene();
  for (auto _ : state) benchmark::DoNotOptimize(skyline::ExtractSkylineFromImage(s.grey));
}
BENCHMARK(BM_ExtractImage)->Unit(benchmark::kMillisecond);

void BM_HorizonProfile(benchmark::State& state) {
  const Scene& s = TheScene();
  const Eigen::Vector3d axis = s.r_w_c.col(2);
  const double az0 = std::atan2(axis.x(), axis.y()) - 35 * M_PI / 180;
  for (auto _ : state) {
    benchmark::DoNotOptimize(s.horizon->Profile(s.p_w_c, az0, 70 * M_PI / 180 / 1920, 1920));
  }
}
BENCHMARK(BM_HorizonProfile)->Unit(benchmark::kMillisecond);

void BM_HorizonElevations(benchmark::State& state) {
  const Scene& s = TheScene();
  const Eigen::Vector3d axis = s.r_w_c.col(2);
  const double az0 = std::atan2(axis.x(), axis.y()) - 35 * M_PI / 180;
  const double step = 70 * M_PI / 180 / 1920, k = s.horizon->options().refraction_k;
  for (auto _ : state) {
    for (int i = 0; i < 1920; ++i) {
      benchmark::DoNotOptimize(s.horizon->Trace(s.p_w_c, az0 + i * step, k, false));
    }
  }
}
BENCHMARK(BM_HorizonElevations)->Unit(benchmark::kMillisecond);

// The horizon all round at the global search's azimuth step (0.5 deg, elevations only): what
// its coarse stage traces at each node of its grid when the heading is unknown, the sea behind
// the camera included.
void BM_HorizonCircle(benchmark::State& state) {
  const Scene& s = TheScene();
  const double k = s.horizon->options().refraction_k;
  for (auto _ : state) {
    for (int i = 0; i < 720; ++i) {
      benchmark::DoNotOptimize(s.horizon->Trace(s.p_w_c, i * M_PI / 360, k, false));
    }
  }
}
BENCHMARK(BM_HorizonCircle)->Unit(benchmark::kMillisecond);

void BM_FrameResidual(benchmark::State& state) {
  const Scene& s = TheScene();
  const auto samples = skyline::SkylineSamples(skyline::ExtractSkylineFromMask(s.mask), 8, 0.5);
  const skyline::SkylineResidualModel model(s.horizon, *s.camera, samples, {});
  std::vector<double> r(model.size());
  Eigen::Matrix<double, Eigen::Dynamic, 3> jr, jp;
  // Two poses a centimetre apart, taken in turn: every evaluation traces the horizon (the model
  // keeps the traces of the last pose only).
  const Eigen::Vector3d p[2] = {s.p_w_c, s.p_w_c + Eigen::Vector3d(0.01, 0.0, 0.0)};
  int k = 0;
  for (auto _ : state) model.Evaluate(s.r_w_c, p[k ^= 1], r.data(), &jr, &jp);
  state.counters["samples"] = model.size();
}
BENCHMARK(BM_FrameResidual)->Unit(benchmark::kMillisecond);

// The same evaluation again at the pose last evaluated (a solver's linearisation after its
// candidate's cost): the traces are re-used.
void BM_FrameResidualAtTheSamePose(benchmark::State& state) {
  const Scene& s = TheScene();
  const auto samples = skyline::SkylineSamples(skyline::ExtractSkylineFromMask(s.mask), 8, 0.5);
  const skyline::SkylineResidualModel model(s.horizon, *s.camera, samples, {});
  std::vector<double> r(model.size());
  Eigen::Matrix<double, Eigen::Dynamic, 3> jr, jp;
  for (auto _ : state) model.Evaluate(s.r_w_c, s.p_w_c, r.data(), &jr, &jp);
  state.counters["samples"] = model.size();
}
BENCHMARK(BM_FrameResidualAtTheSamePose)->Unit(benchmark::kMillisecond);

void BM_FrameTotal(benchmark::State& state) {
  const Scene& s = TheScene();
  for (auto _ : state) {
    const auto samples = skyline::SkylineSamples(skyline::ExtractSkylineFromMask(s.mask), 8, 0.5);
    const skyline::SkylineResidualModel model(s.horizon, *s.camera, samples, {});
    std::vector<double> r(model.size());
    Eigen::Matrix<double, Eigen::Dynamic, 3> jr, jp;
    model.Evaluate(s.r_w_c, s.p_w_c, r.data(), &jr, &jp);
    benchmark::DoNotOptimize(r.data());
  }
}
BENCHMARK(BM_FrameTotal)->Unit(benchmark::kMillisecond);

// What SkylineFrontend's prepare does for the window with the default configuration
// (frame_correlation_m 90, dem_sigma_m 4), then the gate's first evaluation at the same pose.
void BM_FramePrepared(benchmark::State& state) {
  const Scene& s = TheScene();
  const auto samples = skyline::SkylineSamples(skyline::ExtractSkylineFromMask(s.mask), 8, 0.5);
  const Eigen::Vector3d p_prev = s.p_w_c - 10.0 * s.r_w_c.col(2);
  long traced = 0;
  for (auto _ : state) {
    skyline::SkylineResidualModel model(s.horizon, *s.camera, samples, {});
    const skyline::CrestMotion motion = skyline::MeasureCrestMotion(
        *s.horizon, model.HorizonPoints(s.r_w_c, s.p_w_c), p_prev, 90.0);
    const double rho = std::min(motion.rho * 0.9, 0.999);
    model.SetFrameWeight(std::sqrt((1.0 - rho) / (1.0 + rho)));
    model.AddMapError(s.r_w_c, s.p_w_c, 4.0, 90.0);
    std::vector<double> r(model.size());
    Eigen::Matrix<double, Eigen::Dynamic, 3> jr, jp;
    model.Evaluate(s.r_w_c, s.p_w_c, r.data(), &jr, &jp);
    benchmark::DoNotOptimize(r.data());
    traced = model.traced_poses();
  }
  state.counters["traced_poses"] = static_cast<double>(traced);
}
BENCHMARK(BM_FramePrepared)->Unit(benchmark::kMillisecond);

void BM_BaselineFrame(benchmark::State& state) {
  const Scene& s = TheScene();
  skyline::baseline::BaselineInput in;
  in.intended_xy = s.p_w_c.head<2>() + Eigen::Vector2d(20, -25);
  in.previous_xy = s.p_w_c.head<2>() -
                   300.0 * Eigen::Vector2d(std::sin(20 * M_PI / 180), std::cos(20 * M_PI / 180));
  in.camera_z = s.p_w_c.z();
  in.r_level_c = s.r_level;
  for (auto _ : state) {
    benchmark::DoNotOptimize(
        skyline::baseline::LocateFrameBaseline(s.horizon->grid(), *s.camera, s.mask, in));
  }
}
BENCHMARK(BM_BaselineFrame)->Unit(benchmark::kMillisecond);

void BM_SkerryFrameSearch(benchmark::State& state) {
  const Scene& s = TheScene();
  const auto samples = skyline::SkylineSamples(skyline::ExtractSkylineFromMask(s.mask), 8, 0.5);
  skyline::FrameLocatorOptions o;
  o.planar = true;
  o.search_radius_m = 105.0;
  o.grid_step_m = 26.25;
  o.horizontal_sigma_m = 35.0;
  o.prior_heading_deg = 20.0;
  o.heading_window_deg = 17.0;
  o.refine_candidates = 4;
  o.full_profiles = state.range(0) != 0;
  const Eigen::Vector3d prior = s.p_w_c + Eigen::Vector3d(20, -25, 0);
  skyline::FrameLocation loc;
  for (auto _ : state) {
    loc = skyline::LocateFrame(s.horizon, *s.camera, samples, s.r_level, prior, o);
  }
  state.counters["coarse_ms"] = 1e3 * loc.coarse_seconds;
  state.counters["coarse_traces"] = static_cast<double>(loc.coarse_traces);
  state.counters["error_m"] = loc.ok ? (loc.p_w_c - s.p_w_c).head<2>().norm() : -1.0;
}
BENCHMARK(BM_SkerryFrameSearch)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// The global search that starts a run without GNSS (SkylineFrontend::Locate with
// SkylineStartOptions' 1 km and the default preset's map error), on 1 and 2 threads
// (skyline.threads): wall time, both in the same run.
void BM_GlobalStart(benchmark::State& state) {
  const Scene& s = TheScene();
  const auto samples = skyline::SkylineSamples(skyline::ExtractSkylineFromMask(s.mask), 8, 0.5);
  skyline::FrameLocatorOptions o;
  o.residual.threads = static_cast<int>(state.range(0));
  o.dem_sigma_m = 4.0;
  o.map_correlation_m = 90.0;
  o.search_radius_m = 1000.0;
  o.grid_step_m = 100.0;
  o.tilt_sigma_rad = 2.0 * M_PI / 180.0;
  const Eigen::Vector3d prior = s.p_w_c + Eigen::Vector3d(-400, 300, 0);
  double error_m = 0.0;
  for (auto _ : state) {
    const skyline::FrameLocation loc =
        skyline::LocateFrame(s.horizon, *s.camera, samples, s.r_level, prior, o);
    error_m = loc.ok ? (loc.p_w_c - s.p_w_c).head<2>().norm() : -1.0;
  }
  state.counters["threads"] = static_cast<double>(state.range(0));
  state.counters["error_m"] = error_m;  // -1: not located
}
BENCHMARK(BM_GlobalStart)->Arg(1)->Arg(2)->UseRealTime()->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) {
  std::vector<char*> args;
  std::string reps = "--benchmark_repetitions=5", agg = "--benchmark_report_aggregates_only=true";
  bool has_reps = false;
  int cv_threads = 1;
  for (int i = 0; i < argc; ++i) {
    const std::string a = argv[i];
    if (a.rfind("--grid_m=", 0) == 0) {
      const std::string v = a.substr(9);
      char* end = nullptr;
      g_grid_m = std::strtod(v.c_str(), &end);
      if (v.empty() || *end != '\0' || !(g_grid_m >= 0) || !std::isfinite(g_grid_m)) {
        std::fprintf(stderr, "--grid_m: '%s' must be 0 (skerry's default map) or a spacing > 0\n",
                     v.c_str());
        return 2;
      }
      continue;
    }
    if (a.rfind("--cv_threads=", 0) == 0) {
      const std::string v = a.substr(13);
      char* end = nullptr;
      const long n = std::strtol(v.c_str(), &end, 10);
      if (v.empty() || *end != '\0' || n < -1 || n == 0 || n > 256) {
        std::fprintf(stderr, "--cv_threads: '%s' must be -1 (OpenCV's default) or 1 to 256\n",
                     v.c_str());
        return 2;
      }
      cv_threads = static_cast<int>(n);
      continue;
    }
    has_reps |= i > 0 && a.rfind("--benchmark_rep", 0) == 0;
    args.push_back(argv[i]);
  }
  cv::setNumThreads(cv_threads);
  benchmark::AddCustomContext("opencv_threads", std::to_string(cv::getNumThreads()));
  benchmark::AddCustomContext(
      "map", g_grid_m > 0 ? "DEM resampled at --grid_m=" + std::to_string(g_grid_m) + " m"
                          : "skerry's default (HorizonForTrack), frame from the simulator's world");
  if (!has_reps) {
    args.push_back(reps.data());
    args.push_back(agg.data());
  }
  int n = static_cast<int>(args.size());
  benchmark::Initialize(&n, args.data());
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
