// Fuzz target for the importers of outside recordings: the first byte picks EuRoC (the bytes are
// its IMU CSV, or its ground-truth CSV when they start with that file's header) or Husky (its
// IMU CSV, or its GPS CSV when they start with that file's header); the recording's other files
// stay small and valid.

#include "fuzz_files.h"
#include "skerry/core/input_error.h"
#include "skerry/io/importers.h"

namespace {

const char* kEurocImu =
    "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],a_RS_S_x [m "
    "s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n"
    "1403715273262142976,-0.099,0.142,0.024,8.17,-1.98,-2.37\n"
    "1403715273267142912,-0.098,0.139,0.021,8.13,-1.98,-2.39\n";
const char* kEurocSensor =
    "sensor_type: imu\n"
    "T_BS:\n"
    "  cols: 4\n"
    "  rows: 4\n"
    "  data: [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0]\n"
    "rate_hz: 200\n"
    "gyroscope_noise_density: 1.6968e-04\n"
    "gyroscope_random_walk: 1.9393e-05\n"
    "accelerometer_noise_density: 2.0000e-3\n"
    "accelerometer_random_walk: 3.0000e-3\n";
const char* kEurocTruth =
    "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], "
    "q_RS_z [], v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], v_RS_R_z [m s^-1], b_w_RS_S_x [rad s^-1], "
    "b_w_RS_S_y [rad s^-1], b_w_RS_S_z [rad s^-1], b_a_RS_S_x [m s^-2], b_a_RS_S_y [m s^-2], "
    "b_a_RS_S_z [m s^-2]\n"
    "1403715273262142976,0.878895,2.1834,0.948427,0.069433,-0.824237,-0.106942,-0.551702,"
    "0.00157587,0.00179383,-0.00231615,-0.00224703,0.0215352,0.0770299,-0.0180115,0.0659796,"
    "0.0309774\n";
const char* kHuskyImu =
    "bag_time,stamp,frame,qx,qy,qz,qw,wx,wy,wz,ax,ay,az\n"
    "1432235498.025043011,1432235497.988949,imu_link,0.444,-0.545,-0.551,0.450,0.0255,-0.0108,"
    "-0.0151,0.543,9.608,0.206\n"
    "1432235498.058580399,1432235498.0222695,imu_link,0.444,-0.545,-0.551,0.450,0.0013,-0.0054,"
    "-0.0143,-0.413,9.766,0.512\n";
const char* kHuskyFix =
    "bag_time,stamp,frame,status,service,lat,lon,alt,cov_xx,cov_yy,cov_zz,cov_type\n"
    "1432235498.039331675,1432235498.03909,/gps,1,1,42.375812,-71.147394,7.3,0.81,0.81,3.24,1\n";

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace skerry::fuzz;
  if (size == 0) return 0;
  const std::string dir = Scratch();
  const int pick = data[0] % 2;
  const std::string text = Bytes(data + 1, size - 1);
  try {
    if (pick == 0) {
      const std::string imu0 = dir + "/mav0/imu0";
      Write(imu0 + "/sensor.yaml", kEurocSensor);
      const bool truth_fuzzed = text.rfind("#timestamp, p_RS_R_x", 0) == 0;
      Write(imu0 + "/data.csv", truth_fuzzed ? kEurocImu : text);
      Write(dir + "/mav0/state_groundtruth_estimate0/data.csv", truth_fuzzed ? text : kEurocTruth);
      skerry::ImportEuroc(dir);
    } else {
      const bool fix_fuzzed = text.rfind("bag_time,stamp,frame,status", 0) == 0;
      Write(dir + "/imu_data.csv", fix_fuzzed ? kHuskyImu : text);
      Write(dir + "/fix.csv", fix_fuzzed ? text : kHuskyFix);
      skerry::ImportHusky(dir);
    }
  } catch (const skerry::InputError& e) {
    Rejected(e);
  }
  return 0;
}
