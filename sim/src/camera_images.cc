// RenderCameraImages (simulator.h): the simulator's camera frames from its DEM.

#include <Eigen/Geometry>
#include <algorithm>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <stdexcept>

#include "random.h"
#include "skerry/core/input_error.h"
#include "skerry/geo/dem.h"
#include "skerry/sim/simulator.h"
#include "skerry/sim/terrain_renderer.h"
#include "true_pose.h"

namespace skerry::sim {

void RenderCameraImages(const ScenarioConfig& config,
                        std::uint64_t seed,
                        Dataset* data,
                        const std::string& out_dir,
                        const std::function<void(double)>& progress) {
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
  const TerrainRenderOptions options;
  const Eigen::Vector2d grow = Eigen::Vector2d::Constant(options.max_range_m);
  box = Eigen::AlignedBox2d(box.min() - grow, box.max() + grow).intersection(dem.footprint_enu());
  const TerrainRenderer renderer(dem.ResampleToEnu(box, dem.cell_size_m().minCoeff()), options);
  const bool grey = config.camera.images == "grey";
  size_t total = 0, done = 0;
  for (const auto& f : data->camera_frames) total += f.size();
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
      const Eigen::Quaterniond q_w_c = q_w_b * camera.T_b_c.q_b_s;
      const Eigen::Vector3d p_w_c = p_w_b + q_w_b * camera.T_b_c.p_b_s;
      const std::uint64_t noise_seed = static_cast<std::uint64_t>(rng.Uniform() * 0x1.0p53);
      const RenderedFrame r = renderer.Render(camera, q_w_c, p_w_c, grey, noise_seed);
      const std::string path = (dir / f.file).string();
      if (!cv::imwrite(path, grey ? r.grey : r.mask)) {
        throw std::runtime_error("cannot write " + path);
      }
      if (progress) progress(static_cast<double>(++done) / total);
    }
  }
}

}  // namespace skerry::sim
