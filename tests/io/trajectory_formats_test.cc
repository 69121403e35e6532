// TUM, KITTI (+ times sidecar) and EuRoC CSV trajectories: round trips, the real EuRoC ground
// truth, and bad input that must name file, line and field.

#include "skerry/io/trajectory_formats.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "core/test_util.h"

namespace skerry {
namespace {

namespace fs = std::filesystem;
using testing::ExpectInputError;
using testing::FreshDir;
using testing::ReadLines;
using testing::WriteLines;
using testing::WriteText;

const std::string kEurocGroundTruth =
    std::string(SKERRY_SHARED_DATA_DIR) + "/euroc_v1_01/V1_01_easy.csv";

const std::string kAslHeader =
    "#timestamp,p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],q_RS_z []";

/// A wandering trajectory with ns-odd stamps (EuRoC-like epoch) and rotations all around.
std::vector<StampedPose> MakePoses(int n = 50) {
  std::vector<StampedPose> poses;
  for (int k = 0; k < n; ++k) {
    StampedPose p;
    p.t_ns = 1403715273262142976LL + k * 50'000'123LL;
    p.p_w_b = Eigen::Vector3d(100.0 * std::sin(0.1 * k), -3.25 * k, 1e-3 * k * k);
    p.q_w_b = Eigen::AngleAxisd(0.37 * k, Eigen::Vector3d::UnitZ()) *
              Eigen::AngleAxisd(0.21 * k, Eigen::Vector3d::UnitX()) *
              Eigen::AngleAxisd(-0.13 * k, Eigen::Vector3d::UnitY());
    poses.push_back(p);
  }
  return poses;
}

void ExpectSamePoses(const std::vector<StampedPose>& a, const std::vector<StampedPose>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k) {
    EXPECT_EQ(a[k].t_ns, b[k].t_ns) << k;
    EXPECT_LT((a[k].p_w_b - b[k].p_w_b).norm(), 1e-9) << k;
    EXPECT_LT(a[k].q_w_b.angularDistance(b[k].q_w_b), 1e-9) << k;
  }
}

std::vector<std::string> SplitComma(const std::string& line) {
  std::vector<std::string> fields;
  std::stringstream s(line);
  for (std::string f; std::getline(s, f, ',');) fields.push_back(f);
  return fields;
}

// ---------------------------------------------------------------------------------------------

TEST(TrajectoryFormatsTest, NamesAndExtensions) {
  EXPECT_EQ(ParseTrajectoryFormat("tum"), TrajectoryFormat::kTum);
  EXPECT_EQ(ParseTrajectoryFormat("kitti"), TrajectoryFormat::kKitti);
  EXPECT_EQ(ParseTrajectoryFormat("euroc"), TrajectoryFormat::kEuroc);
  EXPECT_THROW(ParseTrajectoryFormat("TUM"), InputError);
  EXPECT_EQ(TrajectoryFormatFromPath("a/b.tum"), TrajectoryFormat::kTum);
  EXPECT_EQ(TrajectoryFormatFromPath("V1_01_easy.txt"), TrajectoryFormat::kTum);
  EXPECT_EQ(TrajectoryFormatFromPath("poses.kitti"), TrajectoryFormat::kKitti);
  EXPECT_EQ(TrajectoryFormatFromPath("data.csv"), TrajectoryFormat::kEuroc);
  ExpectInputError([] { TrajectoryFormatFromPath("poses.json"); }, "poses.json", 0, "extension");
  EXPECT_EQ(TrajectoryFormatFor("poses.json", "kitti"), TrajectoryFormat::kKitti);
  EXPECT_EQ(TrajectoryFormatFor("poses.kitti", ""), TrajectoryFormat::kKitti);
  for (TrajectoryFormat f :
       {TrajectoryFormat::kTum, TrajectoryFormat::kKitti, TrajectoryFormat::kEuroc}) {
    EXPECT_EQ(ParseTrajectoryFormat(TrajectoryFormatName(f)), f);
  }
}

TEST(TrajectoryFormatsTest, RoundTripEachFormat) {
  const std::string dir = FreshDir("rt");
  const std::vector<StampedPose> poses = MakePoses();
  for (const char* name : {"t.tum", "t.kitti", "t.csv"}) {
    SCOPED_TRACE(name);
    const std::string path = dir + "/" + name;
    const TrajectoryFormat format = TrajectoryFormatFromPath(path);
    WriteTrajectory(path, poses, format);
    ExpectSamePoses(ReadTrajectory(path, format), poses);
  }
  // The KITTI file is 12 numbers a line and nothing else; its times are in the sidecar.
  const std::vector<std::string> kitti = ReadLines(dir + "/t.kitti");
  ASSERT_EQ(kitti.size(), poses.size());
  std::istringstream first(kitti[0]);
  int numbers = 0;
  for (double v; first >> v;) ++numbers;
  EXPECT_EQ(numbers, 12);
  const std::vector<std::string> times = ReadLines(KittiTimesPath(dir + "/t.kitti"));
  ASSERT_EQ(times.size(), poses.size());
  EXPECT_EQ(times[1], "1403715273.312143099");
  // EuRoC: ASL header, integer ns, w first.
  const std::vector<std::string> euroc = ReadLines(dir + "/t.csv");
  ASSERT_EQ(euroc.size(), poses.size() + 1);
  EXPECT_EQ(euroc[0], kAslHeader);
  const std::vector<std::string> row = SplitComma(euroc[2]);
  ASSERT_EQ(row.size(), 8u);
  EXPECT_EQ(row[0], "1403715273312143099");
  EXPECT_EQ(std::stod(row[4]), poses[1].q_w_b.w());
}

TEST(TrajectoryFormatsTest, KittiWithoutTimesCountsSeconds) {
  const std::string path = FreshDir("kitti") + "/poses.kitti";
  const std::vector<StampedPose> poses = MakePoses(5);
  WriteTrajectory(path, poses, TrajectoryFormat::kKitti);
  fs::remove(KittiTimesPath(path));
  const std::vector<StampedPose> read = ReadTrajectory(path, TrajectoryFormat::kKitti);
  ASSERT_EQ(read.size(), poses.size());
  for (std::size_t k = 0; k < read.size(); ++k) {
    EXPECT_EQ(read[k].t_ns, static_cast<TimeNs>(k) * 1'000'000'000) << k;
    EXPECT_LT((read[k].p_w_b - poses[k].p_w_b).norm(), 1e-9);
  }
}

TEST(TrajectoryFormatsTest, KittiRotationsAreReorthonormalised) {
  const std::string path = FreshDir("kitti") + "/poses.kitti";
  // Rz(30 deg) printed with 6 decimals (as KITTI's own files are), plus 1e-5 of skew.
  WriteLines(path, {"0.866025 -0.500000 0.000000 1.5 0.500010 0.866025 0.000000 -2.0 "
                    "0.000000 0.000000 1.000000 0.25"});
  const std::vector<StampedPose> read = ReadTrajectory(path, TrajectoryFormat::kKitti);
  ASSERT_EQ(read.size(), 1u);
  EXPECT_NEAR(read[0].q_w_b.norm(), 1.0, 1e-15);
  const Eigen::Matrix3d R = read[0].q_w_b.toRotationMatrix();
  EXPECT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 1e-14);
  const Eigen::Quaterniond expected(Eigen::AngleAxisd(M_PI / 6.0, Eigen::Vector3d::UnitZ()));
  EXPECT_LT(read[0].q_w_b.angularDistance(expected), 1e-5);
  EXPECT_EQ(read[0].p_w_b, Eigen::Vector3d(1.5, -2.0, 0.25));
}

TEST(TrajectoryFormatsTest, EurocFromEstimateRecordsHasAll17Columns) {
  const std::string path = FreshDir("records") + "/states.csv";
  std::vector<EstimateRecord> records;
  for (const StampedPose& p : MakePoses(4)) {
    EstimateRecord r;
    r.state.t_ns = p.t_ns;
    r.state.p_w_b = p.p_w_b;
    r.state.q_w_b = p.q_w_b;
    r.state.v_w = Eigen::Vector3d(1.5, -0.25, 0.125);
    r.state.bg = Eigen::Vector3d(1e-3, 2e-3, 3e-3);
    r.state.ba = Eigen::Vector3d(-0.01, 0.02, -0.03);
    records.push_back(r);
  }
  WriteTrajectory(path, records, TrajectoryFormat::kEuroc);
  const std::vector<std::string> lines = ReadLines(path);
  ASSERT_EQ(lines.size(), 5u);
  EXPECT_EQ(lines[0], kAslHeader +
                          ",v_RS_R_x [m s^-1],v_RS_R_y [m s^-1],v_RS_R_z [m s^-1],"
                          "b_w_RS_S_x [rad s^-1],b_w_RS_S_y [rad s^-1],b_w_RS_S_z [rad s^-1],"
                          "b_a_RS_S_x [m s^-2],b_a_RS_S_y [m s^-2],b_a_RS_S_z [m s^-2]");
  const std::vector<std::string> row = SplitComma(lines[1]);
  ASSERT_EQ(row.size(), 17u);
  EXPECT_EQ(std::stod(row[8]), 1.5);
  EXPECT_EQ(std::stod(row[13]), 3e-3);
  EXPECT_EQ(std::stod(row[16]), -0.03);
  EXPECT_FALSE(IsStatesCsv(path));
  ExpectSamePoses(ReadTrajectory(path, TrajectoryFormat::kEuroc), ToPoses(records));
  // TUM / KITTI from records: the poses.
  const std::string tum = fs::path(path).replace_extension(".tum").string();
  WriteTrajectory(tum, records, TrajectoryFormat::kTum);
  ExpectSamePoses(ReadTrajectory(tum, TrajectoryFormat::kTum), ToPoses(records));
}

TEST(TrajectoryFormatsTest, EurocAcceptsAslSpacingAndExtraColumns) {
  const std::string path = FreshDir("asl") + "/data.csv";
  // ASL's own files put a space after each comma of the header.
  WriteLines(path, {"#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], "
                    "q_RS_y [], q_RS_z [], v_RS_R_x [m s^-1]",
                    "1403636579758555392,4.688319,-1.786938,0.783338,0.534108,-0.153029,"
                    "-0.827383,-0.082152,-0.027876",
                    "1403636579763555584,4.688177,-1.786770,0.787350,0.534640,-0.152990,"
                    "-0.826976,-0.082863,-0.029272"});
  const std::vector<StampedPose> poses = ReadTrajectory(path, TrajectoryFormat::kEuroc);
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_EQ(poses[1].t_ns, 1403636579763555584LL);
  EXPECT_EQ(poses[0].p_w_b.y(), -1.786938);
  const Eigen::Quaterniond q(0.534108, -0.153029, -0.827383, -0.082152);
  EXPECT_LT(poses[0].q_w_b.angularDistance(q.normalized()), 1e-12);
}

TEST(TrajectoryFormatsTest, ReadsTheRealEurocGroundTruth) {
  if (!fs::exists(kEurocGroundTruth)) GTEST_SKIP() << kEurocGroundTruth << " missing";
  const std::vector<StampedPose> poses =
      ReadTrajectory(kEurocGroundTruth, TrajectoryFormatFromPath(kEurocGroundTruth));
  const std::vector<std::string> lines = ReadLines(kEurocGroundTruth);
  ASSERT_GE(lines.size(), 2u);
  ASSERT_EQ(poses.size(), lines.size() - 1);  // every line but the header
  EXPECT_EQ(poses.size(), 2895u);
  // First pose against the text of the file: t[ns], p, q(w, x, y, z).
  const std::vector<std::string> f = SplitComma(lines[1]);
  ASSERT_EQ(f.size(), 17u);
  EXPECT_EQ(poses[0].t_ns, std::stoll(f[0]));
  EXPECT_EQ(poses[0].t_ns, 1403715273262142976LL);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(poses[0].p_w_b[i], std::stod(f[1 + i])) << i;
  const Eigen::Quaterniond q(std::stod(f[4]), std::stod(f[5]), std::stod(f[6]), std::stod(f[7]));
  EXPECT_LT(poses[0].q_w_b.angularDistance(q.normalized()), 1e-12);
  EXPECT_NEAR(poses[0].q_w_b.w(), 0.069433, 1e-5);
  EXPECT_EQ(poses.back().t_ns, std::stoll(SplitComma(lines.back())[0]));

  // Exported to KITTI (with times) and back: the same trajectory.
  const std::string kitti = FreshDir("euroc_kitti") + "/v1_01.kitti";
  WriteTrajectory(kitti, poses, TrajectoryFormat::kKitti);
  ExpectSamePoses(ReadTrajectory(kitti, TrajectoryFormat::kKitti), poses);
}

// ---------------------------------------------------------------------------------------------
// Bad input: file, line and field.

class BadEurocTest : public ::testing::Test {
 protected:
  void SetUp() override { path_ = FreshDir("bad") + "/data.csv"; }
  // The header, two good rows, then `row` on line 4.
  void WriteWithRow(const std::string& row, bool final_newline = true) {
    std::string text = kAslHeader + "\n" + "1000,1,2,3,1,0,0,0\n" + "2000,1,2,3,1,0,0,0\n" + row;
    if (final_newline) text += "\n";
    WriteText(path_, text);
  }
  void Expect(int line, const std::string& field) {
    ExpectInputError([this] { ReadTrajectory(path_, TrajectoryFormat::kEuroc); }, "data.csv", line,
                     field);
  }
  std::string path_;
};

TEST_F(BadEurocTest, TooFewColumns) {
  WriteWithRow("3000,1,2,3,1,0,0");
  Expect(4, "q_RS_z []");
}

TEST_F(BadEurocTest, TooManyColumns) {
  WriteWithRow("3000,1,2,3,1,0,0,0,9");
  Expect(4, "columns");
}

TEST_F(BadEurocTest, NaN) {
  WriteWithRow("3000,1,nan,3,1,0,0,0");
  Expect(4, "p_RS_R_y [m]");
}

TEST_F(BadEurocTest, NonIncreasingTime) {
  WriteWithRow("2000,1,2,3,1,0,0,0");
  Expect(4, "timestamp");
}

TEST_F(BadEurocTest, SecondsInsteadOfNanoseconds) {
  WriteWithRow("3000.5,1,2,3,1,0,0,0");
  Expect(4, "timestamp");
}

TEST_F(BadEurocTest, TruncatedLastLine) {
  WriteWithRow("3000,1,2,3,0.9", /*final_newline=*/false);
  Expect(4, "q_RS_x []");
}

TEST_F(BadEurocTest, NonUnitQuaternion) {
  WriteWithRow("3000,1,2,3,0.5,0,0,0");
  Expect(4, "q_RS_w []");
}

TEST_F(BadEurocTest, QuaternionOrderInHeader) {
  WriteLines(path_, {"#timestamp,px,py,pz,qx,qy,qz,qw", "1000,1,2,3,0,0,0,1"});
  Expect(1, "q_RS_w []");
}

TEST_F(BadEurocTest, MissingHeader) {
  WriteLines(path_, {"1000,1,2,3,1,0,0,0"});
  Expect(1, "header");
}

TEST_F(BadEurocTest, TooFewColumnsInHeader) {
  WriteLines(path_, {"#timestamp,px,py,pz", "1000,1,2,3"});
  Expect(1, "q_RS_w []");
}

TEST(BadKittiTest, WrongColumnCount) {
  const std::string path = FreshDir("bad") + "/poses.kitti";
  WriteLines(path, {"1 0 0 0 0 1 0 0 0 0 1 0", "1 0 0 0 0 1 0 0 0 0 1"});
  ExpectInputError([&] { ReadTrajectory(path, TrajectoryFormat::kKitti); }, "poses.kitti", 2, "tz");
  WriteLines(path, {"1 0 0 0 0 1 0 0 0 0 1 0 7"});
  ExpectInputError([&] { ReadTrajectory(path, TrajectoryFormat::kKitti); }, "poses.kitti", 1,
                   "columns");
}

TEST(BadKittiTest, NaN) {
  const std::string path = FreshDir("bad") + "/poses.kitti";
  WriteLines(path, {"1 0 0 0 0 1 0 NaN 0 0 1 0"});
  ExpectInputError([&] { ReadTrajectory(path, TrajectoryFormat::kKitti); }, "poses.kitti", 1, "ty");
}

TEST(BadKittiTest, NotARotation) {
  const std::string path = FreshDir("bad") + "/poses.kitti";
  WriteLines(path, {"1 0 0 0 0 1 0 0 0 0 1 0", "1 0 0 0 0 1.01 0 0 0 0 1 0"});
  ExpectInputError([&] { ReadTrajectory(path, TrajectoryFormat::kKitti); }, "poses.kitti", 2,
                   "rotation");
  WriteLines(path, {"-1 0 0 0 0 1 0 0 0 0 1 0"});  // a reflection
  ExpectInputError([&] { ReadTrajectory(path, TrajectoryFormat::kKitti); }, "poses.kitti", 1,
                   "rotation");
}

TEST(BadKittiTest, TimesSidecar) {
  const std::string path = FreshDir("bad") + "/poses.kitti";
  WriteLines(path, {"1 0 0 0 0 1 0 0 0 0 1 0", "1 0 0 1 0 1 0 0 0 0 1 0"});
  WriteLines(KittiTimesPath(path), {"0.5", "0.5"});
  ExpectInputError([&] { ReadTrajectory(path, TrajectoryFormat::kKitti); }, "poses.kitti.times", 2,
                   "t");
  WriteLines(KittiTimesPath(path), {"0.5"});
  ExpectInputError([&] { ReadTrajectory(path, TrajectoryFormat::kKitti); }, "poses.kitti.times", 1,
                   "t");
  WriteLines(KittiTimesPath(path), {"0.5", "0.6", "0.7"});
  ExpectInputError([&] { ReadTrajectory(path, TrajectoryFormat::kKitti); }, "poses.kitti.times", 3,
                   "t");
  WriteLines(KittiTimesPath(path), {"0.5", "0.6"});
  const std::vector<StampedPose> poses = ReadTrajectory(path, TrajectoryFormat::kKitti);
  ASSERT_EQ(poses.size(), 2u);
  EXPECT_EQ(poses[1].t_ns, 600'000'000);
}

TEST(BadTumTest, ThroughReadTrajectory) {
  const std::string path = FreshDir("bad") + "/t.tum";
  WriteLines(path, {"# t x y z qx qy qz qw", "0.0 1 2 3 0 0 0 1", "0.1 1 2 inf 0 0 0 1"});
  ExpectInputError([&] { ReadTrajectory(path, TrajectoryFormat::kTum); }, "t.tum", 3, "z");
}

TEST(BadInputTest, MessageNamesFileLineAndField) {
  const std::string path = FreshDir("bad") + "/data.csv";
  WriteLines(path, {kAslHeader, "1000,1,2,3,1,0,0,0", "1000,1,2,3,1,0,0,0"});
  try {
    ReadTrajectory(path, TrajectoryFormat::kEuroc);
    FAIL() << "no InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(path + ":3: timestamp: "), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace skerry
