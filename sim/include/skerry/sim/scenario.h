#pragma once
/// \file
/// A simulation scenario: the vessel's manoeuvres, the sea state, the IMU and GNSS error models.
/// Loaded from YAML with units in every key name (see docs/simulator.md and
/// config/scenarios/*.yaml).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <string>
#include <vector>

#include "skerry/core/geodesy.h"
#include "skerry/core/sensor_config.h"

namespace skerry::sim {

/// IMU grades with preset error models (numbers and sources in docs/simulator.md).
enum class ImuGrade { kConsumer, kTactical, kNavigation };

/// The IMU error model: white-noise and bias random-walk densities, and the 1-sigma of the
/// biases drawn once at the start of a run (turn-on bias).
struct ImuErrorModel {
  ImuNoise noise;
  double gyro_bias_initial_sigma_rad_s = 0.0;
  double accel_bias_initial_sigma_m_s2 = 0.0;
};

/// The preset error model of an IMU grade.
ImuErrorModel ImuGradePreset(ImuGrade grade);

struct ImuModel {
  std::string grade = "tactical";  ///< name of the preset the errors started from
  double rate_hz = 200.0;
  ImuErrorModel errors = ImuGradePreset(ImuGrade::kTactical);
  Eigen::Quaterniond q_b_i = Eigen::Quaterniond::Identity();  ///< IMU -> body rotation
  Eigen::Vector3d p_b_i = Eigen::Vector3d::Zero();            ///< IMU origin in body, m
  double gravity_m_s2 = 9.80665;
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
  std::vector<GnssJump> jumps;
  std::vector<GnssOutage> outages;
  /// Dual-antenna heading, attached to every emitted fix when enabled.
  bool dual_antenna_enabled = false;
  double heading_sigma_deg = 0.2;
  Eigen::Vector3d baseline_b = Eigen::Vector3d::UnitX();
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
  ImuModel imu;
  GnssModel gnss;
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

/// Names of the built-in scenarios found on the search path, sorted, without duplicates.
std::vector<std::string> ListBuiltinScenarios();

}  // namespace skerry::sim
