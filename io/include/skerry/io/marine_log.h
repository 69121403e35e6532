#pragma once
/// \file
/// A marine log in memory: what the NMEA 0183 reader (nmea0183.h) and the NMEA 2000 reader of
/// canboat's JSON (nmea2000_json.h) both fill, before it becomes a skerry Dataset
/// (marine_dataset.h). Every record keeps the source that sent it; bad sentences or records are
/// counted per type and reason, never fatal (docs/marine_logs.md).
///
/// Units: time int64 nanoseconds since the Unix epoch (UTC); angles in degrees, headings and
/// courses clockwise from true north in [0, 360); speeds m/s; heights ellipsoidal metres.

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "skerry/core/time.h"

namespace skerry {

/// Where a fix's sigmas came from.
enum class FixSigmaSource {
  kReceiver,  ///< the receiver's own error estimate (NMEA 0183 GST)
  kHdop,      ///< HDOP times a user range error assumed per fix quality (docs/marine_logs.md)
  kAssumed,   ///< nothing sent: kAssumedSigmaHorizontalM / kAssumedSigmaVerticalM
};
const char* FixSigmaSourceName(FixSigmaSource source);

/// What kind of solution a fix is (GGA quality, 129029 method); it sets the user range error
/// (UERE) that HDOP is multiplied by.
enum class FixKind { kAutonomous, kDifferential, kRtkFloat, kRtkFixed };

/// The 1-sigma user range error assumed per kind of fix, metres: autonomous 4.0 (single
/// frequency, no corrections), differential / SBAS 1.0, RTK float 0.3, RTK fixed 0.02.
double UereM(FixKind kind);

/// Sigmas assumed for a fix sent with neither a receiver sigma (GST) nor an HDOP (NMEA 2000
/// 129025 alone): an autonomous receiver at HDOP 1.4.
inline constexpr double kAssumedSigmaHorizontalM = 4.0;  ///< per horizontal axis
inline constexpr double kAssumedSigmaVerticalM = 8.4;
/// A fix without a height (129025, a GGA without altitude or geoid separation) gets the
/// dataset origin's height with this vertical sigma in gnss.csv.
inline constexpr double kUnknownHeightSigmaM = 100.0;

/// A position fix. Sigmas are 1-sigma per axis (east, north, up), metres.
struct MarineFix {
  TimeNs t_ns = 0;
  double lat_deg = 0.0;
  double lon_deg = 0.0;
  std::optional<double> height_m;  ///< ellipsoidal; absent when the source sent none
  double sigma_east_m = 0.0;
  double sigma_north_m = 0.0;
  double sigma_up_m = 0.0;
  FixSigmaSource sigma_source = FixSigmaSource::kAssumed;
  std::string source;  ///< NMEA 2000: the `src` address; NMEA 0183: the talker (GP, GN, ...)
};

/// Sets `fix`'s sigmas from HDOP (> 0): per horizontal axis HDOP * UERE / sqrt(2) (HDOP * UERE
/// is the 2-D RMS), vertical 1.5 * HDOP * UERE (VDOP taken as 1.5 HDOP, typical of an open sky);
/// sigma_source kHdop.
void SetSigmasFromHdop(double hdop, FixKind kind, MarineFix* fix);
/// Sets the assumed sigmas (kAssumedSigma*), sigma_source kAssumed.
void SetAssumedSigmas(MarineFix* fix);

/// The vessel's true heading, degrees clockwise from true north.
struct HeadingRecord {
  TimeNs t_ns = 0;
  double heading_deg = 0.0;
  bool from_magnetic = false;  ///< sent as magnetic and corrected by deviation and variation
  std::string source;
};

/// Course and speed over ground (true course).
struct CourseRecord {
  TimeNs t_ns = 0;
  double cog_deg = 0.0;
  double sog_m_s = 0.0;
  std::string source;
};

/// Attitude as the device sends it (NMEA 2000 127257: yaw, pitch, roll; signs untouched).
struct AttitudeRecord {
  TimeNs t_ns = 0;
  double roll_deg = 0.0;
  double pitch_deg = 0.0;
  std::optional<double> yaw_deg;  ///< not every device sends it
  std::string source;
};

/// Rate of turn, deg/s, positive turning to starboard (clockwise seen from above).
struct RateOfTurnRecord {
  TimeNs t_ns = 0;
  double rate_deg_s = 0.0;
  std::string source;
};

/// The records beside the position fixes; a dataset keeps them in heading.csv, course.csv,
/// attitude.csv and rate_of_turn.csv (docs/dataset-format.md).
struct MarineRecords {
  std::vector<HeadingRecord> headings;
  std::vector<CourseRecord> courses;
  std::vector<AttitudeRecord> attitudes;
  std::vector<RateOfTurnRecord> rates_of_turn;
  bool empty() const {
    return headings.empty() && courses.empty() && attitudes.empty() && rates_of_turn.empty();
  }
};

/// Why a sentence or record was not used.
enum class BadReason {
  kNotASentence,         ///< NMEA 0183: no `$` or `!` on the line
  kChecksumMismatch,     ///< NMEA 0183: `*hh` is not the XOR of the sentence
  kMissingChecksum,      ///< NMEA 0183: no `*hh` on a sentence with all its fields
  kTruncated,            ///< cut short: fewer fields than the type has and no checksum, or `*h`
  kFieldCount,           ///< a checksummed sentence with the wrong number of fields
  kBadNumber,            ///< a field that does not parse: not entirely a number, a bad letter or
                         ///< date, a JSON value of the wrong type
  kEmptyField,           ///< NMEA 0183: a required field is empty
  kInvalidFix,           ///< fix quality / status / mode says no valid measurement
  kTimeBackwards,        ///< time earlier than the previous record's
  kNoTime,               ///< NMEA 0183: no time to give it (before the first timed sentence or RMC)
  kMalformedJson,        ///< NMEA 2000: a line that is not a JSON object
  kMissingField,         ///< NMEA 2000: a field the record needs is absent
  kNonFinite,            ///< NaN or infinity
  kOutOfRange,           ///< a latitude, longitude, height or HDOP no receiver can mean
  kMagneticNoVariation,  ///< a magnetic heading or course that cannot be made true
};
const char* BadReasonName(BadReason reason);

/// Counts of what a reader saw. `type` is the sentence type (GGA, ...) or the PGN (129025, ...).
struct MarineLogStats {
  static constexpr int kLinesKept = 5;  ///< line numbers kept per (type, reason)
  struct Bad {
    int count = 0;
    std::vector<int> first_lines;  ///< 1-based, the first kLinesKept
  };
  int lines = 0;    ///< non-blank lines read (sentences, or JSON records without the header)
  int used = 0;     ///< became a record (or, GST, a fix's sigma)
  int ignored = 0;  ///< valid but of a type this reader does not use
  std::map<std::string, int> ignored_by_type;
  std::map<std::pair<std::string, BadReason>, Bad> bad;  ///< by (type, reason)

  void AddBad(const std::string& type, BadReason reason, int line);
  void AddIgnored(const std::string& type);
  int BadCount() const;                  ///< all reasons
  int BadCount(BadReason reason) const;  ///< all types
  int BadCount(const std::string& type, BadReason reason) const;
};

/// What a reader made of one log file.
struct MarineLog {
  std::string path;    ///< the file read
  std::string format;  ///< "nmea0183" | "nmea2000"
  std::vector<MarineFix> fixes;
  MarineRecords records;
  MarineLogStats stats;
};

/// A multi-line, human-readable account of the stats (for the CLI): lines, used, ignored by
/// type, and every (type, reason) with its count and first line numbers.
std::string DescribeStats(const MarineLogStats& stats);

}  // namespace skerry
