// RenderCameraImages (simulator.h): the simulator's camera frames from its DEM.

#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <exception>
#include <filesystem>
#include <mutex>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>
#include <string>
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

#include "random.h"
#include "skerry/core/input_error.h"
#include "skerry/geo/dem.h"
#include "skerry/sim/dem_error.h"
#include "skerry/sim/simulator.h"
#include "skerry/sim/terrain_relief.h"
#include "skerry/sim/terrain_renderer.h"
#include "skerry/sim/world_terrain.h"
#include "true_pose.h"

namespace skerry::sim {

void RenderCameraImages(const ScenarioConfig& config,
                        std::uint64_t seed,
                        Dataset* data,
                        const std::string& out_dir,
                        const std::function<void(double)>& progress,
                        int threads) {
  if (data->cameras.empty()) return;
  if (!data->dem) throw std::invalid_argument("RenderCameraImages: the scenario has no dem");
  const LocalFrame frame(data->origin);
  const geo::VerticalDatum datum = data->dem->vertical_datum == "ellipsoidal"
                                       ? geo::VerticalDatum::kEllipsoidal
                                       : geo::VerticalDatum::kEgm96;
  const geo::Dem dem(data->dem->path, frame, geo::DemOptions(datum));
  std::vector<Eigen::Vector3d> track;
  Eigen::AlignedBox2d box;
  for (const NavState& s : data->truth_states) {
    track.push_back(s.p_w_b);
    box.extend(s.p_w_b.head<2>());
  }
  dem.RequireCovers(track, 0.0);
  TerrainRenderOptions options;
  const Eigen::Vector2d grow = Eigen::Vector2d::Constant(options.max_range_m);
  box = Eigen::AlignedBox2d(box.min() - grow, box.max() + grow).intersection(dem.footprint_enu());
  // The raster's surface, off the estimator's grid (world_terrain.h), marched at the step in
  // metres the renderer takes on a grid of the raster's own cell.
  geo::EnuHeightGrid terrain = WorldTerrain(dem, box);
  options.step_spacings *= dem.cell_size_m().minCoeff() / terrain.spacing_m;
  if (config.dem) {
    AddTerrainRelief(config.dem->relief, dem.cell_size_m().minCoeff(), options.earth_radius_m,
                     &terrain);
    AddDemError(config.dem->error, seed, options.earth_radius_m, &terrain);
  }
  const TerrainRenderer renderer(std::move(terrain), options);
  const bool grey = config.camera.images == "grey";
  // The frames to render, in the order their noise seeds are drawn (the same dataset whatever the
  // number of threads); then rendered and written in parallel, each frame on its own.
  struct Job {
    const CameraConfig* camera;
    Eigen::Quaterniond q_w_c;
    Eigen::Vector3d p_w_c;
    std::uint64_t noise_seed;
    std::string path;
  };
  std::vector<Job> jobs;
  Rng rng(seed, RngStream::kCameraNoise);
  for (size_t k = 0; k < data->cameras.size(); ++k) {
    CameraConfig& camera = data->cameras[k];
    const std::filesystem::path dir = std::filesystem::absolute(out_dir) / camera.name;
    std::filesystem::create_directories(dir);
    camera.image_dir = dir.string();
    for (const SensorFrame& f : data->camera_frames[k]) {
      Eigen::Quaterniond q_w_b;
      Eigen::Vector3d p_w_b;
      if (!TruePose(data->truth_states, f.t_ns, &q_w_b, &p_w_b)) {
        throw std::invalid_argument("RenderCameraImages: no truth at a frame's time");
      }
      const std::uint64_t noise_seed = static_cast<std::uint64_t>(rng.Uniform() * 0x1.0p53);
      jobs.push_back({&camera, q_w_b * camera.T_b_c.q_b_s, p_w_b + q_w_b * camera.T_b_c.p_b_s,
                      noise_seed, (dir / f.file).string()});
    }
  }
  const size_t workers = std::min<size_t>(
      jobs.size(), threads > 0 ? static_cast<size_t>(threads)
                               : std::max(1u, std::thread::hardware_concurrency()));
  std::atomic<size_t> next{0};
  std::atomic<bool> failed{false};
  std::mutex mutex;  // guards done, first_error and progress
  size_t done = 0;
  std::exception_ptr first_error;
  const auto work = [&] {
    for (size_t i = next++; i < jobs.size() && !failed; i = next++) {
      try {
        const Job& job = jobs[i];
        const RenderedFrame r =
            renderer.Render(*job.camera, job.q_w_c, job.p_w_c, grey, job.noise_seed);
        if (!cv::imwrite(job.path, grey ? r.grey : r.mask)) {
          throw std::runtime_error("cannot write " + job.path);
        }
        const std::lock_guard<std::mutex> lock(mutex);
        ++done;
        if (progress) progress(static_cast<double>(done) / static_cast<double>(jobs.size()));
      } catch (...) {
        const std::lock_guard<std::mutex> lock(mutex);
        if (!first_error) first_error = std::current_exception();
        failed = true;
      }
    }
  };
  std::vector<std::thread> pool;
  for (size_t t = 1; t < workers; ++t) {
    try {
      pool.emplace_back(work);
    } catch (const std::system_error&) {
      break;  // no more threads to be had: the ones running share the frames
    }
  }
  work();
  for (std::thread& t : pool) t.join();
  if (first_error) std::rethrow_exception(first_error);
}

}  // namespace skerry::sim
