// NMEA 0183: the checksum, each sentence type against numbers worked out by hand, and a log
// with every kind of bad line, a time going backwards and a midnight roll-over.
#include "skerry/io/nmea0183.h"

#include <gtest/gtest.h>

#include <cstdio>

#include "core/test_util.h"
#include "io/nmea_test_util.h"
#include "skerry/io/marine_dataset.h"

namespace skerry::nmea0183 {
namespace {

using skerry::testing::FreshDir;
using skerry::testing::WriteLines;

constexpr TimeNs kS = 1000000000;
constexpr TimeNs kDay = 86400 * kS;

using testing::WithChecksum;

template <typename T>
T Parsed(const std::string& line) {
  const ParseResult r = ParseLine(line);
  const auto* s = std::get_if<Sentence>(&r);
  if (s == nullptr) {
    ADD_FAILURE() << line << ": not parsed";
    return T();
  }
  const T* t = std::get_if<T>(&s->data);
  if (t == nullptr) ADD_FAILURE() << line << ": another type";
  return t == nullptr ? T() : *t;
}

BadReason RejectedFor(const std::string& line) {
  const ParseResult r = ParseLine(line);
  const auto* bad = std::get_if<Rejected>(&r);
  if (bad == nullptr) {
    ADD_FAILURE() << line << ": not rejected";
    return BadReason::kNotASentence;
  }
  return bad->reason;
}

TEST(Nmea0183Checksum, MatchesPublishedSentences) {
  // The examples of the NMEA references (gpsd's "NMEA Revealed"), with their checksums.
  EXPECT_EQ(Checksum("GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,"), 0x47);
  EXPECT_EQ(Checksum("GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W"), 0x6A);
  EXPECT_EQ(Checksum("GPVTG,054.7,T,034.4,M,005.5,N,010.2,K"), 0x48);
  EXPECT_EQ(Checksum(""), 0x00);
  EXPECT_EQ(Checksum("A"), 0x41);
  EXPECT_EQ(Checksum("AA"), 0x00);
  // Lower-case hex is accepted; one wrong digit is a mismatch.
  EXPECT_TRUE(
      std::holds_alternative<Sentence>(ParseLine("$GPVTG,054.7,T,034.4,M,005.5,N,010.2,K*48")));
  EXPECT_TRUE(
      std::holds_alternative<Sentence>(ParseLine("$GPRMC,123519,A,4807.038,N,01131.000,E,"
                                                 "022.4,084.4,230394,003.1,W*6a")));
  EXPECT_EQ(RejectedFor("$GPVTG,054.7,T,034.4,M,005.5,N,010.2,K*49"), BadReason::kChecksumMismatch);
  EXPECT_EQ(RejectedFor("$GPVTG,054.7,T,034.4,M,005.5,N,010.2,K*4G"), BadReason::kChecksumMismatch);
  EXPECT_EQ(RejectedFor("$GPVTG,054.7,T,034.4,M,005.5,N,010.2,K*4"), BadReason::kTruncated);
  EXPECT_EQ(RejectedFor("$GPVTG,054.7,T,034.4,M,005.5,N,010.2,K"), BadReason::kMissingChecksum);
  EXPECT_EQ(RejectedFor("$GPVTG,054.7,T,034.4,M"), BadReason::kTruncated);
  EXPECT_EQ(RejectedFor("no sentence here"), BadReason::kNotASentence);
}

TEST(Nmea0183Parse, Gga) {
  const Gga g = Parsed<Gga>("$GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*47");
  EXPECT_EQ(g.time_of_day_ns, (12 * 3600 + 35 * 60 + 19) * kS);
  EXPECT_DOUBLE_EQ(g.lat_deg, 48.1173);  // 48 deg + 7.038 min / 60
  EXPECT_DOUBLE_EQ(g.lon_deg, 11.0 + 31.0 / 60.0);
  EXPECT_EQ(g.quality, 1);
  EXPECT_EQ(g.kind, FixKind::kAutonomous);
  EXPECT_EQ(*g.hdop, 0.9);
  EXPECT_EQ(*g.altitude_msl_m, 545.4);
  EXPECT_EQ(*g.geoid_separation_m, 46.9);
  // South and west are negative; RTK fixed; empty altitude and HDOP are absent.
  const Gga s = Parsed<Gga>(WithChecksum("GNGGA,000000.25,3351.300,S,15112.600,W,4,12,,,M,,M,,"));
  EXPECT_EQ(s.time_of_day_ns, kS / 4);
  EXPECT_DOUBLE_EQ(s.lat_deg, -(33.0 + 51.3 / 60.0));
  EXPECT_DOUBLE_EQ(s.lon_deg, -(151.0 + 12.6 / 60.0));
  EXPECT_EQ(s.kind, FixKind::kRtkFixed);
  EXPECT_FALSE(s.hdop.has_value());
  EXPECT_FALSE(s.altitude_msl_m.has_value());
  // Bad fields.
  EXPECT_EQ(
      RejectedFor(WithChecksum("GPGGA,123519,4807.038,N,01131.000,E,0,08,0.9,545.4,M,46.9,M,,")),
      BadReason::kInvalidFix);
  EXPECT_EQ(
      RejectedFor(WithChecksum("GPGGA,123519,4807.038,N,01131.000,E,6,08,0.9,545.4,M,46.9,M,,")),
      BadReason::kInvalidFix);
  EXPECT_EQ(
      RejectedFor(WithChecksum("GPGGA,123519,48x7.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,")),
      BadReason::kBadNumber);
  // A quality far beyond one digit (found by the fuzzer: 1e117 cast to int was undefined).
  EXPECT_EQ(RejectedFor(WithChecksum("GPGGA,123519,4807.038,N,01131.000,E," +
                                     std::string(117, '9') + ",08,0.9,545.4,M,,M,,")),
            BadReason::kBadNumber);
  EXPECT_EQ(RejectedFor(WithChecksum("GPGGA,123519,,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,")),
            BadReason::kEmptyField);
  EXPECT_EQ(
      RejectedFor(WithChecksum("GPGGA,123519,9107.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,")),
      BadReason::kOutOfRange);
  EXPECT_EQ(
      RejectedFor(WithChecksum("GPGGA,123519,4807.038,N,01131.000,E,1,08,nan,545.4,M,46.9,M,,")),
      BadReason::kNonFinite);
  EXPECT_EQ(
      RejectedFor(WithChecksum("GPGGA,126519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,")),
      BadReason::kBadNumber);  // minute 65
  EXPECT_EQ(
      RejectedFor(WithChecksum("GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M")),
      BadReason::kFieldCount);
}

TEST(Nmea0183Parse, RmcVtgHdtThsGst) {
  const Rmc r = Parsed<Rmc>("$GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W*6A");
  EXPECT_EQ(r.time_of_day_ns, 45319 * kS);
  EXPECT_EQ(r.days_since_epoch, 8847);  // 1994-03-23
  EXPECT_DOUBLE_EQ(r.lat_deg, 48.1173);
  EXPECT_DOUBLE_EQ(*r.sog_m_s, 22.4 * 1852.0 / 3600.0);  // 11.5236 m/s
  EXPECT_EQ(*r.cog_deg, 84.4);
  EXPECT_EQ(
      RejectedFor(WithChecksum("GPRMC,123519,V,4807.038,N,01131.000,E,022.4,084.4,230394,003.1,W")),
      BadReason::kInvalidFix);
  EXPECT_EQ(
      RejectedFor(WithChecksum("GPRMC,123519,A,4807.038,N,01131.000,E,022.4,084.4,300294,003.1,W")),
      BadReason::kBadNumber);  // 30 February
  // NMEA 2.3 with the mode, at rest without a course; 2000 is 20yy.
  const Rmc rest =
      Parsed<Rmc>(WithChecksum("GNRMC,235959.999,A,4807.038,N,01131.000,E,0.0,,010100,,,D"));
  EXPECT_EQ(rest.days_since_epoch, 10957);  // 2000-01-01
  EXPECT_EQ(rest.time_of_day_ns, 86399 * kS + 999000000);
  EXPECT_FALSE(rest.cog_deg.has_value());
  EXPECT_EQ(*rest.sog_m_s, 0.0);

  const Vtg v = Parsed<Vtg>("$GPVTG,054.7,T,034.4,M,005.5,N,010.2,K*48");
  EXPECT_EQ(v.cog_deg, 54.7);
  EXPECT_DOUBLE_EQ(v.sog_m_s, 5.5 * 1852.0 / 3600.0);  // 2.8294 m/s
  EXPECT_EQ(RejectedFor(WithChecksum("GPVTG,054.7,T,034.4,M,005.5,N,010.2,K,N")),
            BadReason::kInvalidFix);

  EXPECT_EQ(Parsed<Hdt>("$HEHDT,274.07,T*19").heading_deg, 274.07);
  EXPECT_EQ(Parsed<Hdt>(WithChecksum("HEHDT,360.0,T")).heading_deg, 0.0);
  EXPECT_EQ(RejectedFor(WithChecksum("HEHDT,361.0,T")), BadReason::kOutOfRange);
  EXPECT_EQ(Parsed<Ths>("$INTHS,274.07,A*11").heading_deg, 274.07);
  for (const char* mode : {"E", "M", "S", "V"}) {
    EXPECT_EQ(RejectedFor(WithChecksum(std::string("INTHS,274.07,") + mode)),
              BadReason::kInvalidFix)
        << mode;
  }
  EXPECT_EQ(RejectedFor(WithChecksum("INTHS,274.07,X")), BadReason::kBadNumber);

  const Gst g = Parsed<Gst>("$GPGST,172814.0,0.006,0.023,0.020,273.6,0.023,0.020,0.031*6A");
  EXPECT_EQ(g.time_of_day_ns, (17 * 3600 + 28 * 60 + 14) * kS);
  EXPECT_EQ(g.sigma_lat_m, 0.023);
  EXPECT_EQ(g.sigma_lon_m, 0.020);
  EXPECT_EQ(g.sigma_alt_m, 0.031);
  EXPECT_EQ(RejectedFor(WithChecksum("GPGST,172814.0,0.006,0.023,0.020,273.6,,,")),
            BadReason::kEmptyField);

  // Talker-independent; other types and proprietary sentences are ignored, not bad.
  EXPECT_TRUE(std::holds_alternative<Sentence>(
      ParseLine(WithChecksum("INVTG,054.7,T,034.4,M,005.5,N,010.2,K,A"))));
  const ParseResult gsv = ParseLine(WithChecksum("GPGSV,3,1,11,03,03,111,00,04,15,270,00"));
  ASSERT_TRUE(std::holds_alternative<Ignored>(gsv));
  EXPECT_EQ(std::get<Ignored>(gsv).type, "GSV");
  EXPECT_TRUE(
      std::holds_alternative<Ignored>(ParseLine(WithChecksum("PGRME,15.0,M,45.0,M,25.0,M"))));
  // A logger's timestamp before the sentence, and CRLF.
  EXPECT_EQ(Parsed<Hdt>("2024-05-01T10:00:00.123Z $HEHDT,274.07,T*19\r").heading_deg, 274.07);
  EXPECT_EQ(Parsed<Hdt>("1714557600.123,$HEHDT,274.07,T*19").heading_deg, 274.07);
}

TEST(Nmea0183Parse, TimeOfDayAndCoordinates) {
  EXPECT_EQ(*ParseTimeOfDay("000000"), 0);
  EXPECT_EQ(*ParseTimeOfDay("235959.123456789"), 86399 * kS + 123456789);
  EXPECT_FALSE(ParseTimeOfDay("240000").has_value());
  EXPECT_FALSE(ParseTimeOfDay("12345").has_value());
  EXPECT_FALSE(ParseTimeOfDay("123456.").has_value());
  EXPECT_DOUBLE_EQ(*ParseCoordinate("4807.038", "N"), 48.1173);
  EXPECT_DOUBLE_EQ(*ParseCoordinate("00030.000", "W"), -0.5);
  EXPECT_FALSE(ParseCoordinate("4860.000", "N").has_value());  // 60 minutes
  EXPECT_FALSE(ParseCoordinate("48", "N").has_value());
}

// The log of the brief: every kind of bad line, an unknown sentence, a time going backwards and
// a midnight roll-over, with the exact counts expected.
TEST(Nmea0183Log, CountsEveryBadLineAndRollsOverMidnight) {
  const std::string dir = FreshDir("nmea0183");
  const std::string gga_rest = ",4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,";
  std::string corrupted = WithChecksum("GPGGA,235959.50" + gga_rest);
  corrupted[corrupted.size() - 1] = corrupted.back() == '0' ? '1' : '0';
  const std::vector<std::string> lines = {
      WithChecksum("GPRMC,235958.00,A,4807.038,N,01131.000,E,5.0,90.0,311224,,,A"),  // 1
      WithChecksum("GPGGA,235958.00" + gga_rest),                                    // 2 fix 1
      WithChecksum("GPGST,235958.00,1.0,0.5,0.4,10.0,0.3,0.4,0.8"),                  // 3
      WithChecksum("HEHDT,90.5,T"),                                                  // 4
      WithChecksum("GPGGA,235959.00" + gga_rest),                                    // 5 fix 2
      corrupted,                                                                     // 6
      WithChecksum("GPGSV,3,1,11,03,03,111,00,04,15,270,00"),                        // 7 ignored
      WithChecksum("GPGGA,000000.00" + gga_rest),         // 8 fix 3, next day
      "$GPGGA,000000.50,4807.0",                          // 9 truncated
      WithChecksum("GPGGA,000001.00" + gga_rest) + "\r",  // 10 fix 4
      WithChecksum("GPGGA,000000.50" + gga_rest),         // 11 backwards
      WithChecksum("GPRMC,000001.00,A,4807.038,N,01131.000,E,5.2,91.0,010125,,,A"),      // 12
      WithChecksum("GPTHS,91.0,E"),                                                      // 13
      WithChecksum("GPVTG,091.0,T,,M,005.2,N,009.6,K,N"),                                // 14
      WithChecksum("GPGGA,000001.00,4807.038,N,01131.000,E,0,00,,,M,,M,,"),              // 15
      WithChecksum("GPGGA,000001.00,48x7.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,"),  // 16
      WithChecksum("GPGGA,000001.00,,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,"),          // 17
      WithChecksum("HEHDT,91.0,T,EXTRA"),                                                // 18
      "$HEHDT,91.0,T",                                                                   // 19
      "a line of noise",                                                                 // 20
      "2025-01-01T00:00:01.100Z " + WithChecksum("HEHDT,92.0,T"),                        // 21
      "",                                                                                // 22
  };
  WriteLines(dir + "/log.nmea", lines);
  const MarineLog log = ReadLog(dir + "/log.nmea");
  const MarineLogStats& st = log.stats;
  EXPECT_EQ(st.lines, 21);
  EXPECT_EQ(st.used, 9);  // RMC x2, GGA x4, GST, HDT x2
  EXPECT_EQ(st.ignored, 1);
  EXPECT_EQ(st.ignored_by_type.at("GSV"), 1);
  EXPECT_EQ(st.BadCount(), 11);
  EXPECT_EQ(st.BadCount("GGA", BadReason::kChecksumMismatch), 1);
  EXPECT_EQ(st.BadCount("GGA", BadReason::kTruncated), 1);
  EXPECT_EQ(st.BadCount("GGA", BadReason::kTimeBackwards), 1);
  EXPECT_EQ(st.BadCount("THS", BadReason::kInvalidFix), 1);
  EXPECT_EQ(st.BadCount("VTG", BadReason::kInvalidFix), 1);
  EXPECT_EQ(st.BadCount("GGA", BadReason::kInvalidFix), 1);
  EXPECT_EQ(st.BadCount("GGA", BadReason::kBadNumber), 1);
  EXPECT_EQ(st.BadCount("GGA", BadReason::kEmptyField), 1);
  EXPECT_EQ(st.BadCount("HDT", BadReason::kFieldCount), 1);
  EXPECT_EQ(st.BadCount("HDT", BadReason::kMissingChecksum), 1);
  EXPECT_EQ(st.BadCount("?", BadReason::kNotASentence), 1);
  EXPECT_EQ(st.bad.at({"GGA", BadReason::kTimeBackwards}).first_lines, std::vector<int>{11});
  EXPECT_EQ(st.bad.at({"GGA", BadReason::kChecksumMismatch}).first_lines, std::vector<int>{6});

  // 2024-12-31 is day 20088 since 1970-01-01; the roll-over makes 00:00:00 the next day.
  const TimeNs dec31 = 20088 * kDay;
  ASSERT_EQ(log.fixes.size(), 4u);
  EXPECT_EQ(log.fixes[0].t_ns, dec31 + 86398 * kS);
  EXPECT_EQ(log.fixes[1].t_ns, dec31 + 86399 * kS);
  EXPECT_EQ(log.fixes[2].t_ns, dec31 + kDay);
  EXPECT_EQ(log.fixes[3].t_ns, dec31 + kDay + kS);
  EXPECT_EQ(log.fixes[0].source, "GP");
  // Ellipsoidal height = altitude + geoid separation.
  EXPECT_DOUBLE_EQ(*log.fixes[0].height_m, 545.4 + 46.9);
  // GST gives the first fix the receiver's sigmas; the others come from HDOP 0.9 x UERE 4 m.
  EXPECT_EQ(log.fixes[0].sigma_source, FixSigmaSource::kReceiver);
  EXPECT_EQ(log.fixes[0].sigma_north_m, 0.3);
  EXPECT_EQ(log.fixes[0].sigma_east_m, 0.4);
  EXPECT_EQ(log.fixes[0].sigma_up_m, 0.8);
  EXPECT_EQ(log.fixes[1].sigma_source, FixSigmaSource::kHdop);
  EXPECT_NEAR(log.fixes[1].sigma_east_m, 2.545584412271571, 1e-12);  // 0.9 * 4 / sqrt(2)
  EXPECT_NEAR(log.fixes[1].sigma_up_m, 5.4, 1e-12);                  // 1.5 * 0.9 * 4

  ASSERT_EQ(log.records.headings.size(), 2u);
  EXPECT_EQ(log.records.headings[0].t_ns, dec31 + 86398 * kS);  // the epoch's time
  EXPECT_EQ(log.records.headings[0].heading_deg, 90.5);
  EXPECT_EQ(log.records.headings[1].t_ns, dec31 + kDay + kS);
  EXPECT_EQ(log.records.headings[1].heading_deg, 92.0);
  ASSERT_EQ(log.records.courses.size(), 2u);
  EXPECT_EQ(log.records.courses[1].cog_deg, 91.0);
  EXPECT_DOUBLE_EQ(log.records.courses[1].sog_m_s, 5.2 * 1852.0 / 3600.0);

  // As a dataset: four fixes a second apart, origin at the first.
  const Dataset data = MarineLogToDataset(log);
  EXPECT_EQ(data.name, "log");
  EXPECT_FALSE(data.has_imu);
  ASSERT_EQ(data.gnss_fixes.size(), 4u);
  EXPECT_DOUBLE_EQ(data.origin.lat_deg, 48.1173);
  EXPECT_DOUBLE_EQ(data.origin.height_m, 592.3);
  EXPECT_LT(data.gnss_fixes[0].p_w.norm(), 1e-6);
  EXPECT_EQ(data.gnss_fixes[0].sigma_enu_m, Eigen::Vector3d(0.4, 0.3, 0.8));
}

TEST(Nmea0183Log, WithoutRmcNothingIsDatedAndNoFixRemains) {
  const std::string dir = FreshDir("nmea0183_no_rmc");
  WriteLines(dir + "/gga.nmea",
             {WithChecksum("GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,"),
              WithChecksum("HEHDT,90.5,T")});
  const MarineLog log = ReadLog(dir + "/gga.nmea");
  EXPECT_EQ(log.stats.BadCount("GGA", BadReason::kNoTime), 1);
  EXPECT_EQ(log.stats.BadCount("HDT", BadReason::kNoTime), 1);
  EXPECT_TRUE(log.fixes.empty());
  skerry::testing::ExpectInputError([&] { MarineLogToDataset(log); }, "gga.nmea", 0, "");
  skerry::testing::ExpectInputError([&] { ReadLog(dir + "/missing.nmea"); }, "missing.nmea", 0, "");
}

// Sentences before the first RMC take its date, or the day before across midnight.
TEST(Nmea0183Log, DatesSentencesBeforeTheFirstRmc) {
  const std::string dir = FreshDir("nmea0183_before_rmc");
  WriteLines(dir + "/log.nmea",
             {WithChecksum("GPGGA,235959.00,4807.038,N,01131.000,E,2,08,1.0,545.4,M,46.9,M,,"),
              WithChecksum("GPRMC,000000.00,A,4807.038,N,01131.000,E,0.0,,010125,,,A")});
  const MarineLog log = ReadLog(dir + "/log.nmea");
  ASSERT_EQ(log.fixes.size(), 1u);
  EXPECT_EQ(log.fixes[0].t_ns, 20088 * kDay + 86399 * kS);              // 2024-12-31 23:59:59
  EXPECT_NEAR(log.fixes[0].sigma_east_m, 1.0 / std::sqrt(2.0), 1e-12);  // DGPS: UERE 1 m
  EXPECT_EQ(log.stats.BadCount(), 0);
}

}  // namespace
}  // namespace skerry::nmea0183
