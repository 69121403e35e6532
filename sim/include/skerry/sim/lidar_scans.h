#pragma once
/// \file
/// A spinning multi-beam LiDAR in the simulated harbour (harbour_world.h), and its scans written
/// as binary PCD files.
///
/// Model (LidarModelSim in scenario.h). The head turns counter-clockwise about the LiDAR's z
/// axis at rotation_rate_hz; a sweep starts at azimuth -180 deg (aft for a forward-looking
/// mount: the seam lies behind) at the scan's stamp, and fires all beams together every
/// azimuth_step_deg (rounded so that a whole number of steps makes 360 deg). Azimuth a and
/// elevation e give the beam direction d_l = (cos e cos a, cos e sin a, sin e) in the LiDAR frame
/// l (x forward, y left, z up when mounted level). Each firing happens at its own time
/// t = k / n_steps / rotation_rate_hz after the stamp, from the vessel's true pose at that time
/// (truth states interpolated): a moving vessel's scan is skewed, as a real one is, and each point
/// is given in l at its own time, with that time.
///
/// A beam returns the first surface it meets among the world's present boxes (WorldView::kLidar)
/// and the vessel's own hull (an axis-aligned box in the body frame), within max_range_m; none
/// from the water. A return at range r is lost with probability
/// dropout_at_max_range * (r / max_range_m)^dropout_range_exponent, then measured with range
/// noise N(0, range_noise_sigma_m^2) along the beam; returns nearer than min_range_m are dropped.
/// Its intensity is 100 * reflectivity * |cos(incidence)| (a Lambertian target, as a calibrated
/// reflectivity channel reports it: no range fall-off).
///
/// Not modelled: beams fired in sequence within a firing (all fire at once), beam divergence and
/// mixed pixels at edges, multiple returns, returns from water spray or rain, intensity noise,
/// range-dependent noise, rolling timestamps per beam, the sensor's own occlusions other than the
/// hull box.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "skerry/core/time.h"
#include "skerry/io/dataset.h"
#include "skerry/sim/harbour_world.h"
#include "skerry/sim/scenario.h"

namespace skerry::sim {

struct LidarPoint {
  Eigen::Vector3f p_l = Eigen::Vector3f::Zero();  ///< in the LiDAR frame at its own time, m
  float intensity = 0.0f;                         ///< 0..100
  float t_s = 0.0f;                               ///< seconds after the sweep's start
  bool hull = false;  ///< simulator truth: on the own hull (not written to the PCD)
};

struct LidarScan {
  TimeNs t_ns = 0;                 ///< the sweep's start: the scan's stamp in lidar.csv
  std::vector<LidarPoint> points;  ///< in firing order (time increasing)
};

/// The beam elevations (rad), lowest first: the model's list, or `beams` evenly from the
/// minimum to the maximum elevation.
std::vector<double> LidarBeamElevations(const LidarModelSim& model);

/// The vessel's pose T_w_b at a time; false when it is not known.
using BodyPoseAt =
    std::function<bool(TimeNs t_ns, Eigen::Quaterniond* q_w_b, Eigen::Vector3d* p_w_b)>;

/// One sweep of the model starting at t_start_ns, the vessel moving as `pose` says. The noise
/// and dropout come from `noise_seed`. Throws std::invalid_argument when the pose is unknown
/// during the sweep.
LidarScan SimulateLidarScan(const HarbourWorld& world,
                            const LidarModelSim& model,
                            const BodyPoseAt& pose,
                            TimeNs t_start_ns,
                            std::uint64_t noise_seed);

/// Writes a scan as a binary PCD (v0.7) with float32 fields x y z intensity t (t in seconds after
/// the scan's stamp). Throws std::runtime_error when the file cannot be written.
void WriteLidarScanPcd(const LidarScan& scan, const std::string& path);

/// Simulates the dataset's LiDAR scans (Simulate puts their times and names in it) in the
/// scenario's harbour (BuildHarbour(config.harbour, seed)) at the true poses (truth_states), and
/// writes them as PCD into out_dir/<lidar name>/, which becomes the LiDAR's scan folder. Noise
/// from `seed`. Throws std::invalid_argument when the dataset has LiDARs and the scenario no
/// harbour. `progress` (0..1) may be empty.
void RenderLidarScans(const ScenarioConfig& config,
                      std::uint64_t seed,
                      Dataset* data,
                      const std::string& out_dir,
                      const std::function<void(double)>& progress = {});

}  // namespace skerry::sim
