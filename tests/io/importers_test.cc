#include "skerry/io/importers.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "core/test_util.h"

namespace skerry {
namespace {

namespace fs = std::filesystem;
using testing::ExpectInputError;
using testing::FreshDir;
using testing::ReadLines;
using testing::WriteLines;

const std::string kEurocDir = std::string(SKERRY_SHARED_DATA_DIR) + "/euroc_v1_01";
const std::string kHuskyDir = std::string(SKERRY_SHARED_DATA_DIR) + "/husky";

// Copies the files of `from` into a fresh scratch folder so a test can corrupt them.
std::string CopyOf(const std::string& from, const std::string& name) {
  const std::string dir = FreshDir(name);
  for (const auto& entry : fs::directory_iterator(from)) {
    fs::copy_file(entry.path(), fs::path(dir) / entry.path().filename());
    fs::permissions(fs::path(dir) / entry.path().filename(), fs::perms::owner_write,
                    fs::perm_options::add);  // shared data is read-only
  }
  return dir;
}

class EurocImportTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(kEurocDir)) GTEST_SKIP() << kEurocDir << " missing";
  }
};

TEST_F(EurocImportTest, ImportsRealData) {
  const Dataset d = ImportEuroc(kEurocDir);
  EXPECT_EQ(d.name, "euroc_V1_01_easy");
  EXPECT_FALSE(d.has_gnss);
  EXPECT_EQ(d.origin.lat_deg, kEurocOrigin.lat_deg);
  // The Vicon frame's azimuth is unknown: a flat Earth with Zurich's normal gravity.
  EXPECT_EQ(d.earth.kind, EarthKind::kFlat);
  EXPECT_NEAR(d.earth.gravity_m_s2, 9.8068, 1e-4);  // Somigliana at 47.38 N, 500 m
  ASSERT_EQ(d.imu_samples.size(), 29120u);
  EXPECT_EQ(d.imu_samples.front().t_ns, 1403715273262142976LL);
  EXPECT_EQ(d.imu_samples.back().t_ns, 1403715418857143040LL);
  EXPECT_EQ(d.imu_samples.front().gyro_rad_s.y(), 0.017453292519943295);
  EXPECT_EQ(d.imu_samples.front().accel_m_s2.x(), 9.0874956666666655);
  EXPECT_EQ(d.imu.rate_hz, 200.0);
  EXPECT_EQ(d.imu.noise.gyro_noise_density_rad_s_sqrt_hz, 1.6968e-04);
  EXPECT_EQ(d.imu.noise.gyro_bias_random_walk_rad_s2_sqrt_hz, 1.9393e-05);
  EXPECT_EQ(d.imu.noise.accel_noise_density_m_s2_sqrt_hz, 2.0e-3);
  EXPECT_EQ(d.imu.noise.accel_bias_random_walk_m_s3_sqrt_hz, 3.0e-3);
  EXPECT_NEAR(d.imu.q_b_i.angularDistance(Eigen::Quaterniond::Identity()), 0.0, 1e-12);
  EXPECT_EQ(d.imu.p_b_i, Eigen::Vector3d::Zero());

  ASSERT_EQ(d.truth_states.size(), 2895u);
  ASSERT_EQ(d.groundtruth.size(), 2895u);
  const NavState& s0 = d.truth_states.front();
  EXPECT_EQ(s0.t_ns, 1403715273262142976LL);
  EXPECT_EQ(s0.p_w_b, Eigen::Vector3d(0.878895, 2.1834, 0.948427));
  EXPECT_NEAR(s0.q_w_b.w(), 0.069433, 1e-5);  // file order is w, x, y, z
  EXPECT_NEAR(s0.q_w_b.x(), -0.824237, 1e-5);
  EXPECT_NEAR(s0.bg.z(), 0.0770299, 1e-12);
  EXPECT_NEAR(s0.ba.y(), 0.0659796, 1e-12);
  // Frames: at rest, the specific force rotated into the world is +g along up.
  const Eigen::Vector3d f_w = s0.q_w_b * (d.imu.q_b_i * (d.imu_samples.front().accel_m_s2 - s0.ba));
  EXPECT_LT((f_w - Eigen::Vector3d(0.0, 0.0, 9.81)).norm(), 0.3) << f_w.transpose();
  // The EuRoC gyro bias estimate matches the mean gyro at rest (first 0.5 s).
  Eigen::Vector3d mean_gyro = Eigen::Vector3d::Zero();
  for (int k = 0; k < 100; ++k) mean_gyro += d.imu_samples[k].gyro_rad_s / 100.0;
  EXPECT_LT((mean_gyro - s0.bg).norm(), 5e-3);
}

TEST_F(EurocImportTest, SurvivesWriteAndLoad) {
  const Dataset d = ImportEuroc(kEurocDir);
  const std::string dir = FreshDir("euroc_as_dataset");
  WriteDataset(d, dir);
  const Dataset b = LoadDataset(dir);
  ASSERT_EQ(b.imu_samples.size(), d.imu_samples.size());
  EXPECT_EQ(b.imu_samples[12345].t_ns, d.imu_samples[12345].t_ns);
  EXPECT_EQ(b.imu_samples[12345].accel_m_s2, d.imu_samples[12345].accel_m_s2);
  ASSERT_EQ(b.truth_states.size(), d.truth_states.size());
  EXPECT_EQ(b.truth_states[100].v_w, d.truth_states[100].v_w);
  EXPECT_EQ(b.groundtruth.size(), d.groundtruth.size());
}

TEST_F(EurocImportTest, ErrorsKeepLineNumbersOfTheOriginalFiles) {
  const std::string dir = CopyOf(kEurocDir, "euroc_bad");
  std::vector<std::string> yaml = ReadLines(dir + "/imu0_sensor.yaml");
  for (std::string& line : yaml) {
    if (line.rfind("gyroscope_noise_density", 0) == 0) line = "gyroscope_noise_density: lots";
  }
  WriteLines(dir + "/imu0_sensor.yaml", yaml);
  // Line 17 of the file even though the `%YAML:1.0` directive was stripped.
  ExpectInputError([&] { ImportEuroc(dir); }, "imu0_sensor.yaml", 17, "gyroscope_noise_density");

  fs::copy_file(kEurocDir + "/imu0_sensor.yaml", dir + "/imu0_sensor.yaml",
                fs::copy_options::overwrite_existing);
  std::vector<std::string> imu = ReadLines(dir + "/imu0_data.csv");
  imu[5] = imu[5].substr(0, imu[5].rfind(','));  // line 6 loses a_RS_S_z
  WriteLines(dir + "/imu0_data.csv", imu);
  ExpectInputError([&] { ImportEuroc(dir); }, "imu0_data.csv", 6, "a_RS_S_z [m s^-2]");
}

// The sequence as ASL publishes it (the "ASL Dataset Format" zip): <sequence>/mav0/imu0/data.csv
// with imu0/sensor.yaml, and state_groundtruth_estimate0/data.csv with its original 17-column
// header. Built here from the real V1_01 files; any sequence name.
std::string AslLayout(const std::string& sequence) {
  const std::string root = FreshDir("euroc_asl") + "/" + sequence;
  const fs::path mav0 = fs::path(root) / "mav0";
  fs::create_directories(mav0 / "imu0");
  fs::create_directories(mav0 / "state_groundtruth_estimate0");
  fs::copy_file(kEurocDir + "/imu0_data.csv", mav0 / "imu0" / "data.csv");
  fs::copy_file(kEurocDir + "/imu0_sensor.yaml", mav0 / "imu0" / "sensor.yaml");
  std::vector<std::string> gt = ReadLines(kEurocDir + "/V1_01_easy.csv");
  gt[0] =
      "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], "
      "q_RS_z [], v_RS_R_x [m s^-1], v_RS_R_y [m s^-1], v_RS_R_z [m s^-1], b_w_RS_S_x [rad s^-1], "
      "b_w_RS_S_y [rad s^-1], b_w_RS_S_z [rad s^-1], b_a_RS_S_x [m s^-2], b_a_RS_S_y [m s^-2], "
      "b_a_RS_S_z [m s^-2]";
  WriteLines((mav0 / "state_groundtruth_estimate0" / "data.csv").string(), gt);
  for (const auto& p : fs::recursive_directory_iterator(root)) {
    fs::permissions(p.path(), fs::perms::owner_write, fs::perm_options::add);
  }
  return root;
}

TEST_F(EurocImportTest, ReadsTheAslLayoutOfAnySequence) {
  const Dataset flat = ImportEuroc(kEurocDir);
  const std::string root = AslLayout("MH_04_difficult");
  for (const std::string& dir : {root, root + "/mav0", root + "/"}) {
    SCOPED_TRACE(dir);
    const Dataset d = ImportEuroc(dir);
    EXPECT_EQ(d.name, "euroc_MH_04_difficult");
    ASSERT_EQ(d.imu_samples.size(), flat.imu_samples.size());
    EXPECT_EQ(d.imu_samples[777].gyro_rad_s, flat.imu_samples[777].gyro_rad_s);
    ASSERT_EQ(d.truth_states.size(), flat.truth_states.size());
    EXPECT_EQ(d.truth_states[500].p_w_b, flat.truth_states[500].p_w_b);
    EXPECT_EQ(d.truth_states[500].q_w_b.coeffs(), flat.truth_states[500].q_w_b.coeffs());
    EXPECT_EQ(d.truth_states[500].ba, flat.truth_states[500].ba);
  }
  // A sequence without ground truth still imports (its IMU), with a warning.
  fs::remove_all(root + "/mav0/state_groundtruth_estimate0");
  const Dataset no_truth = ImportEuroc(root);
  EXPECT_EQ(no_truth.imu_samples.size(), flat.imu_samples.size());
  EXPECT_TRUE(no_truth.groundtruth.empty());
}

TEST_F(EurocImportTest, BadAslFoldersNameWhatIsWrong) {
  const std::string root = AslLayout("V2_02_medium");
  // A header-only IMU file is empty, not "an estimator that never initialised".
  WriteLines(root + "/mav0/imu0/data.csv",
             {"#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
              "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]"});
  ExpectInputError([&] { ImportEuroc(root); }, "imu0/data.csv", 0, "timestamp [ns]");
  // A ground-truth row with a column missing.
  const std::string root2 = AslLayout("V2_03_difficult");
  std::vector<std::string> gt = ReadLines(root2 + "/mav0/state_groundtruth_estimate0/data.csv");
  gt[9] = gt[9].substr(0, gt[9].rfind(','));
  WriteLines(root2 + "/mav0/state_groundtruth_estimate0/data.csv", gt);
  ExpectInputError([&] { ImportEuroc(root2); }, "state_groundtruth_estimate0/data.csv", 10,
                   "b_a_RS_S_z [m s^-2]");
  // No sensor.yaml.
  fs::remove(root2 + "/mav0/imu0/sensor.yaml");
  ExpectInputError([&] { ImportEuroc(root2); }, "sensor.yaml", 0, "file");
  // Not a EuRoC folder at all.
  ExpectInputError([&] { ImportEuroc(FreshDir("not_euroc")); }, "not_euroc", 0, "");
}

class HuskyImportTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(kHuskyDir)) GTEST_SKIP() << kHuskyDir << " missing";
  }
};

TEST_F(HuskyImportTest, ImportsRealData) {
  const Dataset d = ImportHusky(kHuskyDir);
  ASSERT_EQ(d.imu_samples.size(), 11865u);
  EXPECT_EQ(d.imu_samples.front().t_ns, 1432235497988949000LL);  // `stamp`, exact
  EXPECT_NEAR(d.imu.rate_hz, 30.0, 1e-12);
  for (std::size_t k = 1; k < d.imu_samples.size(); ++k) {
    ASSERT_GT(d.imu_samples[k].t_ns, d.imu_samples[k - 1].t_ns);
  }
  // Mean period ~1/30 s.
  const double period_s = NsToSeconds(d.imu_samples.back().t_ns - d.imu_samples.front().t_ns) /
                          static_cast<double>(d.imu_samples.size() - 1);
  EXPECT_NEAR(period_s, 1.0 / 30.0, 1e-3);

  ASSERT_TRUE(d.has_gnss);
  ASSERT_EQ(d.gnss_fixes.size(), 989u);
  EXPECT_EQ(d.origin.lat_deg, 42.375812);
  EXPECT_EQ(d.origin.lon_deg, -71.14739466666667);
  EXPECT_LT(d.gnss_fixes.front().p_w.norm(), 1e-6);
  EXPECT_NEAR(d.gnss_fixes.front().sigma_enu_m.x(), 0.9, 1e-12);
  EXPECT_NEAR(d.gnss_fixes.front().sigma_enu_m.z(), 1.8, 1e-12);
  // A robot in a parking lot: fixes stay within ~150 m. The receiver's altitude wanders from
  // +7 m to -28 m over the run (real noise, although it claims sigma_u = 1.8 m): a filter must
  // not trust it, and this test only bounds it.
  double min_up = 0.0;
  for (const GnssFix& f : d.gnss_fixes) {
    EXPECT_LT(f.p_w.head<2>().norm(), 200.0);
    EXPECT_LT(std::fabs(f.p_w.z()), 50.0);
    min_up = std::min(min_up, f.p_w.z());
  }
  EXPECT_LT(min_up, -30.0);
  // The extrinsic puts gravity on body up: the mean specific force in the body is ~+9.8 z.
  Eigen::Vector3d mean_f_b = Eigen::Vector3d::Zero();
  for (const ImuSample& s : d.imu_samples) mean_f_b += d.imu.q_b_i * s.accel_m_s2;
  mean_f_b /= static_cast<double>(d.imu_samples.size());
  EXPECT_NEAR(mean_f_b.z(), 9.79, 0.1) << mean_f_b.transpose();
  EXPECT_LT(mean_f_b.head<2>().norm(), 0.5) << mean_f_b.transpose();
}

TEST_F(HuskyImportTest, DropsExactDuplicatesAndSkipsNoFix) {
  const std::string dir = CopyOf(kHuskyDir, "husky_duplicates");
  std::vector<std::string> imu = ReadLines(dir + "/imu_data.csv");
  // The same message recorded twice: identical but for bag_time.
  std::string dup = imu[10];
  dup.replace(0, dup.find(','), "1432235499.999999999");
  imu.insert(imu.begin() + 11, dup);
  WriteLines(dir + "/imu_data.csv", imu);
  std::vector<std::string> fix = ReadLines(dir + "/fix.csv");
  fix.insert(fix.begin() + 3, "1432235498.5,1432235498.5,/gps,-1,1,nan,nan,nan,0,0,0,0");
  WriteLines(dir + "/fix.csv", fix);
  const Dataset d = ImportHusky(dir);
  EXPECT_EQ(d.imu_samples.size(), 11865u);
  EXPECT_EQ(d.gnss_fixes.size(), 989u);
}

TEST_F(HuskyImportTest, OtherNonIncreasingStampsAreErrors) {
  const std::string dir = CopyOf(kHuskyDir, "husky_backwards");
  std::vector<std::string> imu = ReadLines(dir + "/imu_data.csv");
  // Same stamp, different content: not a duplicate; reported on file line 12.
  std::string clash = imu[10];
  clash.replace(clash.rfind(','), std::string::npos, ",0.5");
  imu.insert(imu.begin() + 11, clash);
  WriteLines(dir + "/imu_data.csv", imu);
  ExpectInputError([&] { ImportHusky(dir); }, "imu_data.csv", 12, "stamp");
  // A stamp going backwards in fix.csv.
  fs::copy_file(kHuskyDir + "/imu_data.csv", dir + "/imu_data.csv",
                fs::copy_options::overwrite_existing);
  std::vector<std::string> fix = ReadLines(dir + "/fix.csv");
  std::swap(fix[4], fix[5]);
  WriteLines(dir + "/fix.csv", fix);
  ExpectInputError([&] { ImportHusky(dir); }, "fix.csv", 6, "stamp");
}

}  // namespace
}  // namespace skerry
