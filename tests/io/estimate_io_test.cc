#include "skerry/io/estimate_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "core/test_util.h"
#include "skerry/core/so3.h"

namespace skerry {
namespace {

using testing::ExpectInputError;
using testing::FreshDir;
using testing::ReadLines;
using testing::WriteLines;

StateCovariance RandomCovariance(int seed) {
  std::srand(seed);
  const Eigen::Matrix<double, 15, 15> a = Eigen::Matrix<double, 15, 15>::Random();
  const StateCovariance P = a * a.transpose() * 0.01 + StateCovariance::Identity() * 1e-4;
  return 0.5 * (P + P.transpose());  // exactly symmetric, as a writer would store it
}

std::vector<EstimateRecord> MakeRecords() {
  std::vector<EstimateRecord> records;
  for (int k = 0; k < 4; ++k) {
    EstimateRecord r;
    r.state.t_ns = 1403715273262142976LL + k * 100000003LL;
    r.state.p_w_b = Eigen::Vector3d(k / 3.0, -k, 2.0);
    r.state.q_w_b = ExpQ(Eigen::Vector3d(0.1, 0.2, 0.3 * k));
    r.state.v_w = Eigen::Vector3d(1.0, 0.0, -0.1 * k);
    r.state.bg = Eigen::Vector3d(1e-5, 2e-5, 3e-5);
    r.state.ba = Eigen::Vector3d(0.1, 0.2, 0.3);
    r.has_covariance = (k != 1);
    if (r.has_covariance) r.covariance = RandomCovariance(k);
    records.push_back(r);
  }
  return records;
}

TEST(EstimateIoTest, HeadingSigmaIsWorldZRotation) {
  StateCovariance P = StateCovariance::Identity();
  P(2, 2) = std::pow(2.0 * M_PI / 180.0, 2);
  EXPECT_NEAR(HeadingSigmaDeg(P), 2.0, 1e-12);
}

TEST(EstimateIoTest, RoundTrip) {
  const std::string dir = FreshDir("estimate_io");
  const std::vector<EstimateRecord> records = MakeRecords();
  WriteEstimateFiles(dir, records);

  const std::vector<std::string> states = ReadLines(dir + "/states.csv");
  EXPECT_EQ(states[0],
            "t,px,py,pz,qx,qy,qz,qw,vx,vy,vz,bgx,bgy,bgz,bax,bay,baz,sigma_px,sigma_py,sigma_pz,"
            "sigma_heading_deg");
  EXPECT_EQ(states[2].substr(states[2].size() - 4), ",,,,");  // no covariance: empty sigmas
  const std::vector<std::string> cov = ReadLines(dir + "/covariances.csv");
  EXPECT_EQ(cov.size(), 4u);  // header + 3 records with covariance
  EXPECT_EQ(cov[0].substr(0, 45), "t,c00,c01,c02,c03,c04,c05,c06,c07,c08,c09,c0_");
  EXPECT_EQ(cov[0].substr(cov[0].size() - 20), "c13_13,c13_14,c14_14");

  const std::vector<EstimateRecord> back =
      ReadEstimate(dir + "/states.csv", dir + "/covariances.csv");
  ASSERT_EQ(back.size(), records.size());
  for (std::size_t k = 0; k < records.size(); ++k) {
    EXPECT_EQ(back[k].state.t_ns, records[k].state.t_ns);
    EXPECT_EQ(back[k].state.p_w_b, records[k].state.p_w_b);
    EXPECT_NEAR(back[k].state.q_w_b.angularDistance(records[k].state.q_w_b), 0.0, 1e-15);
    EXPECT_EQ(back[k].state.v_w, records[k].state.v_w);
    EXPECT_EQ(back[k].state.bg, records[k].state.bg);
    EXPECT_EQ(back[k].state.ba, records[k].state.ba);
    EXPECT_EQ(back[k].has_covariance, records[k].has_covariance);
    if (records[k].has_covariance) {
      EXPECT_EQ(back[k].covariance, records[k].covariance);
    }
  }
  // Without the covariance file: states only.
  const std::vector<EstimateRecord> states_only = ReadEstimate(dir + "/states.csv");
  EXPECT_FALSE(states_only[0].has_covariance);
  EXPECT_EQ(ToPoses(back)[2].p_w_b, records[2].state.p_w_b);
}

TEST(EstimateIoTest, WrittenInPiecesIsWrittenWhole) {
  const std::string whole = FreshDir("estimate_io_whole");
  const std::string pieces = FreshDir("estimate_io_pieces");
  const std::vector<EstimateRecord> records = MakeRecords();
  WriteEstimateFiles(whole, records);
  EstimateFilesWriter writer(pieces);
  // Nothing appears under the files' names before Commit: a run killed now leaves none.
  EXPECT_FALSE(std::filesystem::exists(pieces + "/states.csv"));
  for (const EstimateRecord& r : records) writer.Append({r});
  writer.Append({});
  EXPECT_FALSE(std::filesystem::exists(pieces + "/trajectory.tum"));
  writer.Commit();
  EXPECT_EQ(writer.count(), records.size());
  for (const char* file : {"/trajectory.tum", "/states.csv", "/covariances.csv"}) {
    EXPECT_EQ(ReadLines(pieces + file), ReadLines(whole + file)) << file;
  }
}

TEST(EstimateIoTest, BadInput) {
  const std::string dir = FreshDir("estimate_io_bad");
  WriteEstimateFiles(dir, MakeRecords());
  // A covariance at a time with no state.
  std::vector<std::string> cov = ReadLines(dir + "/covariances.csv");
  cov[2].replace(0, cov[2].find(','), "1403715274.000000000");
  WriteLines(dir + "/cov2.csv", cov);
  ExpectInputError([&] { ReadEstimate(dir + "/states.csv", dir + "/cov2.csv"); }, "cov2.csv", 3,
                   "t");
  // A NaN in the covariance.
  cov = ReadLines(dir + "/covariances.csv");
  cov[1].replace(cov[1].find(',') + 1, 0, "nan");
  WriteLines(dir + "/cov3.csv", cov);
  ExpectInputError([&] { ReadEstimate(dir + "/states.csv", dir + "/cov3.csv"); }, "cov3.csv", 2,
                   "c00");
  // A non-unit quaternion in the states.
  std::vector<std::string> states = ReadLines(dir + "/states.csv");
  states.push_back("2000000000.0,0,0,0,0,0,0,3,0,0,0,0,0,0,0,0,0,,,,");
  WriteLines(dir + "/states2.csv", states);
  ExpectInputError([&] { ReadEstimate(dir + "/states2.csv"); }, "states2.csv", 6, "qw");
}

}  // namespace
}  // namespace skerry
