#pragma once
// Shared by the fuzz targets: each turns libFuzzer's bytes into the file(s) a reader of outside
// input opens, calls the reader, and accepts only one way of failing: skerry::InputError (a clear
// error naming the file, line and field). Any other exception escapes and aborts the process,
// which libFuzzer reports as a crash, as it does for sanitizer reports, timeouts and leaks.

#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

namespace skerry::fuzz {

/// A scratch folder of this process, emptied for every input.
inline std::string Scratch() {
  static const std::string dir = [] {
    const char* base = std::getenv("SKERRY_FUZZ_TMP");
    const std::string d = std::string(base != nullptr ? base : "/tmp") + "/skerry-fuzz-" +
                          std::to_string(static_cast<long>(::getpid()));
    return d;
  }();
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

/// An input the reader refused, the one accepted way to fail; with SKERRY_FUZZ_VERBOSE set the
/// message is printed (to see what a seed or a crash input trips over).
inline void Rejected(const std::exception& e) {
  if (std::getenv("SKERRY_FUZZ_VERBOSE") != nullptr)
    std::fprintf(stderr, "rejected: %s\n", e.what());
}

inline void Write(const std::string& path, const std::string& text) {
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  std::ofstream(path, std::ios::binary) << text;
}

inline std::string Bytes(const uint8_t* data, size_t size) {
  return std::string(reinterpret_cast<const char*>(data), size);
}

/// Splits the input at the first "\n====\n" (the separator the seed files use) into two files'
/// contents; without one, the second part is empty.
inline std::pair<std::string, std::string> SplitTwo(const std::string& in) {
  const std::string sep = "\n====\n";
  const size_t at = in.find(sep);
  if (at == std::string::npos) return {in, ""};
  return {in.substr(0, at + 1), in.substr(at + sep.size())};
}

/// A small valid dataset's files, replaced one at a time by the fuzzer's bytes.
inline const char* kDatasetYaml =
    "name: fuzz\n"
    "origin: {lat_deg: 47.6, lon_deg: 9.4, height_m: 400.0}\n"
    "sensors:\n"
    "  imu:\n"
    "    file: imu.csv\n"
    "    rate_hz: 100\n"
    "    T_b_i: {q_xyzw: [0, 0, 0, 1], p_m: [0, 0, 0]}\n"
    "    gyro_noise_density_rad_s_sqrt_hz: 1.7e-4\n"
    "    accel_noise_density_m_s2_sqrt_hz: 2.0e-3\n"
    "    gyro_bias_random_walk_rad_s2_sqrt_hz: 2.0e-5\n"
    "    accel_bias_random_walk_m_s3_sqrt_hz: 3.0e-3\n"
    "  gnss:\n"
    "    file: gnss.csv\n"
    "    lever_arm_b_m: [0, 0, 1]\n"
    "  pose_fixes:\n"
    "    file: pose_fixes.csv\n"
    "    T_b_s: {q_xyzw: [0, 0, 0, 1], p_m: [0, 0, 0]}\n"
    "  lidar_top:\n"
    "    scans: scans\n"
    "    file: lidar.csv\n"
    "    T_b_l: {q_xyzw: [0, 0, 0, 1], p_m: [0, 0, 1]}\n"
    "groundtruth: groundtruth.tum\n";
/// lidar.csv lists files of scans/, which the harness creates (empty: only their presence is
/// read with the dataset).
inline const char* kLidarCsv = "t,file\n0.01,a.pcd\n0.02,b.pcd\n";
inline const char* kImuCsv =
    "t,wx,wy,wz,ax,ay,az\n"
    "0.00,0.001,0.002,0.003,0.1,0.2,9.8\n"
    "0.01,0.001,0.002,0.003,0.1,0.2,9.8\n"
    "0.02,0.001,0.002,0.003,0.1,0.2,9.8\n";
inline const char* kGnssCsv =
    "t,lat,lon,height,sigma_e,sigma_n,sigma_u\n"
    "0.005,47.6,9.4,400.0,0.5,0.5,1.0\n"
    "0.015,47.6000001,9.4,400.0,0.5,0.5,1.0\n";
inline const char* kPoseFixesCsv =
    "t,kind,east,north,up,heading_deg,cov_ee,cov_en,cov_eu,cov_eh,cov_nn,cov_nu,cov_nh,cov_uu,"
    "cov_uh,cov_hh\n"
    "0.01,en,1,2,0,0,0.25,0,0,0,0.25,0,0,1,0,1\n";
inline const char* kGroundTruthTum =
    "# t x y z qx qy qz qw\n"
    "0.0 0 0 0 0 0 0 1\n"
    "0.01 0.01 0 0 0 0 0 1\n";

}  // namespace skerry::fuzz
