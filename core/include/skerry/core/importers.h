#pragma once
/// \file
/// Importers that turn public recordings into skerry datasets (in memory; WriteDataset saves
/// them).

#include <string>

#include "skerry/core/dataset.h"

namespace skerry {

struct EurocImportOptions {
  std::string imu_file = "imu0_data.csv";
  std::string imu_config_file = "imu0_sensor.yaml";
  /// EuRoC ground truth `t[ns],p,q(w,x,y,z),v,bg,ba`.
  std::string groundtruth_file = "V1_01_easy.csv";
  /// The Vicon room is taken as local ENU (its z is up; its x is not known to point east) at
  /// this arbitrary origin, so that GNSS can be simulated on top of the recording.
  GeoOrigin origin{47.6, 9.4, 400.0};
};

/// EuRoC MAV (ASL format, flattened into one folder): IMU samples in the IMU frame, T_BS as the
/// IMU -> body extrinsic, body = the Vicon body, ground truth as poses and full truth states.
/// No GNSS (has_gnss false). Throws InputError on malformed input.
Dataset ImportEuroc(const std::string& euroc_dir,
                    const EurocImportOptions& options = EurocImportOptions());

/// Clearpath Husky from robot_localization's test1.bag, decoded to CSV (`imu_data.csv`,
/// `fix.csv`): IMU (~30 Hz) and GNSS (~2.5 Hz) on the header stamps, origin at the first valid
/// fix, no ground truth. Exact duplicate rows (same stamp and content) are dropped with a
/// warning; any other non-increasing stamp is an InputError.
Dataset ImportHusky(const std::string& husky_dir);

}  // namespace skerry
