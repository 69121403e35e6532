#pragma once
/// \file
/// A skerry dataset folder (see docs/dataset-format.md): dataset.yaml, imu.csv (unless the dataset
/// has no IMU), gnss.csv and an optional groundtruth.tum; the simulator adds truth_states.csv and
/// events.csv; marine logs add heading.csv, course.csv, attitude.csv and rate_of_turn.csv.

#include <optional>
#include <string>
#include <vector>

#include "skerry/core/earth_model.h"
#include "skerry/core/geodesy.h"
#include "skerry/core/gnss_event.h"
#include "skerry/core/measurements.h"
#include "skerry/core/nav_state.h"
#include "skerry/core/sensor_config.h"
#include "skerry/io/csv_reader.h"
#include "skerry/io/marine_log.h"
#include "skerry/io/trajectory.h"

namespace skerry {

/// One frame or scan of a camera or LiDAR: its time and file (relative to the sensor's folder).
struct SensorFrame {
  TimeNs t_ns = 0;
  std::string file;
};

/// The maps a dataset names (`maps:`); the geodata layer (geo/) loads them.
struct MapConfig {
  std::string path;            ///< absolute, or relative to the dataset folder as written
  std::string crs;             ///< optional CRS override (EPSG:xxxx, WKT, or a .prj/.wkt file)
  std::string vertical_datum;  ///< DEMs: egm96 | ellipsoidal
  /// Orthophotos: where the photograph was taken from (its projection centre, ellipsoidal
  /// height), when known: the LiDAR/aerial alignment models its relief displacement.
  std::optional<GeoOrigin> viewpoint;
  /// Orthophotos of 16-bit, 32-bit or float cells: the share of valid cells clipped at each end
  /// of the stretch onto 8 bits, in [0, 0.5) (geo::OrthophotoOptions::clip_fraction); unset:
  /// the geodata layer's default.
  std::optional<double> clip_fraction;
};

struct Dataset {
  std::string name;
  std::string directory;
  GeoOrigin origin;
  EarthConfig earth;  ///< dataset.yaml `earth:`; WGS84 unless it says otherwise
  /// false: no `sensors.imu` and no imu.csv (a marine log's dataset); `imu`, `imu_samples` and
  /// `imu_path` are then unused, and every estimator command refuses it (RequireImu).
  bool has_imu = true;
  ImuConfig imu;
  GnssConfig gnss;
  bool has_gnss = false;
  std::string gnss_path;  ///< the GNSS file LoadDataset read (for messages); empty otherwise
  std::string imu_path;   ///< the IMU file; empty without IMU
  std::vector<ImuSample> imu_samples;    ///< strictly increasing time
  std::vector<GnssFix> gnss_fixes;       ///< strictly increasing time, p_w filled
  std::vector<StampedPose> groundtruth;  ///< empty when absent
  /// The ground-truth file LoadDataset read (ReadTum reads it again); empty without one.
  std::string groundtruth_path;
  std::vector<NavState> truth_states;  ///< truth_states.csv; empty when absent
  std::vector<GnssEvent> events;       ///< events.csv; empty when absent
  /// Pose fixes from an external matcher (sensors.pose_fixes).
  bool has_pose_fixes = false;
  SensorMount pose_fix_mount;  ///< the measured frame s on the vessel
  std::string pose_fix_path;
  std::vector<PoseFix> pose_fixes;  ///< strictly increasing time
  /// Simulator truth (pose_fix_outliers.csv): the times of the pose fixes it made gross.
  std::vector<TimeNs> pose_fix_outliers;
  /// Cameras and LiDARs (sensors.camera*, sensors.lidar*), with their frames in time order.
  std::vector<CameraConfig> cameras;
  std::vector<std::vector<SensorFrame>> camera_frames;  ///< per camera
  std::vector<LidarConfig> lidars;
  std::vector<std::vector<SensorFrame>> lidar_scans;  ///< per LiDAR
  /// The vessel floats at this height (sensors.water_surface); absent for a vehicle on land.
  std::optional<WaterSurfaceConfig> water_surface;
  std::optional<MapConfig> dem;         ///< maps.dem
  std::optional<MapConfig> orthophoto;  ///< maps.orthophoto
  /// heading.csv, course.csv, attitude.csv, rate_of_turn.csv when present (marine logs; not read
  /// with DatasetParts::kWithoutStreams; not used by the estimators yet). Each strictly
  /// increasing in time; `source` is not kept.
  MarineRecords marine;

  /// The Earth the estimators use for this dataset (origin + earth).
  EarthModel Earth() const { return EarthModel(origin, earth); }
};

/// What LoadDataset reads: everything; all but the files that grow with the recording's
/// length (imu.csv, gnss.csv, truth_states.csv), which a long run streams instead
/// (measurement_stream.h: DatasetFileStream); or all but truth_states.csv, the simulator's full
/// true states, which no estimator reads (`truth_states` stays empty: 144 bytes a state not held
/// through a run; the accuracy figures use the ground truth, `groundtruth`).
enum class DatasetParts { kAll, kWithoutStreams, kWithoutTruthStates };

/// Loads a dataset folder. Throws InputError naming the file, line and field on any malformed,
/// truncated, non-finite, or out-of-order input, missing key or unknown sensor.
Dataset LoadDataset(const std::string& directory, DatasetParts parts = DatasetParts::kAll);

/// Throws InputError (`DIR/dataset.yaml: sensors.imu: ...`) naming the dataset when it has no
/// IMU: what every command that integrates an IMU (run, smooth, compare) calls first, since the
/// estimators themselves need IMU samples. `command` is said in the message.
void RequireImu(const Dataset& data, const std::string& command);

/// The rows of imu.csv and gnss.csv (docs/dataset-format.md), one at a time: the reader with its
/// header checked, and the current row parsed and checked (InputError naming file, line, column).
CsvReader OpenImuCsv(const std::string& path);
ImuSample ReadImuRow(CsvReader* reader);
/// An imu.csv with a header and no rows.
[[noreturn]] void ThrowNoImuSamples(const std::string& path);
CsvReader OpenGnssCsv(const std::string& path);
GnssFix ReadGnssRow(const LocalFrame& frame, CsvReader* reader);

/// Reads a pose_fixes.csv file (docs/dataset-format.md); throws InputError naming the line and
/// column on bad input, a covariance that is not positive definite included.
std::vector<PoseFix> ReadPoseFixesCsv(const std::string& path);

/// Reads an events.csv file (simulator GNSS outages and jumps); throws InputError on bad input.
std::vector<GnssEvent> ReadEventsCsv(const std::string& path);

/// The data a live system holds at `t_end_ns`: the IMU samples, GNSS fixes, ground truth and
/// truth states up to and including that time, and the events that started by then (an event
/// still running is cut at `t_end_ns`). Sensors, origin and name are kept.
Dataset DatasetUntil(const Dataset& data, TimeNs t_end_ns);

/// Writes a dataset folder (creating it). Inverse of LoadDataset. Camera image folders, LiDAR
/// scan folders and maps are named where they are: relative to `directory` when inside it (so
/// the folder moves as a whole), else by absolute path.
void WriteDataset(const Dataset& dataset, const std::string& directory);

}  // namespace skerry
