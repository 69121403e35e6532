// skerry import of marine logs (NMEA 0183; NMEA 2000 as canboat JSON), its summary, and the
// estimator commands refusing the dataset without IMU they make.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "apps/cli_test_util.h"
#include "core/test_util.h"
#include "io/nmea_test_util.h"
#include "skerry/io/dataset.h"
#include "skerry/io/nmea0183.h"

namespace skerry {
namespace {

namespace fs = std::filesystem;
using testing::CliResult;
using testing::FreshDir;
using testing::Quote;
using testing::RunCli;
using testing::WriteLines;

const std::string kWideTurn =
    std::string(SKERRY_SHARED_DATA_DIR) + "/boat/furuno-130842-wide-turn.si.jsonl.gz";

using testing::WithChecksum;

bool Contains(const std::string& text, const std::string& what) {
  return text.find(what) != std::string::npos;
}

TEST(MarineCli, ImportsNmea2000AndRunRefusesTheDatasetWithoutImu) {
  if (!fs::exists(kWideTurn)) GTEST_SKIP() << kWideTurn << " missing";
  const std::string dir = FreshDir("marine_cli");
  const std::string data = dir + "/boat";
  const CliResult r =
      RunCli("import --format nmea2000 " + Quote(kWideTurn) + " --out " + Quote(data));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(Contains(r.out, "21190 lines read, 15483 used, 5707 of types not used, 0 bad"))
      << r.out;
  EXPECT_TRUE(Contains(r.out,
                       "fix: kept 1754 from source 25 (sources: 25 x1755, 52 x1097); "
                       "dropped 1097 of other sources, 1 at a time already taken"))
      << r.out;
  EXPECT_TRUE(Contains(r.out,
                       "fixes: 1754 from 2026-08-03T04:47:01.360Z to "
                       "2026-08-03T04:50:40.701Z UTC (219.3 s), 7.99 Hz, track 644.9 m"))
      << r.out;
  EXPECT_TRUE(Contains(r.out, "heading: none")) << r.out;
  EXPECT_FALSE(LoadDataset(data).has_imu);

  for (const char* command : {"run", "smooth"}) {
    const CliResult e = RunCli(std::string(command) + " --dataset " + Quote(data) + " --out " +
                               Quote(dir + "/result-" + command));
    EXPECT_EQ(e.status, 2) << command << "\n" << e.err;
    EXPECT_TRUE(Contains(e.err, data + "/dataset.yaml: sensors.imu: dataset "
                                       "'furuno-130842-wide-turn' has no IMU"))
        << command << "\n"
        << e.err;
    EXPECT_TRUE(Contains(e.err, std::string("`") + command + "` integrates an IMU")) << e.err;
    EXPECT_FALSE(fs::exists(dir + "/result-" + command + "/summary.json"));
  }
  const CliResult c = RunCli("compare --dataset " + Quote(data) + " --config default --out " +
                             Quote(dir + "/compare"));
  EXPECT_EQ(c.status, 2) << c.err;
  EXPECT_TRUE(Contains(c.err, "has no IMU")) << c.err;

  // A second import into the same folder needs --overwrite; --source picks the other receiver.
  EXPECT_EQ(RunCli("import --format nmea2000 --input " + Quote(kWideTurn) + " --out " + Quote(data))
                .status,
            2);
  const CliResult other = RunCli("import --format nmea2000 --input " + Quote(kWideTurn) +
                                 " --out " + Quote(data) + " --overwrite --source fix=52");
  ASSERT_EQ(other.status, 0) << other.err;
  EXPECT_TRUE(Contains(other.out, "fix: kept 1097 from source 52")) << other.out;
  EXPECT_EQ(LoadDataset(data).gnss_fixes.size(), 1097u);
}

TEST(MarineCli, ImportsNmea0183AndNamesBadInput) {
  const std::string dir = FreshDir("marine_cli_0183");
  const std::string gga = ",4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,";
  WriteLines(dir + "/log.nmea",
             {WithChecksum("GPRMC,120000.00,A,4807.038,N,01131.000,E,5.0,90.0,010524,,,A"),
              WithChecksum("GPGGA,120000.00" + gga), WithChecksum("GPGGA,120001.00" + gga),
              "$GPGGA,120002.00,4807.038,N*00", WithChecksum("HEHDT,90.5,T")});
  const CliResult r = RunCli("import --format nmea0183 " + Quote(dir + "/log.nmea") + " --out " +
                             Quote(dir + "/d"));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(Contains(r.out, "5 lines read, 4 used, 0 of types not used, 1 bad")) << r.out;
  EXPECT_TRUE(Contains(r.out, "bad GGA: checksum mismatch x1 (line 4)")) << r.out;
  EXPECT_TRUE(Contains(r.out, "fixes: 2 from 2024-05-01T12:00:00.000Z")) << r.out;
  const Dataset d = LoadDataset(dir + "/d");
  EXPECT_EQ(d.gnss_fixes.size(), 2u);
  EXPECT_EQ(d.marine.headings.size(), 1u);
  EXPECT_EQ(d.marine.courses.size(), 1u);

  // Unknown format, a file that is not canboat JSON, a bad --source.
  CliResult e = RunCli("import --format nmea --input " + Quote(dir + "/log.nmea") + " --out " +
                       Quote(dir + "/e"));
  EXPECT_EQ(e.status, 2);
  EXPECT_TRUE(Contains(e.err, "--format: expected euroc, husky, nmea0183 or nmea2000")) << e.err;
  e = RunCli("import --format nmea2000 --input " + Quote(dir + "/log.nmea") + " --out " +
             Quote(dir + "/e"));
  EXPECT_EQ(e.status, 2);
  EXPECT_TRUE(Contains(e.err, dir + "/log.nmea: not canboat JSON")) << e.err;
  e = RunCli("import --format nmea0183 --input " + Quote(dir + "/log.nmea") + " --out " +
             Quote(dir + "/e") + " --source gyro=HE");
  EXPECT_EQ(e.status, 2);
  EXPECT_TRUE(Contains(e.err, "--source")) << e.err;
}

}  // namespace
}  // namespace skerry
