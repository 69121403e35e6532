#pragma once
/// \file
/// A simulation scenario: the vessel's manoeuvres, the sea state, the IMU and GNSS error models.
/// Loaded from YAML with units in every key name (see docs/simulator.md and
/// config/scenarios/*.yaml).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "skerry/core/earth_model.h"
#include "skerry/core/geodesy.h"
#include "skerry/core/sensor_config.h"
#include "skerry/sim/dem_error.h"
#include "skerry/sim/terrain_relief.h"

namespace skerry::sim {

/// IMU grades with preset error models (numbers and sources in docs/simulator.md).
enum class ImuGrade { kConsumer, kTactical, kNavigation };

/// The IMU error model. `noise` and the initial sigmas are the datasheet model, what a user
/// tells skerry (the simulator writes them to dataset.yaml); the rest are errors a real unit has
/// and skerry's IMU model does not, each drawn once per run or driven by its own random stream.
struct ImuErrorModel {
  ImuNoise noise;
  double gyro_bias_initial_sigma_rad_s = 0.0;  ///< turn-on bias, drawn once per axis
  double accel_bias_initial_sigma_m_s2 = 0.0;
  /// Scale-factor errors, 1-sigma per axis (ppm), drawn once: measured = (I + S + M) true.
  double gyro_scale_factor_ppm = 0.0;
  double accel_scale_factor_ppm = 0.0;
  /// Axis misalignment (non-orthogonality), 1-sigma of each off-diagonal of M (mrad).
  double gyro_misalignment_mrad = 0.0;
  double accel_misalignment_mrad = 0.0;
  /// In-run bias wander. With bias_instability_tau_s > 0 it is a first-order Gauss-Markov
  /// process per axis (stationary sigma = the instability, correlation time tau), bounded where
  /// the estimator's random walk is not; with tau = 0 it is a random walk with the datasheet
  /// densities of `noise` (the estimator's own model).
  double gyro_bias_instability_rad_s = 0.0;
  double accel_bias_instability_m_s2 = 0.0;
  double bias_instability_tau_s = 0.0;
};

/// The preset error model of an IMU grade.
ImuErrorModel ImuGradePreset(ImuGrade grade);

struct ImuModel {
  std::string grade = "tactical";  ///< name of the preset the errors started from
  double rate_hz = 200.0;
  ImuErrorModel errors = ImuGradePreset(ImuGrade::kTactical);
  Eigen::Quaterniond q_b_i = Eigen::Quaterniond::Identity();  ///< IMU -> body rotation
  Eigen::Vector3d p_b_i = Eigen::Vector3d::Zero();            ///< IMU origin in body, m
};

/// Every fix in [start_s, start_s + duration_s) is shifted by offset_enu_m.
struct GnssJump {
  double start_s = 0.0;
  double duration_s = 0.0;
  Eigen::Vector3d offset_enu_m = Eigen::Vector3d::Zero();
};

/// No fix in [start_s, start_s + duration_s).
struct GnssOutage {
  double start_s = 0.0;
  double duration_s = 0.0;
};

struct GnssModel {
  double rate_hz = 1.0;
  Eigen::Vector3d p_b_g = Eigen::Vector3d::Zero();  ///< (primary) antenna in body, m
  /// True white noise added to every fix (1-sigma, per axis).
  double noise_sigma_horizontal_m = 0.3;
  double noise_sigma_vertical_m = 0.5;
  /// What the receiver claims (written to gnss.csv); need not equal the true noise.
  double reported_sigma_horizontal_m = 0.5;
  double reported_sigma_vertical_m = 0.8;
  /// Slowly wandering error, first-order Gauss-Markov per axis with stationary sigma and
  /// correlation time tau. Zero sigma disables it.
  double drift_sigma_horizontal_m = 0.0;
  double drift_sigma_vertical_m = 0.0;
  double drift_tau_s = 300.0;
  /// A second, slower Gauss-Markov process (ionosphere, orbits, clocks), which skerry's one
  /// drift state does not model. Zero sigma disables it.
  double slow_drift_sigma_horizontal_m = 0.0;
  double slow_drift_sigma_vertical_m = 0.0;
  double slow_drift_tau_s = 1800.0;
  /// Multipath bursts: episodes after exponentially distributed gaps (mean 1 / rate_per_hour),
  /// each lasting an exponentially distributed time (mean mean_duration_s), during which a fast
  /// Gauss-Markov error (sigma, tau) adds to every fix; a share d / (1/rate + d) of the time is
  /// in a burst. Zero rate disables them.
  double multipath_rate_per_hour = 0.0;
  double multipath_mean_duration_s = 20.0;
  double multipath_sigma_horizontal_m = 1.0;
  double multipath_sigma_vertical_m = 2.0;
  double multipath_tau_s = 2.0;
  /// Timing: the receiver measures at time_offset_s + k / rate_hz (off the estimator's keyframe
  /// grid unless the offset is a multiple of its period) and each fix is stamped latency_s +
  /// N(0, stamp_jitter_s^2) later than the instant it measured (a host clock stamping arrival).
  /// The estimator is told neither.
  double time_offset_s = 0.0;
  double latency_s = 0.0;
  double stamp_jitter_s = 0.0;
  std::vector<GnssJump> jumps;
  std::vector<GnssOutage> outages;
  /// Dual-antenna heading, attached to every emitted fix when enabled.
  bool dual_antenna_enabled = false;
  double heading_sigma_deg = 0.2;
  Eigen::Vector3d baseline_b = Eigen::Vector3d::UnitX();
};

/// Pose fixes from an external matcher (a LiDAR/aerial matcher, radar against a chart, USBL):
/// the pose of a frame s on the vessel (T_b_s) measured at time_offset_s + k / rate_hz inside
/// [start_s, end_s), with white noise of the given sigmas, and with probability
/// outlier_probability a gross error instead: a horizontal offset of outlier_min_m to twice that
/// in a random direction, and a heading error of +-outlier_heading_min_deg to twice that.
struct PoseFixModel {
  bool enabled = false;
  double rate_hz = 1.0;
  double time_offset_s = 0.37;  ///< off a 10 Hz keyframe grid
  double start_s = 0.0;
  double end_s = 1e300;
  std::string kind = "enh";  ///< en | enu | enh | enuh: what each fix measures
  double sigma_horizontal_m = 0.5;
  double sigma_vertical_m = 1.0;
  double sigma_heading_deg = 1.0;
  double outlier_probability = 0.0;
  double outlier_min_m = 20.0;
  double outlier_heading_min_deg = 20.0;
  SensorMount mount;  ///< T_b_s of the measured frame
};

/// Cameras rendered from a DEM (terrain_renderer.h): frames at time_offset_s + k / rate_hz in
/// [start_s, end_s), a forward camera or a ring of four (forward, port, aft, starboard), the
/// true pose with the waves' roll and pitch. `images`: what is written, a segmentation mask (sky
/// 255) or the shaded grey image.
struct CameraModelSim {
  bool enabled = false;
  double rate_hz = 1.0;
  double time_offset_s = 0.23;  ///< off the 10 Hz keyframe grid
  double start_s = 0.0;
  double end_s = 1e300;
  int width_px = 1920;
  int height_px = 1080;
  double horizontal_fov_deg = 70.0;
  std::vector<double> distortion = {-0.05, 0.01, 0.0, 0.0};  ///< OpenCV k1 k2 p1 p2 [k3]
  std::string images = "mask";                               ///< mask | grey
  bool ring = false;
  Eigen::Vector3d p_b_c = Eigen::Vector3d(2.0, 0.0, 4.0);  ///< forward camera on the mast, m
  double pitch_down_deg = 0.0;  ///< the cameras look this much below the horizontal
};

/// The terrain the cameras see (dataset.yaml maps.dem).
struct DemSim {
  std::string path;  ///< absolute (relative paths are resolved against the scenario file)
  std::string vertical_datum = "egm96";
  /// The DEM's own error in the world the cameras see (dem_error.h); the estimator is given the
  /// file as it is.
  DemErrorSpec error;
  /// The relief the raster averaged away, given back to the world the cameras see
  /// (terrain_relief.h; dataset.yaml's map stays the raster).
  TerrainReliefSpec relief;
};

/// The aerial photograph of the harbour (aerial_render.h), written as an orthophoto (8-bit grey
/// PNG, world file, CRS sidecar in the UTM zone of the origin) and named in dataset.yaml
/// maps.orthophoto. A perspective camera camera_height_m above the water at the harbour's
/// centre looks straight down; the image is rectified to the terrain (land, quays, piers,
/// breakwaters) but not to what stands on it, so buildings, boats and poles lean outward as in a
/// real (not true) orthophoto.
struct AerialImageSim {
  bool enabled = true;
  double resolution_m = 0.16;      ///< ground sample distance
  double margin_m = 30.0;          ///< beyond the harbour and the track
  double camera_height_m = 800.0;  ///< above the water
  double sun_azimuth_deg = 135.0;  ///< towards the sun, clockwise from north
  double sun_elevation_deg = 40.0;
  /// Georeferencing error: the image shows every object this far east / north of where it is
  /// (a misregistered photo). Zero by default.
  double image_offset_east_m = 0.0;
  double image_offset_north_m = 0.0;
  double noise_grey = 2.0;  ///< pixel noise, grey levels (1 sigma)
};

/// The built-in harbour (harbour_world.h): a square basin with quays on three sides, a
/// breakwater with an entrance on the fourth (south), piers, buildings, bollards, poles, a crane,
/// moored boats drawn from the seed, and a channel between two long parallel quays leading north
/// out of the basin. Placed with its basin's centre at (centre_east_m, centre_north_m) in w,
/// turned by rotation_deg (counter-clockwise seen from above).
struct HarbourSpec {
  bool enabled = false;
  double centre_east_m = 0.0;
  double centre_north_m = 0.0;
  double rotation_deg = 0.0;
  double water_level_up_m = 0.0;  ///< the water surface's up coordinate in w
  double basin_size_m = 250.0;    ///< the basin is basin_size_m x basin_size_m
  double quay_height_m = 1.8;     ///< quay and land tops above the water
  double entrance_width_m = 50.0;
  int piers = 3;  ///< 0..3: two from the north quay, a third from the west quay
  double channel_width_m = 40.0;
  double channel_length_m = 240.0;  ///< from the basin's north quay to the channel's open end
  int boats_moored = 14;            ///< in the photograph and still there
  int boats_image_only = 4;         ///< moored when the photograph was taken, gone now
  int boats_lidar_only = 3;         ///< arrived since the photograph
  AerialImageSim aerial_image;
};

/// A spinning LiDAR (lidar_scans.h) scanning the harbour from the vessel's true, moving pose.
/// One sweep takes 1 / rotation_rate_hz; a sweep is written every 1 / write_rate_hz from
/// time_offset_s, stamped with its start. The vessel's own hull and superstructure, one box in
/// the body frame, returns points too.
struct LidarModelSim {
  bool enabled = false;
  double write_rate_hz = 1.0;
  double time_offset_s = 0.13;  ///< off the 10 Hz keyframe grid
  double start_s = 0.0;
  double end_s = 1e300;
  double rotation_rate_hz = 10.0;
  /// Beam elevations; empty: `beams` evenly from min to max elevation.
  std::vector<double> elevations_deg;
  int beams = 32;
  double min_elevation_deg = -25.0;
  double max_elevation_deg = 15.0;
  double azimuth_step_deg = 0.4;
  double min_range_m = 0.5;
  double max_range_m = 100.0;
  double range_noise_sigma_m = 0.03;
  /// A return is lost with probability dropout_at_max_range * (range / max_range) ^ exponent.
  double dropout_at_max_range = 0.5;
  double dropout_range_exponent = 2.0;
  SensorMount T_b_l{Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.0, 0.0, 3.0)};
  /// The own hull and superstructure: an axis-aligned box in the body frame.
  Eigen::Vector3d hull_centre_b_m = Eigen::Vector3d(0.0, 0.0, 0.25);
  Eigen::Vector3d hull_size_m = Eigen::Vector3d(15.0, 4.5, 2.5);
  double hull_reflectivity = 0.6;
};

/// One manoeuvre. Turns keep the speed; speed changes keep the heading.
struct Leg {
  enum class Type { kStraight, kTurn, kSpeedChange };
  Type type = Type::kStraight;
  double duration_s = 0.0;  ///< kStraight
  double angle_deg = 0.0;   ///< kTurn: > 0 to starboard (heading increases), < 0 to port
  double rate_deg_s = 0.0;  ///< kTurn: steady rate of turn (> 0)
  double ramp_s = -1.0;     ///< kTurn: rate-of-turn ramp time; < 0 uses TrajectorySpec's
  double to_m_s = 0.0;      ///< kSpeedChange: final speed (>= 0)
  double accel_m_s2 = 0.0;  ///< kSpeedChange: mean |acceleration| (> 0); the peak is twice it
};

struct TrajectorySpec {
  Eigen::Vector3d start_enu_m = Eigen::Vector3d::Zero();
  double start_heading_deg = 0.0;  ///< clockwise from north
  double start_speed_m_s = 5.0;    ///< through the water, along the body x axis
  /// Constant water current (east, north) added to the velocity over ground; makes course over
  /// ground differ from heading.
  Eigen::Vector2d current_enu_m_s = Eigen::Vector2d::Zero();
  double turn_ramp_s = 3.0;  ///< default time to reach the steady rate of turn
  /// Heel in turns per m/s^2 of centripetal acceleration; > 0 heels outward (displacement
  /// hull), < 0 inward (planing hull).
  double heel_deg_per_m_s2 = 0.0;
  /// Manoeuvres in order; after the last one the vessel goes straight on, and legs running past
  /// the scenario's end are cut.
  std::vector<Leg> legs;
};

/// One sinusoid of a sum a * sin(2 pi t / period + phase), the phase drawn from the seed.
struct WaveComponent {
  double amplitude = 0.0;  ///< deg for roll/pitch, m for heave (peak, not peak-to-peak)
  double period_s = 1.0;
};

struct WaveSpec {
  std::vector<WaveComponent> roll_deg;
  std::vector<WaveComponent> pitch_deg;
  std::vector<WaveComponent> heave_m;
};

struct ScenarioConfig {
  std::string name;
  std::string source_file;  ///< the YAML it came from (empty if built in code)
  double duration_s = 600.0;
  std::uint64_t seed = 1;  ///< default seed; Simulate() takes the one to use
  GeoOrigin origin{47.60, 9.45, 440.0};
  /// The world simulated: the round, rotating WGS84 Earth, or the flat one (earth_motion.h).
  EarthConfig earth;
  ImuModel imu;
  GnssModel gnss;
  PoseFixModel pose_fixes;
  CameraModelSim camera;
  std::optional<DemSim> dem;
  /// The harbour world the LiDAR scans and the aerial image shows.
  HarbourSpec harbour;
  LidarModelSim lidar;
  /// The vessel floats (written to dataset.yaml sensors.water_surface when enabled): its body
  /// origin stays at its starting ellipsoidal height up to the waves.
  bool water_surface_enabled = false;
  double water_surface_sigma_m = 0.3;
  double water_surface_rate_hz = 1.0;
  double groundtruth_rate_hz = 50.0;  ///< groundtruth.tum and truth_states.csv
  TrajectorySpec trajectory;
  WaveSpec waves;
};

/// Loads a scenario: a path to a YAML file (anything containing '/' or ending in .yaml/.yml), or
/// a built-in NAME looked up as NAME.yaml in, in order, $SKERRY_SCENARIO_DIR, the installed
/// share/skerry/scenarios and the source tree's config/scenarios. Throws InputError naming the
/// file, line and key path on bad YAML, unknown keys, wrong types, non-finite or out-of-range
/// values, and when no scenario of that name exists.
ScenarioConfig LoadScenario(const std::string& name_or_path);

/// Parses scenario YAML text; `file` names it in errors.
ScenarioConfig ParseScenario(const std::string& yaml_text, const std::string& file);

/// The GNSS drift an estimator assumes (its Gauss-Markov state; EstimatorConfig::gnss_drift).
struct DriftModel {
  double sigma_horizontal_m = 0.15;
  double sigma_vertical_m = 0.3;
  double tau_s = 300.0;
};

/// The scenario in the world of skerry's model: no scale factor, misalignment or Gauss-Markov
/// bias (the bias random-walks with the datasheet densities), no second GNSS process,
/// multipath, latency or stamp jitter, the receiver reporting its true white-noise sigmas, and
/// the GNSS drift the estimator assumes. Motion, Earth, events, rates and the receiver's time
/// offset are kept.
ScenarioConfig MatchedToEstimator(const ScenarioConfig& config, const DriftModel& drift);

/// Names of the built-in scenarios found on the search path, sorted, without duplicates.
std::vector<std::string> ListBuiltinScenarios();

}  // namespace skerry::sim
