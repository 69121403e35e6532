// Datasets without IMU and the marine files: written, loaded, refused where bad; a dataset with
// an IMU is written as before.
#include "skerry/io/marine_dataset.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "core/test_util.h"
#include "skerry/io/dataset.h"

namespace skerry {
namespace {

namespace fs = std::filesystem;
using testing::ExpectInputError;
using testing::FreshDir;
using testing::ReadLines;
using testing::WriteLines;

constexpr TimeNs kT0 = 1785732421000000000;  // 2026-08-03T04:47:01Z

Dataset Marine() {
  MarineLog log;
  log.path = "/logs/boat.si.jsonl.gz";
  log.format = "nmea2000";
  for (int k = 0; k < 3; ++k) {
    MarineFix f;
    f.t_ns = kT0 + k * 100000000;
    f.lat_deg = 34.4 + k * 1e-5;
    f.lon_deg = 133.5;
    f.height_m = k == 0 ? std::nullopt : std::optional<double>(40.0);
    SetSigmasFromHdop(1.0, FixKind::kAutonomous, &f);
    f.source = "25";
    log.fixes.push_back(f);
  }
  log.records.headings = {{kT0, 359.5, false, "36"}, {kT0 + 1, 0.25, true, "36"}};
  log.records.courses = {{kT0, 10.0, 2.5, "25"}};
  log.records.attitudes = {{kT0, 1.0, -2.0, std::nullopt, "27"}, {kT0 + 5, 1.5, -2.5, 3.0, "27"}};
  log.records.rates_of_turn = {{kT0, -0.5, "27"}};
  return MarineLogToDataset(log);
}

TEST(MarineDataset, WritesAndLoadsWithoutImu) {
  const Dataset d = Marine();
  EXPECT_EQ(d.name, "boat");
  // The origin's height is the first height any fix has; the fix without one gets it, loosely.
  EXPECT_EQ(d.origin.height_m, 40.0);
  EXPECT_EQ(d.gnss_fixes[0].height_m, 40.0);
  EXPECT_EQ(d.gnss_fixes[0].sigma_enu_m.z(), kUnknownHeightSigmaM);
  EXPECT_EQ(d.gnss_fixes[1].sigma_enu_m.z(), 6.0);  // 1.5 * HDOP 1 * UERE 4 m
  const std::string dir = FreshDir("no_imu");
  WriteDataset(d, dir);
  EXPECT_FALSE(fs::exists(dir + "/imu.csv"));
  for (const std::string& line : ReadLines(dir + "/dataset.yaml")) {
    EXPECT_EQ(line.find("imu"), std::string::npos) << line;
  }
  EXPECT_EQ(ReadLines(dir + "/attitude.csv"),
            (std::vector<std::string>{"t,roll_deg,pitch_deg,yaw_deg", "1785732421.000000000,1,-2,",
                                      "1785732421.000000005,1.5,-2.5,3"}));
  const Dataset b = LoadDataset(dir);
  EXPECT_FALSE(b.has_imu);
  EXPECT_EQ(b.gnss_fixes.size(), 3u);
  ASSERT_EQ(b.marine.headings.size(), 2u);
  EXPECT_EQ(b.marine.headings[1].t_ns, kT0 + 1);
  EXPECT_EQ(b.marine.headings[1].heading_deg, 0.25);
  EXPECT_EQ(b.marine.courses[0].sog_m_s, 2.5);
  EXPECT_FALSE(b.marine.attitudes[0].yaw_deg.has_value());
  EXPECT_EQ(*b.marine.attitudes[1].yaw_deg, 3.0);
  EXPECT_EQ(b.marine.rates_of_turn[0].rate_deg_s, -0.5);
  // Cut in time like every other stream.
  EXPECT_EQ(DatasetUntil(b, kT0).marine.headings.size(), 1u);
  EXPECT_EQ(DatasetUntil(b, kT0).marine.attitudes.size(), 1u);

  // Bad marine files are InputErrors naming file, line and column.
  WriteLines(dir + "/heading.csv", {"t,heading_deg", "1.0,360.0"});
  ExpectInputError([&] { LoadDataset(dir); }, "heading.csv", 2, "heading_deg");
  WriteLines(dir + "/heading.csv", {"t,heading_deg", "2.0,1", "1.0,2"});
  ExpectInputError([&] { LoadDataset(dir); }, "heading.csv", 3, "t");
  WriteLines(dir + "/heading.csv", {"t,heading_deg"});
  WriteLines(dir + "/course.csv", {"t,cog_deg,sog_m_s", "1.0,10,-1"});
  ExpectInputError([&] { LoadDataset(dir); }, "course.csv", 2, "sog_m_s");
  WriteLines(dir + "/course.csv", {"t,cog_deg"});
  ExpectInputError([&] { LoadDataset(dir); }, "course.csv", 1, "sog_m_s");
}

TEST(MarineDataset, DatasetsWithImuAreWrittenAsBefore) {
  Dataset d;
  d.name = "with_imu";
  ImuSample s;
  s.t_ns = 1000;
  d.imu_samples.push_back(s);
  EXPECT_TRUE(d.has_imu);  // the default: every dataset but a marine log's
  const std::string dir = FreshDir("with_imu");
  WriteDataset(d, dir);
  EXPECT_TRUE(fs::exists(dir + "/imu.csv"));
  EXPECT_FALSE(fs::exists(dir + "/heading.csv"));
  const Dataset b = LoadDataset(dir);
  EXPECT_TRUE(b.has_imu);
  EXPECT_EQ(b.imu_samples.size(), 1u);
  RequireImu(b, "run");  // no throw
}

}  // namespace
}  // namespace skerry
