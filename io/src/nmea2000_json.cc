#include "skerry/io/nmea2000_json.h"

#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>

#include "civil_time.h"
#include "skerry/core/input_error.h"
#include "text_lines.h"

namespace skerry::nmea2000 {
namespace {

using nlohmann::json;

constexpr double kRadToDeg = 180.0 / M_PI;
constexpr double kMaxAbsHeightM = 1e5;

struct FieldError {
  BadReason reason;
};
[[noreturn]] void Fail(BadReason reason) { throw FieldError{reason}; }

// A finite number of `fields`, or nullopt when absent; a value of another type or NaN/Inf fails.
std::optional<double> OptionalNumber(const json& fields, const char* name) {
  const auto it = fields.find(name);
  if (it == fields.end() || it->is_null()) return std::nullopt;
  if (!it->is_number()) Fail(BadReason::kBadNumber);
  const double v = it->get<double>();
  if (!std::isfinite(v)) Fail(BadReason::kNonFinite);
  return v;
}

double Number(const json& fields, const char* name) {
  const std::optional<double> v = OptionalNumber(fields, name);
  if (!v) Fail(BadReason::kMissingField);
  return *v;
}

std::string Text(const json& fields, const char* name) {
  const auto it = fields.find(name);
  if (it == fields.end() || it->is_null()) Fail(BadReason::kMissingField);
  if (!it->is_string()) Fail(BadReason::kBadNumber);
  return it->get<std::string>();
}

// Degrees clockwise from north, in [0, 360).
double Heading360(double rad) {
  double deg = std::fmod(rad * kRadToDeg, 360.0);
  if (deg < 0.0) deg += 360.0;
  return deg >= 360.0 ? 0.0 : deg;
}

void LatLon(const json& fields, MarineFix* fix) {
  fix->lat_deg = Number(fields, "Latitude");
  fix->lon_deg = Number(fields, "Longitude");
  if (std::fabs(fix->lat_deg) > 90.0 || std::fabs(fix->lon_deg) > 180.0) {
    Fail(BadReason::kOutOfRange);
  }
}

// 129029's Method: the kind of fix, or kInvalidFix. Strings as canboat prints them, or the
// lookup codes (showLookupValues).
FixKind MethodKind(const json& fields) {
  const auto it = fields.find("Method");
  if (it == fields.end() || it->is_null()) Fail(BadReason::kMissingField);
  int code = -1;
  if (it->is_number_integer()) {
    code = it->get<int>();
  } else if (it->is_string()) {
    const std::string m = it->get<std::string>();
    static const char* const kNames[] = {
        "no GNSS",           "GNSS fix",  "DGNSS fix",           "Precise GNSS",
        "RTK Fixed Integer", "RTK float", "Estimated (DR) mode", "Manual Input",
        "Simulate mode"};
    for (int i = 0; i < 9; ++i) {
      if (m == kNames[i]) code = i;
    }
    if (code < 0) Fail(BadReason::kBadNumber);
  } else {
    Fail(BadReason::kBadNumber);
  }
  switch (code) {
    case 1:
      return FixKind::kAutonomous;
    case 2:
    case 3:
      return FixKind::kDifferential;
    case 4:
      return FixKind::kRtkFixed;
    case 5:
      return FixKind::kRtkFloat;
    default:
      Fail(BadReason::kInvalidFix);
  }
}

// One record of a PGN read here into `log`; throws FieldError.
void ReadRecord(int pgn, TimeNs t, const std::string& src, const json& fields, MarineLog* log) {
  switch (pgn) {
    case 129025: {
      MarineFix fix;
      fix.t_ns = t;
      LatLon(fields, &fix);
      SetAssumedSigmas(&fix);
      fix.source = src;
      log->fixes.push_back(fix);
      return;
    }
    case 129029: {
      MarineFix fix;
      fix.t_ns = t;
      const FixKind kind = MethodKind(fields);
      LatLon(fields, &fix);
      fix.height_m = OptionalNumber(fields, "Altitude");
      if (fix.height_m && std::fabs(*fix.height_m) > kMaxAbsHeightM) Fail(BadReason::kOutOfRange);
      const std::optional<double> hdop = OptionalNumber(fields, "HDOP");
      if (hdop && !(*hdop > 0.0)) Fail(BadReason::kOutOfRange);
      if (hdop) {
        SetSigmasFromHdop(*hdop, kind, &fix);
      } else {
        SetAssumedSigmas(&fix);
      }
      fix.source = src;
      log->fixes.push_back(fix);
      return;
    }
    case 129026: {
      const std::string reference = Text(fields, "COG Reference");
      const double cog = Number(fields, "COG");
      const double sog = Number(fields, "SOG");
      if (reference != "True") Fail(BadReason::kMagneticNoVariation);
      if (sog < 0.0) Fail(BadReason::kOutOfRange);
      log->records.courses.push_back({t, Heading360(cog), sog, src});
      return;
    }
    case 127250: {
      double heading = Number(fields, "Heading");
      const std::string reference = Text(fields, "Reference");
      bool magnetic = false;
      if (reference == "Magnetic") {
        const std::optional<double> variation = OptionalNumber(fields, "Variation");
        if (!variation) Fail(BadReason::kMagneticNoVariation);
        heading += OptionalNumber(fields, "Deviation").value_or(0.0) + *variation;
        magnetic = true;
      } else if (reference != "True") {
        Fail(BadReason::kBadNumber);
      }
      log->records.headings.push_back({t, Heading360(heading), magnetic, src});
      return;
    }
    case 127257: {
      AttitudeRecord a;
      a.t_ns = t;
      a.pitch_deg = Number(fields, "Pitch") * kRadToDeg;
      a.roll_deg = Number(fields, "Roll") * kRadToDeg;
      const std::optional<double> yaw = OptionalNumber(fields, "Yaw");
      if (yaw) a.yaw_deg = *yaw * kRadToDeg;
      a.source = src;
      log->records.attitudes.push_back(a);
      return;
    }
    case 127251:
      log->records.rates_of_turn.push_back({t, Number(fields, "Rate") * kRadToDeg, src});
      return;
    default:
      return;
  }
}

bool IsRead(int pgn) {
  return pgn == 129025 || pgn == 129029 || pgn == 129026 || pgn == 127250 || pgn == 127257 ||
         pgn == 127251;
}

}  // namespace

MarineLog ReadCanboatJson(const std::string& path) {
  MarineLog log;
  log.path = path;
  log.format = "nmea2000";
  MarineLogStats& stats = log.stats;
  TextLines lines(path);
  std::string text;
  bool first = true, header_seen = false;
  int records = 0;  // lines that are canboat records (timestamp, pgn, src)
  TimeNs last_t = std::numeric_limits<TimeNs>::min();
  while (lines.Next(&text)) {
    if (text.find_first_not_of(" \t\r") == std::string::npos) continue;
    const int line = lines.line();
    const json j = json::parse(text, nullptr, /*allow_exceptions=*/false);
    const bool object = !j.is_discarded() && j.is_object();
    if (first && object && j.contains("units") && !j.contains("pgn")) {
      first = false;
      header_seen = true;
      const auto units = j.find("units");
      if (!units->is_string() || units->get<std::string>() != "si") {
        throw InputError(path, line, "units",
                         "canboat JSON in units " + units->dump() +
                             ": expected \"si\" (decode with analyzer -json -si)");
      }
      continue;
    }
    first = false;
    ++stats.lines;
    if (!object) {
      stats.AddBad("?", BadReason::kMalformedJson, line);
      continue;
    }
    const auto pgn_it = j.find("pgn");
    if (pgn_it == j.end()) {
      stats.AddBad("?", BadReason::kMissingField, line);
      continue;
    }
    if (!pgn_it->is_number_integer()) {
      stats.AddBad("?", BadReason::kBadNumber, line);
      continue;
    }
    const int pgn = pgn_it->get<int>();
    const std::string type = std::to_string(pgn);
    const auto ts = j.find("timestamp");
    const auto src = j.find("src");
    if (ts == j.end() || src == j.end()) {
      stats.AddBad(type, BadReason::kMissingField, line);
      continue;
    }
    TimeNs t = 0;
    if (!ts->is_string() || !ParseIsoUtc(ts->get<std::string>(), &t) || !src->is_number_integer()) {
      stats.AddBad(type, BadReason::kBadNumber, line);
      continue;
    }
    ++records;
    if (t < last_t) {
      stats.AddBad(type, BadReason::kTimeBackwards, line);
      continue;
    }
    last_t = t;  // the logger's clock, whatever becomes of the record
    if (!IsRead(pgn)) {
      stats.AddIgnored(type);
      continue;
    }
    const auto fields = j.find("fields");
    if (fields == j.end()) {
      stats.AddBad(type, BadReason::kMissingField, line);
      continue;
    }
    if (!fields->is_object()) {
      stats.AddBad(type, BadReason::kBadNumber, line);
      continue;
    }
    try {
      ReadRecord(pgn, t, std::to_string(src->get<long long>()), *fields, &log);
    } catch (const FieldError& e) {
      stats.AddBad(type, e.reason, line);
      continue;
    }
    ++stats.used;
  }
  if (records == 0) {
    throw InputError(path, 0, "",
                     "not canboat JSON: no line is a record with \"timestamp\", \"pgn\" and "
                     "\"src\" (expected analyzer -json -si output, one object a line)");
  }
  if (!header_seen) {
    throw InputError(path, 1, "units",
                     "no canboat header line ({\"version\": ..., \"units\": \"si\"}): the units "
                     "of the records are unknown (decode with analyzer -json -si)");
  }
  return log;
}

}  // namespace skerry::nmea2000
