#pragma once
/// \file
/// Importers that turn public recordings into skerry datasets (in memory; WriteDataset saves
/// them).

#include <cstdint>
#include <string>

#include "skerry/core/geodesy.h"
#include "skerry/io/dataset.h"

namespace skerry {

/// Where the EuRoC MAV datasets were recorded: ETH Zurich (the machine hall and the Vicon room).
/// Only the Earth's gravity there and simulated GNSS depend on it.
inline constexpr GeoOrigin kEurocOrigin{47.3764, 8.5481, 500.0};

/// EuRoC MAV (Burri et al., IJRR 2016) as ASL publishes it, any sequence: `dir` is the sequence
/// folder holding `mav0/` (the unpacked "ASL Dataset Format" zip, e.g. `MH_01_easy/`) or `mav0/`
/// itself, with `imu0/data.csv` (`#timestamp [ns],w_RS_S_x [rad s^-1],...`), `imu0/sensor.yaml`
/// (T_BS, rate, noise densities) and, when present, `state_groundtruth_estimate0/data.csv` (the
/// 17 columns `#timestamp, p_RS_R_x [m], ..., q_RS_w [], ..., b_a_RS_S_z [m s^-2]`); the
/// dataset is named euroc_<sequence folder>. Also reads the flattened copy in
/// ../shared/data/euroc_v1_01 (`imu0_data.csv`, `imu0_sensor.yaml` and one ground-truth CSV with
/// the short header `#time(ns),px,...`), named after that CSV.
///
/// IMU samples in the IMU frame, T_BS as the IMU -> body extrinsic, body = EuRoC's body frame,
/// ground truth as poses and full truth states. The Vicon / Leica world has z up but its azimuth
/// is unknown, so the Earth's rotation cannot be put into it: the dataset says earth: flat, with
/// the WGS84 normal gravity at kEurocOrigin (its 15 deg/h are left to the gyro bias, below the
/// ADIS16448's in-run bias stability). No GNSS (has_gnss false). Throws InputError naming the
/// folder and what it lacks, or the file, line and field of bad content.
Dataset ImportEuroc(const std::string& dir);

/// Position fixes made from a recording's ground truth, for one without GNSS (EuRoC): every
/// 1/rate_hz from the first ground-truth pose (for duration_s, or all of it when 0), the truth
/// position interpolated there plus white noise of sigma_m per axis, carrying sigma_m. The noise
/// comes from a 64-bit Mersenne twister through Box-Muller, the same sequence on every standard
/// library. Replaces data->gnss_fixes; the antenna is the body origin.
void AddFixesFromGroundTruth(
    double rate_hz, double sigma_m, std::uint64_t seed, Dataset* data, double duration_s = 0.0);

/// Clearpath Husky from robot_localization's test1.bag, decoded to CSV (`imu_data.csv`,
/// `fix.csv`): IMU (~30 Hz) and GNSS (~2.5 Hz) on the header stamps, origin at the first valid
/// fix, no ground truth. Exact duplicate rows (same stamp and content) are dropped with a
/// warning; any other non-increasing stamp is an InputError.
Dataset ImportHusky(const std::string& husky_dir);

}  // namespace skerry
