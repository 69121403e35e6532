// NMEA 2000 as canboat JSON: a log written here with every kind of bad record, files that are
// not canboat JSON, and the real Furuno boat log of ../shared/data/boat against figures computed
// independently from the same file (python3, gzip + json, its own WGS84 ECEF -> ENU).
#include "skerry/io/nmea2000_json.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "core/test_util.h"
#include "skerry/io/marine_dataset.h"

namespace skerry::nmea2000 {
namespace {

namespace fs = std::filesystem;
using skerry::testing::ExpectInputError;
using skerry::testing::FreshDir;
using skerry::testing::WriteLines;

constexpr TimeNs kS = 1000000000;
const std::string kWideTurn =
    std::string(SKERRY_SHARED_DATA_DIR) + "/boat/furuno-130842-wide-turn.si.jsonl.gz";
const std::string kHeader = R"({"version":"8.0.0-beta3","units":"si","showLookupValues":false})";

// One canboat record at 2026-08-03T04:47:<second>Z.
std::string Record(const std::string& second, int pgn, int src, const std::string& fields) {
  return R"({"timestamp":"2026-08-03T04:47:)" + second + R"(Z","prio":2,"src":)" +
         std::to_string(src) + R"(,"dst":255,"pgn":)" + std::to_string(pgn) +
         R"(,"description":"x","fields":)" + fields + "}";
}

TEST(Nmea2000Json, ReadsEachPgnAndCountsBadRecords) {
  const std::string dir = FreshDir("n2k");
  const std::vector<std::string> lines = {
      kHeader,                                                                             // 1
      Record("01.000", 129025, 25, R"({"Latitude":34.4012383,"Longitude":133.5591560})"),  // 2
      Record("01.100", 129029, 3,
             R"({"Latitude":34.5,"Longitude":133.5,"Altitude":41.25,"HDOP":1.5,)"
             R"("Method":"DGNSS fix","Geoidal Separation":35.0})"),                         // 3
      Record("01.200", 129026, 25, R"({"COG Reference":"True","COG":5.0824,"SOG":2.76})"),  // 4
      Record("01.300", 127250, 36,
             R"({"Heading":2.4277,"Deviation":0.0100,"Variation":0.0698,"Reference":"Magnetic"})"),
      Record("01.400", 127257, 52, R"({"Yaw":-1.2473,"Pitch":-0.0294,"Roll":0.0606})"),  // 6
      Record("01.500", 127251, 27, R"({"SID":0,"Rate":-0.00044031})"),                   // 7
      Record("01.600", 128259, 35, R"({"Speed Water Referenced":2.16})"),  // 8 not read
      R"({"timestamp":"2026-08-03T04:47:01.700Z","src":25,"pgn":129025,"fields":{"Lat)",  // 9
      Record("01.800", 129025, 25, R"({"Latitude":34.4})"),                      // 10 missing
      Record("01.900", 129025, 25, R"({"Latitude":34.4,"Longitude":1e999})"),    // 11 not JSON
      Record("02.000", 129025, 25, R"({"Latitude":"34.4","Longitude":133.5})"),  // 12 type
      Record("02.100", 129025, 25, R"({"Latitude":94.4,"Longitude":133.5})"),    // 13 range
      Record("02.200", 129029, 3,
             R"({"Latitude":34.5,"Longitude":133.5,"Method":"no GNSS"})"),  // 14
      Record("02.300", 129029, 3,
             R"({"Latitude":34.5,"Longitude":133.5,"Altitude":1441151966657.9,)"
             R"("HDOP":0.0,"Method":"GNSS fix"})"),                                     // 15 range
      Record("02.400", 127250, 36, R"({"Heading":2.4,"Reference":"Magnetic"})"),        // 16
      Record("02.500", 129026, 25, R"({"COG Reference":"Magnetic","COG":1,"SOG":2})"),  // 17
      Record("01.950", 127251, 27, R"({"Rate":0.01})"),                                 // 18 back
      R"({"timestamp":"2026-08-03T04:47:02.600Z","src":36,"pgn":129025})",              // 19
      R"({"timestamp":"2026-08-03 04:47","src":36,"pgn":129025,"fields":{}})",          // 20 time
      "",                                                                               // blank
      R"({"timestamp":"2026-08-03-04:47:02.700","src":27,"pgn":127251,"fields":{"Rate":0.02}})",
  };
  WriteLines(dir + "/log.jsonl", lines);
  const MarineLog log = ReadCanboatJson(dir + "/log.jsonl");
  const MarineLogStats& st = log.stats;
  EXPECT_EQ(st.lines, 20);  // the header and the blank line are not counted
  EXPECT_EQ(st.used, 7);
  EXPECT_EQ(st.ignored, 1);
  EXPECT_EQ(st.ignored_by_type.at("128259"), 1);
  EXPECT_EQ(st.BadCount(), 12);
  // NaN and infinity are not JSON: 1e999 overflows, and the line is malformed (line 11).
  EXPECT_EQ(st.BadCount("?", BadReason::kMalformedJson), 2);
  EXPECT_EQ(st.bad.at({"?", BadReason::kMalformedJson}).first_lines, (std::vector<int>{9, 11}));
  EXPECT_EQ(st.BadCount("129025", BadReason::kMissingField), 2);  // lines 10 and 19
  EXPECT_EQ(st.bad.at({"129025", BadReason::kMissingField}).first_lines,
            (std::vector<int>{10, 19}));
  EXPECT_EQ(st.BadCount("129025", BadReason::kBadNumber), 2);  // lines 12 and 20
  EXPECT_EQ(st.BadCount("129025", BadReason::kOutOfRange), 1);
  EXPECT_EQ(st.BadCount("129029", BadReason::kInvalidFix), 1);
  EXPECT_EQ(st.BadCount("129029", BadReason::kOutOfRange), 1);
  EXPECT_EQ(st.BadCount("127250", BadReason::kMagneticNoVariation), 1);
  EXPECT_EQ(st.BadCount("129026", BadReason::kMagneticNoVariation), 1);
  EXPECT_EQ(st.BadCount("127251", BadReason::kTimeBackwards), 1);

  const TimeNs t0 = SecondsToNs(1785732420.0) + kS;  // 2026-08-03T04:47:01Z
  ASSERT_EQ(log.fixes.size(), 2u);
  EXPECT_EQ(log.fixes[0].t_ns, t0);
  EXPECT_EQ(log.fixes[0].lat_deg, 34.4012383);
  EXPECT_EQ(log.fixes[0].source, "25");
  EXPECT_FALSE(log.fixes[0].height_m.has_value());
  EXPECT_EQ(log.fixes[0].sigma_source, FixSigmaSource::kAssumed);
  EXPECT_EQ(log.fixes[1].t_ns, t0 + kS / 10);
  EXPECT_EQ(*log.fixes[1].height_m, 41.25);
  EXPECT_EQ(log.fixes[1].sigma_source, FixSigmaSource::kHdop);
  EXPECT_NEAR(log.fixes[1].sigma_east_m, 1.5 * 1.0 / std::sqrt(2.0), 1e-12);  // DGNSS: 1 m
  ASSERT_EQ(log.records.courses.size(), 1u);
  EXPECT_NEAR(log.records.courses[0].cog_deg, 5.0824 * 180.0 / M_PI, 1e-9);  // 291.20 deg
  EXPECT_EQ(log.records.courses[0].sog_m_s, 2.76);
  ASSERT_EQ(log.records.headings.size(), 1u);
  // Magnetic 2.4277 rad + deviation 0.01 + variation 0.0698 = 2.5075 rad true.
  EXPECT_NEAR(log.records.headings[0].heading_deg, 2.5075 * 180.0 / M_PI, 1e-9);
  EXPECT_TRUE(log.records.headings[0].from_magnetic);
  ASSERT_EQ(log.records.attitudes.size(), 1u);
  EXPECT_NEAR(*log.records.attitudes[0].yaw_deg, -1.2473 * 180.0 / M_PI, 1e-9);
  EXPECT_NEAR(log.records.attitudes[0].roll_deg, 0.0606 * 180.0 / M_PI, 1e-9);
  ASSERT_EQ(log.records.rates_of_turn.size(), 2u);
  EXPECT_NEAR(log.records.rates_of_turn[0].rate_deg_s, -0.025227904677405277, 1e-12);
  EXPECT_EQ(log.records.rates_of_turn[1].t_ns, t0 + 1700 * kS / 1000);  // canboat's old spelling
}

TEST(Nmea2000Json, RefusesFilesThatAreNotCanboatJson) {
  const std::string dir = FreshDir("n2k_not");
  WriteLines(dir + "/fix.csv", {"t,lat,lon", "1,2,3"});
  ExpectInputError([&] { ReadCanboatJson(dir + "/fix.csv"); }, "fix.csv", 0, "");
  WriteLines(dir + "/empty.jsonl", {});
  ExpectInputError([&] { ReadCanboatJson(dir + "/empty.jsonl"); }, "empty.jsonl", 0, "");
  WriteLines(dir + "/std.jsonl",
             {R"({"version":"5","units":"std"})", Record("01.000", 127251, 27, R"({"Rate":1})")});
  ExpectInputError([&] { ReadCanboatJson(dir + "/std.jsonl"); }, "std.jsonl", 1, "units");
  WriteLines(dir + "/headless.jsonl", {Record("01.000", 127251, 27, R"({"Rate":1})")});
  ExpectInputError([&] { ReadCanboatJson(dir + "/headless.jsonl"); }, "headless.jsonl", 1, "units");
  ExpectInputError([&] { ReadCanboatJson(dir + "/none.jsonl"); }, "none.jsonl", 0, "");
}

class Nmea2000RealLog : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!fs::exists(kWideTurn)) GTEST_SKIP() << kWideTurn << " missing";
  }
};

// Figures from python3 over the same file (gzip + json; WGS84 ECEF -> ENU at the first fix):
// 21,191 lines = header + 21,190 records, 15,483 of the six PGNs read, 5,707 others; position
// (129025) from src 25 x1755 (one repeated timestamp: 1754 distinct) and src 52 x1097; 1754
// fixes from 04:47:01.360 to 04:50:40.701 (219.341 s, 7.9921 Hz), horizontal track 644.882 m.
TEST_F(Nmea2000RealLog, FurunoWideTurn) {
  const MarineLog log = ReadCanboatJson(kWideTurn);
  EXPECT_EQ(log.stats.lines, 21190);
  EXPECT_EQ(log.stats.used, 15483);
  EXPECT_EQ(log.stats.ignored, 5707);
  EXPECT_EQ(log.stats.BadCount(), 0) << DescribeStats(log.stats);
  EXPECT_EQ(log.fixes.size(), 1755u + 1097u);

  MarineSelection sel;
  const Dataset data = MarineLogToDataset(log, {}, &sel);
  EXPECT_EQ(data.name, "furuno-130842-wide-turn");
  EXPECT_FALSE(data.has_imu);
  EXPECT_TRUE(data.has_gnss);
  const MarineKindSelection& fix = sel.at(MarineKind::kFix);
  EXPECT_EQ(fix.source, "25");
  EXPECT_EQ(fix.other_sources, 1097);
  EXPECT_EQ(fix.duplicates, 1);
  EXPECT_EQ(fix.kept, 1754);
  ASSERT_EQ(data.gnss_fixes.size(), 1754u);
  EXPECT_EQ(data.origin.lat_deg, 34.4012383);
  EXPECT_EQ(data.origin.lon_deg, 133.559156);
  EXPECT_EQ(data.origin.height_m, 0.0);  // 129025 has no height
  EXPECT_EQ(
      data.gnss_fixes[0].sigma_enu_m,
      Eigen::Vector3d(kAssumedSigmaHorizontalM, kAssumedSigmaHorizontalM, kUnknownHeightSigmaM));
  const TrackFigures track = FixTrackFigures(data.gnss_fixes);
  EXPECT_EQ(track.fixes, 1754);
  EXPECT_NEAR(track.span_s, 219.341, 1e-9);
  EXPECT_NEAR(track.rate_hz, 7.992121855922969, 1e-9);
  EXPECT_NEAR(track.length_m, 644.8820605750914, 0.01);
  // The other kinds: course and attitude from src 52, rate of turn from src 27, no heading.
  EXPECT_EQ(sel.at(MarineKind::kCourse).source, "52");
  EXPECT_EQ(data.marine.courses.size(), 878u);
  EXPECT_EQ(sel.at(MarineKind::kAttitude).source, "52");
  EXPECT_EQ(data.marine.attitudes.size(), 2195u);
  EXPECT_TRUE(data.marine.attitudes[0].yaw_deg.has_value());
  EXPECT_EQ(sel.at(MarineKind::kRateOfTurn).source, "27");
  EXPECT_EQ(data.marine.rates_of_turn.size(), 4384u);
  EXPECT_TRUE(data.marine.headings.empty());
  // Choosing the other position source.
  MarineDatasetOptions other;
  other.sources[MarineKind::kFix] = "52";
  EXPECT_EQ(MarineLogToDataset(log, other).gnss_fixes.size(), 1097u);
  other.sources[MarineKind::kFix] = "99";
  ExpectInputError([&] { MarineLogToDataset(log, other); }, "wide-turn.si.jsonl.gz", 0, "fix");
}

// Import, write, load: a dataset without IMU comes back the same, with its marine files.
TEST_F(Nmea2000RealLog, RoundTripWithoutImu) {
  const Dataset data = MarineLogToDataset(ReadCanboatJson(kWideTurn));
  const std::string dir = FreshDir("n2k_dataset");
  WriteDataset(data, dir);
  EXPECT_FALSE(fs::exists(dir + "/imu.csv"));
  EXPECT_TRUE(fs::exists(dir + "/course.csv"));
  EXPECT_FALSE(fs::exists(dir + "/heading.csv"));  // none in this log
  const Dataset back = LoadDataset(dir);
  EXPECT_FALSE(back.has_imu);
  EXPECT_TRUE(back.imu_samples.empty());
  EXPECT_TRUE(back.imu_path.empty());
  ASSERT_EQ(back.gnss_fixes.size(), data.gnss_fixes.size());
  for (std::size_t k = 0; k < data.gnss_fixes.size(); ++k) {
    EXPECT_EQ(back.gnss_fixes[k].t_ns, data.gnss_fixes[k].t_ns);
    EXPECT_EQ(back.gnss_fixes[k].lat_deg, data.gnss_fixes[k].lat_deg);
    EXPECT_LT((back.gnss_fixes[k].p_w - data.gnss_fixes[k].p_w).norm(), 1e-9);
  }
  EXPECT_EQ(back.marine.courses.size(), data.marine.courses.size());
  EXPECT_EQ(back.marine.courses.back().cog_deg, data.marine.courses.back().cog_deg);
  EXPECT_EQ(back.marine.attitudes.size(), data.marine.attitudes.size());
  EXPECT_EQ(*back.marine.attitudes[7].yaw_deg, *data.marine.attitudes[7].yaw_deg);
  EXPECT_EQ(back.marine.rates_of_turn.size(), data.marine.rates_of_turn.size());
  EXPECT_EQ(back.marine.rates_of_turn[3].rate_deg_s, data.marine.rates_of_turn[3].rate_deg_s);
  EXPECT_EQ(back.marine.rates_of_turn[3].t_ns, data.marine.rates_of_turn[3].t_ns);
  ExpectInputError([&] { RequireImu(back, "run"); }, "dataset.yaml", 0, "sensors.imu");
  // Written again, it is the same folder.
  const std::string again = FreshDir("n2k_dataset_again");
  WriteDataset(back, again);
  for (const char* file :
       {"dataset.yaml", "gnss.csv", "course.csv", "attitude.csv", "rate_of_turn.csv"}) {
    EXPECT_EQ(skerry::testing::ReadText(dir + "/" + file),
              skerry::testing::ReadText(again + "/" + file))
        << file;
  }
}

}  // namespace
}  // namespace skerry::nmea2000
