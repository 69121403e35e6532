#include "skerry/io/dataset.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "core/test_util.h"
#include "io/dataset_folder_test.h"
#include "skerry/core/heading.h"
#include "skerry/core/so3.h"

namespace skerry {
namespace {

using testing::ExpectInputError;
using testing::FreshDir;
using testing::ReadLines;
using testing::WriteLines;
using testing::WriteText;

constexpr TimeNs kT0 = 1403715273262142976LL;  // needs all 19 digits: doubles would lose ns

Dataset MakeDataset() {
  Dataset d;
  d.name = "harbour: test";  // needs quoting in YAML
  d.origin = {47.6, 9.4, 440.123456789};
  d.imu.rate_hz = 200.0;
  d.imu.q_b_i = ExpQ(Eigen::Vector3d(0.01, -0.02, 3.0));
  d.imu.p_b_i = Eigen::Vector3d(0.1, -0.2, 0.3);
  d.imu.noise.gyro_noise_density_rad_s_sqrt_hz = 1.7e-4;
  d.imu.noise.accel_noise_density_m_s2_sqrt_hz = 2.1e-3;
  d.imu.noise.gyro_bias_random_walk_rad_s2_sqrt_hz = 1.9393e-5;
  d.imu.noise.accel_bias_random_walk_m_s3_sqrt_hz = 3.0e-3;
  d.imu.gyro_bias_prior_sigma_rad_s = 2e-3;
  d.imu.accel_bias_prior_sigma_m_s2 = 0.1;
  d.imu.gyro_scale_factor_sigma_ppm = 50.0;
  d.imu.gyro_misalignment_sigma_mrad = 0.1;
  d.earth.kind = EarthKind::kFlat;
  d.earth.gravity_m_s2 = 9.81;
  for (int k = 0; k < 20; ++k) {
    ImuSample s;
    s.t_ns = kT0 + k * 5000001LL;
    s.gyro_rad_s = Eigen::Vector3d(0.1 / 3.0, -k * 1e-3, std::sqrt(2.0));
    s.accel_m_s2 = Eigen::Vector3d(0.2, std::exp(-k), 9.80665 + 1e-12 * k);
    d.imu_samples.push_back(s);
  }
  d.has_gnss = true;
  d.gnss.p_b_g = Eigen::Vector3d(0.0, 0.5, 2.0);
  d.gnss.baseline_b = Eigen::Vector3d(0.0, 1.0, 0.0);
  const LocalFrame frame(d.origin);
  for (int k = 0; k < 4; ++k) {
    GnssFix f;
    f.t_ns = kT0 + k * 25000000LL;
    f.lat_deg = 47.6 + 1e-5 * k;
    f.lon_deg = 9.4 - 2e-5 * k;
    f.height_m = 440.5 + 0.1 * k;
    f.sigma_enu_m = Eigen::Vector3d(0.5, 0.6, 1.2);
    if (k % 2 == 1) {
      f.has_heading = true;
      f.heading_deg = 123.456 + k;
      f.sigma_heading_deg = 0.3;
    }
    f.p_w = frame.ToEnu(f.lat_deg, f.lon_deg, f.height_m);
    d.gnss_fixes.push_back(f);
  }
  for (int k = 0; k < 3; ++k) {
    NavState s;
    s.t_ns = kT0 + k * 33333333LL;
    s.p_w_b = Eigen::Vector3d(k, 2.0 * k, -0.1);
    s.q_w_b = QuaternionFromRollPitchHeading(0.01 * k, 0.02, 1.0 + k);
    s.v_w = Eigen::Vector3d(1.0, 0.5, 0.0);
    s.bg = Eigen::Vector3d(1e-4, -2e-4, 3e-4);
    s.ba = Eigen::Vector3d(0.01, 0.02, -0.03);
    d.truth_states.push_back(s);
    d.groundtruth.push_back({s.t_ns, s.p_w_b, s.q_w_b});
  }
  d.events.push_back({kT0 + 10, kT0 + 2000000000LL, "outage", Eigen::Vector3d::Zero()});
  d.events.push_back({kT0 + 3000000000LL, kT0 + 4000000000LL, "jump", Eigen::Vector3d(5, -3, 0.5)});
  return d;
}

void ExpectQuaternionEq(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  EXPECT_NEAR(a.angularDistance(b), 0.0, 1e-15);
}

TEST(DatasetTest, RoundTrip) {
  const std::string dir = FreshDir("dataset_round_trip");
  const Dataset d = MakeDataset();
  WriteDataset(d, dir);
  const Dataset b = LoadDataset(dir);
  EXPECT_EQ(b.name, d.name);
  EXPECT_EQ(b.directory, dir);
  EXPECT_EQ(b.origin.lat_deg, d.origin.lat_deg);
  EXPECT_EQ(b.origin.lon_deg, d.origin.lon_deg);
  EXPECT_EQ(b.origin.height_m, d.origin.height_m);
  EXPECT_EQ(b.imu.rate_hz, d.imu.rate_hz);
  ExpectQuaternionEq(b.imu.q_b_i, d.imu.q_b_i);
  EXPECT_EQ(b.imu.p_b_i, d.imu.p_b_i);
  EXPECT_EQ(b.imu.noise.gyro_noise_density_rad_s_sqrt_hz, 1.7e-4);
  EXPECT_EQ(b.imu.noise.accel_noise_density_m_s2_sqrt_hz, 2.1e-3);
  EXPECT_EQ(b.imu.noise.gyro_bias_random_walk_rad_s2_sqrt_hz, 1.9393e-5);
  EXPECT_EQ(b.imu.noise.accel_bias_random_walk_m_s3_sqrt_hz, 3.0e-3);
  EXPECT_EQ(b.imu.gyro_bias_prior_sigma_rad_s, 2e-3);
  EXPECT_EQ(b.imu.accel_bias_prior_sigma_m_s2, 0.1);
  EXPECT_EQ(b.imu.gyro_scale_factor_sigma_ppm, 50.0);
  EXPECT_EQ(b.imu.gyro_misalignment_sigma_mrad, 0.1);
  EXPECT_EQ(b.earth.kind, EarthKind::kFlat);
  EXPECT_EQ(b.earth.gravity_m_s2, 9.81);
  ASSERT_EQ(b.imu_samples.size(), d.imu_samples.size());
  for (std::size_t k = 0; k < d.imu_samples.size(); ++k) {
    EXPECT_EQ(b.imu_samples[k].t_ns, d.imu_samples[k].t_ns);
    EXPECT_EQ(b.imu_samples[k].gyro_rad_s, d.imu_samples[k].gyro_rad_s);
    EXPECT_EQ(b.imu_samples[k].accel_m_s2, d.imu_samples[k].accel_m_s2);
  }
  ASSERT_TRUE(b.has_gnss);
  EXPECT_EQ(b.gnss.p_b_g, d.gnss.p_b_g);
  EXPECT_EQ(b.gnss.baseline_b, d.gnss.baseline_b);
  ASSERT_EQ(b.gnss_fixes.size(), d.gnss_fixes.size());
  for (std::size_t k = 0; k < d.gnss_fixes.size(); ++k) {
    const GnssFix& x = b.gnss_fixes[k];
    const GnssFix& y = d.gnss_fixes[k];
    EXPECT_EQ(x.t_ns, y.t_ns);
    EXPECT_EQ(x.lat_deg, y.lat_deg);
    EXPECT_EQ(x.lon_deg, y.lon_deg);
    EXPECT_EQ(x.height_m, y.height_m);
    EXPECT_EQ(x.sigma_enu_m, y.sigma_enu_m);
    EXPECT_EQ(x.has_heading, y.has_heading);
    EXPECT_EQ(x.heading_deg, y.heading_deg);
    EXPECT_EQ(x.sigma_heading_deg, y.sigma_heading_deg);
    EXPECT_LT((x.p_w - y.p_w).norm(), 1e-9);
  }
  EXPECT_GT(b.gnss_fixes[3].p_w.norm(), 1.0);  // p_w really is filled on load
  ASSERT_EQ(b.groundtruth.size(), d.groundtruth.size());
  ASSERT_EQ(b.truth_states.size(), d.truth_states.size());
  for (std::size_t k = 0; k < d.truth_states.size(); ++k) {
    const NavState& x = b.truth_states[k];
    const NavState& y = d.truth_states[k];
    EXPECT_EQ(x.t_ns, y.t_ns);
    EXPECT_EQ(x.p_w_b, y.p_w_b);
    ExpectQuaternionEq(x.q_w_b, y.q_w_b);
    EXPECT_EQ(x.v_w, y.v_w);
    EXPECT_EQ(x.bg, y.bg);
    EXPECT_EQ(x.ba, y.ba);
    EXPECT_EQ(b.groundtruth[k].t_ns, d.groundtruth[k].t_ns);
    EXPECT_EQ(b.groundtruth[k].p_w_b, d.groundtruth[k].p_w_b);
  }
  ASSERT_EQ(b.events.size(), 2u);
  EXPECT_EQ(b.events[1].t_start_ns, d.events[1].t_start_ns);
  EXPECT_EQ(b.events[1].t_end_ns, d.events[1].t_end_ns);
  EXPECT_EQ(b.events[1].type, "jump");
  EXPECT_EQ(b.events[1].offset_enu_m, d.events[1].offset_enu_m);
  EXPECT_EQ(b.events[0].type, "outage");
}

// What a live system holds at t: every stream's prefix up to and including t, events that started
// by then cut at t, and everything else unchanged.
TEST(DatasetTest, DatasetUntilKeepsWhatArrivedByThen) {
  const Dataset d = MakeDataset();
  const TimeNs t = kT0 + 50000000LL;  // the third fix, between IMU samples 9 and 10
  const Dataset cut = DatasetUntil(d, t);
  ASSERT_EQ(cut.imu_samples.size(), 10u);
  EXPECT_EQ(cut.imu_samples.back().t_ns, d.imu_samples[9].t_ns);
  ASSERT_EQ(cut.gnss_fixes.size(), 3u);
  EXPECT_EQ(cut.gnss_fixes.back().t_ns, t);  // a fix at exactly t is kept
  EXPECT_EQ(cut.truth_states.size(), 2u);
  EXPECT_EQ(cut.groundtruth.size(), 2u);
  ASSERT_EQ(cut.events.size(), 1u);  // the outage has started, the jump has not
  EXPECT_EQ(cut.events[0].type, "outage");
  EXPECT_EQ(cut.events[0].t_start_ns, d.events[0].t_start_ns);
  EXPECT_EQ(cut.events[0].t_end_ns, t);
  EXPECT_EQ(cut.name, d.name);
  EXPECT_EQ(cut.imu.rate_hz, d.imu.rate_hz);
  EXPECT_TRUE(cut.gnss.p_b_g.isApprox(d.gnss.p_b_g));
  // Before everything: nothing; after everything: all of it.
  EXPECT_TRUE(DatasetUntil(d, kT0 - 1).imu_samples.empty());
  const Dataset all = DatasetUntil(d, kT0 + 10000000000LL);
  EXPECT_EQ(all.imu_samples.size(), d.imu_samples.size());
  EXPECT_EQ(all.events.size(), 2u);
  EXPECT_EQ(all.events[1].t_end_ns, d.events[1].t_end_ns);
}

TEST(DatasetTest, MinimalDatasetWithoutOptionalParts) {
  const std::string dir = FreshDir("dataset_minimal");
  Dataset d = MakeDataset();
  d.has_gnss = false;
  d.gnss_fixes.clear();
  d.groundtruth.clear();
  d.truth_states.clear();
  d.events.clear();
  for (GnssFix& f : d.gnss_fixes) f.has_heading = false;
  WriteDataset(d, dir);
  const Dataset b = LoadDataset(dir);
  EXPECT_FALSE(b.has_gnss);
  EXPECT_TRUE(b.gnss_fixes.empty());
  EXPECT_TRUE(b.groundtruth.empty());
  EXPECT_TRUE(b.truth_states.empty());
  EXPECT_TRUE(b.events.empty());
  EXPECT_EQ(b.imu_samples.size(), d.imu_samples.size());
}

// A camera's images inside the dataset folder are named relative to it, so the folder can be
// moved as a whole; a folder elsewhere stays an absolute path.
TEST(DatasetTest, FoldersInsideTheDatasetMoveWithIt) {
  namespace fs = std::filesystem;
  const std::string dir = FreshDir("dataset_moves");
  const std::string elsewhere = FreshDir("dataset_moves_elsewhere_images");
  fs::remove_all(dir + "_moved");
  Dataset d = MakeDataset();
  for (const std::string& folder : {dir + "/images", elsewhere}) {
    fs::create_directories(folder);
    std::ofstream(folder + "/000000.png") << "not read here";
  }
  for (const std::string& name : {std::string("camera"), std::string("camera_aft")}) {
    CameraConfig c;
    c.name = name;
    c.image_dir = name == "camera" ? dir + "/images" : elsewhere;
    c.file = name + ".csv";
    c.width_px = 640;
    c.height_px = 480;
    c.fx = c.fy = 500.0;
    c.cx = 320.0;
    c.cy = 240.0;
    d.cameras.push_back(c);
    d.camera_frames.push_back({{kT0, "000000.png"}});
  }
  WriteDataset(d, dir);
  std::ifstream in(dir + "/dataset.yaml");
  const std::string yaml((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(yaml.find("images: images\n"), std::string::npos) << yaml;
  EXPECT_NE(yaml.find("images: " + fs::weakly_canonical(elsewhere).string() + "\n"),
            std::string::npos)
      << yaml;
  fs::rename(dir, dir + "_moved");
  const Dataset b = LoadDataset(dir + "_moved");
  ASSERT_EQ(b.cameras.size(), 2u);
  EXPECT_TRUE(fs::equivalent(b.cameras[0].image_dir, dir + "_moved/images"));
  EXPECT_TRUE(fs::equivalent(b.cameras[1].image_dir, elsewhere));
}

// A hand-written dataset.yaml so that the expected line numbers are visible here.
constexpr char kYaml[] =
    "name: harbour\n"                                     // 1
    "origin:\n"                                           // 2
    "  lat_deg: 47.60\n"                                  // 3
    "  lon_deg: 9.40\n"                                   // 4
    "  height_m: 440.0\n"                                 // 5
    "sensors:\n"                                          // 6
    "  imu:\n"                                            // 7
    "    file: imu.csv\n"                                 // 8
    "    rate_hz: 200\n"                                  // 9
    "    T_b_i:\n"                                        // 10
    "      q_xyzw: [0, 0, 0, 1]\n"                        // 11
    "      p_m: [0.0, 0.0, 0.0]\n"                        // 12
    "    gyro_noise_density_rad_s_sqrt_hz: 1.7e-4\n"      // 13
    "    accel_noise_density_m_s2_sqrt_hz: 2.0e-3\n"      // 14
    "    gyro_bias_random_walk_rad_s2_sqrt_hz: 2.0e-5\n"  // 15
    "    accel_bias_random_walk_m_s3_sqrt_hz: 3.0e-3\n"   // 16
    "  gnss:\n"                                           // 17
    "    file: gnss.csv\n"                                // 18
    "    lever_arm_b_m: [0.0, 0.0, 2.0]\n"                // 19
    "groundtruth: groundtruth.tum\n";                     // 20

class DatasetErrorTest : public testing::DatasetFolderTest {
 protected:
  void SetUp() override {
    MakeDir("dataset_errors_");
    WriteText(dir_ + "/dataset.yaml", kYaml);
    WriteText(dir_ + "/imu.csv",
              "t,wx,wy,wz,ax,ay,az\n"
              "0.000,0,0,0,0,0,9.8\n"
              "0.005,0,0,0,0,0,9.8\n"
              "0.010,0,0,0,0,0,9.8\n"
              "0.015,0,0,0,0,0,9.8\n");
    WriteText(dir_ + "/gnss.csv",
              "t,lat,lon,height,sigma_e,sigma_n,sigma_u\n"
              "0.0,47.6,9.4,440,0.5,0.5,1\n"
              "1.0,47.6,9.4,440,0.5,0.5,1\n");
    WriteText(dir_ + "/groundtruth.tum", "# t x y z qx qy qz qw\n0.0 0 0 0 0 0 0 1\n");
  }
};

TEST_F(DatasetErrorTest, ValidFolderLoads) {
  const Dataset d = LoadDataset(dir_);
  EXPECT_EQ(d.imu_samples.size(), 4u);
  EXPECT_EQ(d.imu_samples[1].t_ns, 5000000);
  EXPECT_EQ(d.gnss_fixes.size(), 2u);
  EXPECT_EQ(d.groundtruth.size(), 1u);
  EXPECT_EQ(d.imu.gyro_bias_prior_sigma_rad_s, ImuConfig().gyro_bias_prior_sigma_rad_s);
  // The gyro's datasheet calibration sigmas are optional: absent, nothing is stated.
  EXPECT_FALSE(d.imu.has_gyro_calibration_prior());
}

TEST_F(DatasetErrorTest, NegativeGyroCalibrationSigma) {
  ReplaceLine("dataset.yaml", 16,
              "    accel_bias_random_walk_m_s3_sqrt_hz: 3.0e-3\n"
              "    gyro_misalignment_sigma_mrad: -0.1");
  ExpectError("dataset.yaml", 17, "sensors.imu.gyro_misalignment_sigma_mrad");
  ReplaceLine("dataset.yaml", 17, "    gyro_scale_factor_sigma_ppm: .nan");
  ExpectError("dataset.yaml", 17, "sensors.imu.gyro_scale_factor_sigma_ppm");
}

TEST_F(DatasetErrorTest, TruncatedCsvLine) {
  ReplaceLine("imu.csv", 3, "0.005,0,0,0,0");
  ExpectError("imu.csv", 3, "ay");
}

TEST_F(DatasetErrorTest, NaNInCsv) {
  ReplaceLine("gnss.csv", 3, "1.0,47.6,9.4,440,0.5,nan,1");
  ExpectError("gnss.csv", 3, "sigma_n");
}

TEST_F(DatasetErrorTest, InfInCsv) {
  ReplaceLine("imu.csv", 4, "0.010,0,inf,0,0,0,9.8");
  ExpectError("imu.csv", 4, "wy");
}

TEST_F(DatasetErrorTest, NonNumericTextInCsv) {
  ReplaceLine("imu.csv", 2, "0.000,0,0,zero,0,0,9.8");
  ExpectError("imu.csv", 2, "wz");
}

TEST_F(DatasetErrorTest, NonIncreasingTime) {
  ReplaceLine("imu.csv", 4, "0.005,0,0,0,0,0,9.8");
  ExpectError("imu.csv", 4, "t");
}

TEST_F(DatasetErrorTest, DecreasingTimeInGnss) {
  ReplaceLine("gnss.csv", 3, "-1.0,47.6,9.4,440,0.5,0.5,1");
  ExpectError("gnss.csv", 3, "t");
}

TEST_F(DatasetErrorTest, MissingYamlKey) {
  // Reported on the line where the enclosing mapping (sensors.imu) starts.
  ReplaceLine("dataset.yaml", 13, "");
  ExpectError("dataset.yaml", 8, "sensors.imu.gyro_noise_density_rad_s_sqrt_hz");
}

TEST_F(DatasetErrorTest, MissingSection) {
  std::vector<std::string> lines = ReadLines(dir_ + "/dataset.yaml");
  lines.erase(lines.begin() + 1, lines.begin() + 5);  // origin
  WriteLines(dir_ + "/dataset.yaml", lines);
  ExpectError("dataset.yaml", 1, "origin");
}

TEST_F(DatasetErrorTest, UnknownSensor) {
  ReplaceLine("dataset.yaml", 17, "  sonar:");
  ExpectError("dataset.yaml", 17, "sensors.sonar");
}

TEST_F(DatasetErrorTest, UnknownKeyInSensor) {
  ReplaceLine("dataset.yaml", 9, "    rate_hzz: 200");
  ExpectError("dataset.yaml", 9, "sensors.imu.rate_hzz");
}

// The samples come every 5 ms: 200 Hz as declared. Declared at 100 or 400 Hz they are refused,
// naming the key's line and both rates; within 25 % (a clock's jitter, a rounded rate) they load.
TEST_F(DatasetErrorTest, ImuRateAgainstTheSamples) {
  for (const char* wrong : {"100", "400", "1e6"}) {
    SCOPED_TRACE(wrong);
    ReplaceLine("dataset.yaml", 9, std::string("    rate_hz: ") + wrong);
    ExpectError("dataset.yaml", 9, "sensors.imu.rate_hz");
    try {
      LoadDataset(dir_);
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(
                    "declares " + std::string(wrong == std::string("1e6") ? "1e+06" : wrong) +
                    " Hz, but the samples of "),
                std::string::npos)
          << e.what();
      EXPECT_NE(std::string(e.what()).find("come at 200 Hz (median interval 0.005 s)"),
                std::string::npos)
          << e.what();
    }
  }
  for (const char* close : {"170", "200", "240"}) {
    ReplaceLine("dataset.yaml", 9, std::string("    rate_hz: ") + close);
    EXPECT_NO_THROW(LoadDataset(dir_)) << close;
  }
  // One gap does not move the median.
  ReplaceLine("dataset.yaml", 9, "    rate_hz: 200");
  ReplaceLine("imu.csv", 5, "0.500,0,0,0,0,0,9.8");
  EXPECT_NO_THROW(LoadDataset(dir_));
}

TEST_F(DatasetErrorTest, NonNumericYamlValue) {
  ReplaceLine("dataset.yaml", 9, "    rate_hz: fast");
  ExpectError("dataset.yaml", 9, "sensors.imu.rate_hz");
}

TEST_F(DatasetErrorTest, NonFiniteYamlValue) {
  ReplaceLine("dataset.yaml", 5, "  height_m: .nan");
  ExpectError("dataset.yaml", 5, "origin.height_m");
}

TEST_F(DatasetErrorTest, WrongListLength) {
  ReplaceLine("dataset.yaml", 19, "    lever_arm_b_m: [0.0, 2.0]");
  ExpectError("dataset.yaml", 19, "sensors.gnss.lever_arm_b_m");
}

TEST_F(DatasetErrorTest, NonUnitQuaternionInYaml) {
  ReplaceLine("dataset.yaml", 11, "      q_xyzw: [0, 0, 0.5, 1]");
  ExpectError("dataset.yaml", 11, "sensors.imu.T_b_i.q_xyzw");
}

TEST_F(DatasetErrorTest, YamlSyntaxError) {
  ReplaceLine("dataset.yaml", 9, "    rate_hz: [200");
  try {
    LoadDataset(dir_);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_GT(e.line(), 0) << e.what();
  }
}

TEST_F(DatasetErrorTest, MissingDataFile) {
  std::filesystem::remove(dir_ + "/gnss.csv");
  ExpectError("gnss.csv", 0, "");
}

TEST_F(DatasetErrorTest, BadHeader) {
  ReplaceLine("imu.csv", 1, "t,wx,wy,wz,ax,ay");
  ExpectError("imu.csv", 1, "az");
}

TEST_F(DatasetErrorTest, BadGroundTruth) {
  WriteText(dir_ + "/groundtruth.tum",
            "# t x y z qx qy qz qw\n0.0 0 0 0 0 0 0 1\n0.1 0 0 0 0 0 0 2\n");
  ExpectError("groundtruth.tum", 3, "qw");
}

TEST_F(DatasetErrorTest, HalfAHeading) {
  WriteText(dir_ + "/gnss.csv",
            "t,lat,lon,height,sigma_e,sigma_n,sigma_u,heading_deg,sigma_heading_deg\n"
            "0.0,47.6,9.4,440,0.5,0.5,1,10.0,0.5\n"
            "1.0,47.6,9.4,440,0.5,0.5,1,,\n"
            "2.0,47.6,9.4,440,0.5,0.5,1,12.0,\n");
  ExpectError("gnss.csv", 4, "sigma_heading_deg");
}

TEST_F(DatasetErrorTest, BadEvents) {
  WriteText(dir_ + "/events.csv",
            "t_start,t_end,type,de,dn,du\n1.0,2.0,outage,0,0,0\n3.0,4.0,spoof,0,0,0\n");
  ExpectError("events.csv", 3, "type");
}

TEST_F(DatasetErrorTest, BadTruthStates) {
  WriteText(dir_ + "/truth_states.csv",
            "t,px,py,pz,qx,qy,qz,qw,vx,vy,vz,bgx,bgy,bgz,bax,bay,baz\n"
            "0.0,0,0,0,0,0,0,1,0,0,0,0,0,0,0,0,0\n"
            "0.1,0,0,0,0,0,0,1,0,0,0,0,0,0,0,0\n");
  ExpectError("truth_states.csv", 3, "baz");
}

// The rows are reserved from a count of the file's lines before they are read: a last row cut
// short without its line end, or blank lines by the thousand, are still what they were (the cut
// row's line and column named; the blank lines skipped, the samples all there).
TEST_F(DatasetErrorTest, ReservedReadsKeepTheirErrorsAndRows) {
  WriteText(dir_ + "/imu.csv",
            "t,wx,wy,wz,ax,ay,az\n"
            "0.000,0,0,0,0,0,9.8\n"
            "0.005,0,0,0,0,0,9.8\n"
            "0.010,0,0,0");
  ExpectError("imu.csv", 4, "ax");
  std::string blank_lines(5000, '\n');
  WriteText(dir_ + "/imu.csv", "t,wx,wy,wz,ax,ay,az\n" + blank_lines + "0.000,0,0,0,0,0,9.8\n" +
                                   blank_lines + "0.005,0,0,0,0,0,9.8");
  const Dataset d = LoadDataset(dir_);
  ASSERT_EQ(d.imu_samples.size(), 2u);
  EXPECT_EQ(d.imu_samples[1].t_ns, 5000000);
  EXPECT_EQ(d.imu_samples[1].accel_m_s2.z(), 9.8);
  // No room kept for the 10,000 blank lines: at most one row per 7 bytes (7 columns).
  EXPECT_LT(d.imu_samples.capacity(), 2000u);
  WriteText(dir_ + "/groundtruth.tum", "# t x y z qx qy qz qw\n0.0 0 0 0 0 0 0 1\n0.1 0 0 0 0 0");
  ExpectError("groundtruth.tum", 3, "qz");
}

// kWithoutTruthStates: the estimators' load, everything but truth_states.csv (not even read: a
// bad one does not stop it); kAll still reads and checks it.
TEST_F(DatasetErrorTest, WithoutTruthStatesLoadsTheRest) {
  WriteText(dir_ + "/truth_states.csv",
            "t,px,py,pz,qx,qy,qz,qw,vx,vy,vz,bgx,bgy,bgz,bax,bay,baz\n"
            "0.0,0,0,0,0,0,0,1,0,0,0,0,0,0,0,0,0\n");
  EXPECT_EQ(LoadDataset(dir_).truth_states.size(), 1u);
  const Dataset d = LoadDataset(dir_, DatasetParts::kWithoutTruthStates);
  EXPECT_TRUE(d.truth_states.empty());
  EXPECT_EQ(d.imu_samples.size(), 4u);
  EXPECT_EQ(d.gnss_fixes.size(), 2u);
  EXPECT_EQ(d.groundtruth.size(), 1u);
  EXPECT_EQ(d.groundtruth_path, dir_ + "/groundtruth.tum");
  EXPECT_EQ(ReadTum(d.groundtruth_path).size(), 1u);
  ReplaceLine("truth_states.csv", 2, "0.0,0,0,0,0,0,0,1,0,0");
  EXPECT_NO_THROW(LoadDataset(dir_, DatasetParts::kWithoutTruthStates));
  ExpectError("truth_states.csv", 2, "vz");
}

}  // namespace
}  // namespace skerry
