#include "skerry/io/nmea0183.h"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <vector>

#include "civil_time.h"
#include "text_lines.h"

namespace skerry::nmea0183 {
namespace {

constexpr double kKnotM_S = 1852.0 / 3600.0;
constexpr TimeNs kNsPerSecond = 1000000000;
constexpr TimeNs kHalfDayNs = 12 * 3600 * kNsPerSecond;
constexpr TimeNs kDayNs = 2 * kHalfDayNs;

// A field that failed, and why: the parse functions below return this through Fail.
struct FieldError {
  BadReason reason;
};

std::vector<std::string_view> Split(std::string_view body) {
  std::vector<std::string_view> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = body.find(',', start);
    if (comma == std::string_view::npos) {
      fields.push_back(body.substr(start));
      return fields;
    }
    fields.push_back(body.substr(start, comma - start));
    start = comma + 1;
  }
}

int HexDigit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

// The fields of one sentence, each parsed or failing with a reason (thrown as FieldError and
// caught once in ParseLine, which keeps every per-type parser a straight list of fields).
class Fields {
 public:
  explicit Fields(std::vector<std::string_view> f) : f_(std::move(f)) {}
  std::size_t size() const { return f_.size(); }
  std::string_view Text(std::size_t i) const { return f_.at(i); }
  bool Empty(std::size_t i) const { return f_.at(i).empty(); }

  [[noreturn]] static void Fail(BadReason reason) { throw FieldError{reason}; }

  std::string_view Required(std::size_t i) const {
    if (Empty(i)) Fail(BadReason::kEmptyField);
    return Text(i);
  }
  double Number(std::size_t i) const { return ParseNumber(Required(i)); }
  std::optional<double> OptionalNumber(std::size_t i) const {
    if (Empty(i)) return std::nullopt;
    return ParseNumber(Text(i));
  }
  char Letter(std::size_t i) const {
    const std::string_view t = Required(i);
    if (t.size() != 1) Fail(BadReason::kBadNumber);
    return t[0];
  }
  TimeNs TimeOfDay(std::size_t i) const {
    const std::optional<TimeNs> t = ParseTimeOfDay(Required(i));
    if (!t) Fail(BadReason::kBadNumber);
    return *t;
  }
  double Coordinate(std::size_t i, bool latitude) const {
    const std::string_view value = Required(i);
    const std::string_view hemisphere = Required(i + 1);
    const std::optional<double> deg = ParseCoordinate(value, hemisphere);
    if (!deg) Fail(BadReason::kBadNumber);
    const bool letter_ok = latitude ? (hemisphere == "N" || hemisphere == "S")
                                    : (hemisphere == "E" || hemisphere == "W");
    if (!letter_ok) Fail(BadReason::kBadNumber);
    if (std::fabs(*deg) > (latitude ? 90.0 : 180.0)) Fail(BadReason::kOutOfRange);
    return *deg;
  }
  // A heading or course in degrees, [0, 360] accepted and 360 folded to 0.
  double Angle(std::size_t i) const {
    const double a = Number(i);
    if (a < 0.0 || a > 360.0) Fail(BadReason::kOutOfRange);
    return a == 360.0 ? 0.0 : a;
  }

 private:
  static double ParseNumber(std::string_view t) {
    for (char c : t) {
      if (!(std::isdigit(static_cast<unsigned char>(c)) || c == '.' || c == '-' || c == '+')) {
        std::string lower;
        for (char d : t) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(d)));
        if (lower.find("nan") != std::string::npos || lower.find("inf") != std::string::npos) {
          Fail(BadReason::kNonFinite);
        }
        Fail(BadReason::kBadNumber);
      }
    }
    const std::string s(t);
    char* end = nullptr;
    const double v = std::strtod(s.c_str(), &end);
    if (end != s.c_str() + s.size() || s.empty()) Fail(BadReason::kBadNumber);
    if (!std::isfinite(v)) Fail(BadReason::kNonFinite);
    return v;
  }

  std::vector<std::string_view> f_;
};

// Field counts after the address: the ones each type may have (the first is the fewest).
std::vector<std::size_t> FieldCounts(const std::string& type) {
  if (type == "GGA") return {14};
  if (type == "RMC") return {11, 12, 13};  // NMEA 2.2; 2.3 adds the mode; 4.1 the nav status
  if (type == "VTG") return {8, 9};        // 2.3 adds the mode
  if (type == "HDT") return {2};
  if (type == "THS") return {2};
  if (type == "GST") return {8};
  return {};
}

Gga ParseGga(const Fields& f) {
  Gga g;
  g.time_of_day_ns = f.TimeOfDay(0);
  g.lat_deg = f.Coordinate(1, true);
  g.lon_deg = f.Coordinate(3, false);
  // The indicator is one digit (NMEA 0183 4.11, 0-9; others fall to the default below); beyond
  // two digits it is a bad number, and one beyond int's range must not reach the cast (the
  // fuzzer's 1e117).
  const double quality = f.Number(5);
  if (quality != std::floor(quality) || std::abs(quality) > 99.0) {
    Fields::Fail(BadReason::kBadNumber);
  }
  g.quality = static_cast<int>(quality);
  switch (g.quality) {
    case 1:
    case 3:
      g.kind = FixKind::kAutonomous;
      break;
    case 2:
    case 9:
      g.kind = FixKind::kDifferential;
      break;
    case 4:
      g.kind = FixKind::kRtkFixed;
      break;
    case 5:
      g.kind = FixKind::kRtkFloat;
      break;
    default:  // 0 none, 6 estimated (dead reckoning), 7 manual, 8 simulator
      Fields::Fail(BadReason::kInvalidFix);
  }
  g.hdop = f.OptionalNumber(7);
  if (g.hdop && !(*g.hdop > 0.0)) Fields::Fail(BadReason::kOutOfRange);
  g.altitude_msl_m = f.OptionalNumber(8);
  g.geoid_separation_m = f.OptionalNumber(10);
  return g;
}

Rmc ParseRmc(const Fields& f) {
  Rmc r;
  r.time_of_day_ns = f.TimeOfDay(0);
  if (f.Letter(1) != 'A') Fields::Fail(BadReason::kInvalidFix);
  // The mode (NMEA 2.3): N not valid, E estimated (dead reckoning).
  if (f.size() >= 12 && !f.Empty(11) && (f.Text(11) == "N" || f.Text(11) == "E")) {
    Fields::Fail(BadReason::kInvalidFix);
  }
  r.lat_deg = f.Coordinate(2, true);
  r.lon_deg = f.Coordinate(4, false);
  const std::optional<double> sog_kn = f.OptionalNumber(6);
  if (sog_kn) {
    if (*sog_kn < 0.0) Fields::Fail(BadReason::kOutOfRange);
    r.sog_m_s = *sog_kn * kKnotM_S;
  }
  if (!f.Empty(7)) r.cog_deg = f.Angle(7);
  const std::string_view date = f.Required(8);
  std::int64_t days = 0;
  if (!ParseDdMmYy(date, &days)) Fields::Fail(BadReason::kBadNumber);
  r.days_since_epoch = days;
  return r;
}

Vtg ParseVtg(const Fields& f) {
  Vtg v;
  if (f.size() >= 9 && (f.Text(8) == "N" || f.Text(8) == "E")) {
    Fields::Fail(BadReason::kInvalidFix);
  }
  v.cog_deg = f.Angle(0);
  const double sog_kn = f.Number(4);
  if (sog_kn < 0.0) Fields::Fail(BadReason::kOutOfRange);
  v.sog_m_s = sog_kn * kKnotM_S;
  return v;
}

Hdt ParseHdt(const Fields& f) {
  Hdt h;
  h.heading_deg = f.Angle(0);
  if (f.Text(1) != "T") Fields::Fail(BadReason::kBadNumber);
  return h;
}

Ths ParseThs(const Fields& f) {
  Ths t;
  const char mode = f.Letter(1);
  if (mode != 'A' && mode != 'E' && mode != 'M' && mode != 'S' && mode != 'V') {
    Fields::Fail(BadReason::kBadNumber);
  }
  if (mode != 'A') Fields::Fail(BadReason::kInvalidFix);
  t.heading_deg = f.Angle(0);
  return t;
}

Gst ParseGst(const Fields& f) {
  Gst g;
  g.time_of_day_ns = f.TimeOfDay(0);
  g.sigma_lat_m = f.Number(5);
  g.sigma_lon_m = f.Number(6);
  g.sigma_alt_m = f.Number(7);
  if (!(g.sigma_lat_m > 0.0 && g.sigma_lon_m > 0.0 && g.sigma_alt_m > 0.0)) {
    Fields::Fail(BadReason::kOutOfRange);
  }
  return g;
}

// The time of day a sentence carries, if any.
std::optional<TimeNs> TimeOfDayOf(const Sentence& s) {
  if (const auto* g = std::get_if<Gga>(&s.data)) return g->time_of_day_ns;
  if (const auto* r = std::get_if<Rmc>(&s.data)) return r->time_of_day_ns;
  if (const auto* g = std::get_if<Gst>(&s.data)) return g->time_of_day_ns;
  return std::nullopt;
}

}  // namespace

std::uint8_t Checksum(std::string_view body) {
  std::uint8_t sum = 0;
  for (char c : body) sum ^= static_cast<std::uint8_t>(c);
  return sum;
}

std::optional<double> ParseCoordinate(std::string_view value, std::string_view hemisphere) {
  const std::size_t dot = value.find('.');
  const std::size_t int_digits = dot == std::string_view::npos ? value.size() : dot;
  if (int_digits < 3 || int_digits > 5) return std::nullopt;
  for (std::size_t i = 0; i < value.size(); ++i) {
    if (i == dot) continue;
    if (!std::isdigit(static_cast<unsigned char>(value[i]))) return std::nullopt;
  }
  const double degrees = std::strtod(std::string(value.substr(0, int_digits - 2)).c_str(), nullptr);
  const double minutes = std::strtod(std::string(value.substr(int_digits - 2)).c_str(), nullptr);
  if (!(minutes < 60.0)) return std::nullopt;
  const double deg = degrees + minutes / 60.0;
  if (hemisphere == "S" || hemisphere == "W") return -deg;
  return deg;
}

std::optional<TimeNs> ParseTimeOfDay(std::string_view value) {
  if (value.size() < 6) return std::nullopt;
  for (int i = 0; i < 6; ++i) {
    if (!std::isdigit(static_cast<unsigned char>(value[i]))) return std::nullopt;
  }
  auto two = [&](int i) { return (value[i] - '0') * 10 + (value[i + 1] - '0'); };
  const int h = two(0), m = two(2), s = two(4);
  if (h > 23 || m > 59 || s > 60) return std::nullopt;  // 60: a leap second
  TimeNs fraction_ns = 0;
  if (value.size() > 6) {
    if (value[6] != '.' || value.size() == 7 || value.size() > 16) return std::nullopt;
    TimeNs scale = kNsPerSecond;
    for (std::size_t i = 7; i < value.size(); ++i) {
      if (!std::isdigit(static_cast<unsigned char>(value[i]))) return std::nullopt;
      scale /= 10;
      fraction_ns += (value[i] - '0') * scale;
    }
  }
  return (static_cast<TimeNs>(h) * 3600 + m * 60 + s) * kNsPerSecond + fraction_ns;
}

ParseResult ParseLine(std::string_view line) {
  const std::size_t start = line.find_first_of("$!");
  if (start == std::string_view::npos) return Rejected{"?", BadReason::kNotASentence};
  std::string_view sentence = line.substr(start);
  while (!sentence.empty() && std::isspace(static_cast<unsigned char>(sentence.back()))) {
    sentence.remove_suffix(1);
  }
  const std::size_t star = sentence.find('*');
  const std::string_view body =
      sentence.substr(1, star == std::string_view::npos ? std::string_view::npos : star - 1);
  const std::vector<std::string_view> parts = Split(body);

  // The address: talker (2 letters) + type (3), or a proprietary / unusual one.
  const std::string_view address = parts.front();
  bool address_ok = address.size() == 5;
  for (char c : address) address_ok = address_ok && std::isalnum(static_cast<unsigned char>(c));
  const std::string type = address_ok ? std::string(address.substr(2)) : std::string("?");
  const std::string talker = address_ok ? std::string(address.substr(0, 2)) : std::string();
  const std::vector<std::size_t> counts = FieldCounts(type);
  const std::size_t field_count = parts.size() - 1;

  if (star != std::string_view::npos) {
    const std::string_view hex = sentence.substr(star + 1);
    if (hex.size() < 2) return Rejected{type, BadReason::kTruncated};
    if (hex.size() > 2 || HexDigit(hex[0]) < 0 || HexDigit(hex[1]) < 0 ||
        Checksum(body) != HexDigit(hex[0]) * 16 + HexDigit(hex[1])) {
      return Rejected{type, BadReason::kChecksumMismatch};
    }
  } else {
    if (!counts.empty() && field_count < counts.front()) {
      return Rejected{type, BadReason::kTruncated};
    }
    return Rejected{type, BadReason::kMissingChecksum};
  }
  if (!address_ok || address.front() == 'P') {
    return Ignored{std::string(address.empty() ? "?" : address)};
  }
  if (counts.empty()) return Ignored{type};
  bool count_ok = false;
  for (std::size_t n : counts) count_ok = count_ok || n == field_count;
  if (!count_ok) return Rejected{type, BadReason::kFieldCount};

  const Fields fields(std::vector<std::string_view>(parts.begin() + 1, parts.end()));
  Sentence s;
  s.talker = talker;
  s.type = type;
  try {
    if (type == "GGA") s.data = ParseGga(fields);
    if (type == "RMC") s.data = ParseRmc(fields);
    if (type == "VTG") s.data = ParseVtg(fields);
    if (type == "HDT") s.data = ParseHdt(fields);
    if (type == "THS") s.data = ParseThs(fields);
    if (type == "GST") s.data = ParseGst(fields);
  } catch (const FieldError& e) {
    return Rejected{type, e.reason};
  }
  return s;
}

MarineLog ReadLog(const std::string& path) {
  MarineLog log;
  log.path = path;
  log.format = "nmea0183";
  MarineLogStats& stats = log.stats;

  // Pass 1: parse every line.
  struct Item {
    int line;
    Sentence sentence;
  };
  std::vector<Item> items;
  {
    TextLines lines(path);
    std::string text;
    while (lines.Next(&text)) {
      if (text.find_first_not_of(" \t\r") == std::string::npos) continue;
      ++stats.lines;
      ParseResult r = ParseLine(text);
      if (auto* s = std::get_if<Sentence>(&r)) {
        items.push_back({lines.line(), std::move(*s)});
      } else if (const auto* bad = std::get_if<Rejected>(&r)) {
        stats.AddBad(bad->type, bad->reason, lines.line());
      } else {
        stats.AddIgnored(std::get<Ignored>(r).type);
      }
    }
  }

  // Pass 2: the clock. Anchored on the first RMC's date.
  const Rmc* anchor = nullptr;
  for (const Item& item : items) {
    if ((anchor = std::get_if<Rmc>(&item.sentence.data)) != nullptr) break;
  }
  bool started = false;
  std::int64_t day = 0;
  TimeNs last_tod = 0;
  TimeNs last_t = std::numeric_limits<TimeNs>::min();
  bool any_gga = false;
  std::vector<MarineFix> rmc_fixes;
  std::map<TimeNs, Gst> gst_at;
  for (const Item& item : items) {
    const Sentence& s = item.sentence;
    TimeNs t = 0;
    if (const std::optional<TimeNs> tod = TimeOfDayOf(s)) {
      if (anchor == nullptr) {
        stats.AddBad(s.type, BadReason::kNoTime, item.line);
        continue;
      }
      std::int64_t d = day;
      if (const auto* rmc = std::get_if<Rmc>(&s.data)) {
        d = rmc->days_since_epoch;
      } else if (!started) {
        d = anchor->days_since_epoch - (*tod > anchor->time_of_day_ns + kHalfDayNs ? 1 : 0);
      } else if (*tod + kHalfDayNs < last_tod) {
        d = day + 1;  // past midnight
      }
      t = d * kDayNs + *tod;
      if (started && t < last_t) {
        stats.AddBad(s.type, BadReason::kTimeBackwards, item.line);
        continue;
      }
      started = true;
      day = d;
      last_tod = *tod;
      last_t = t;
    } else {
      if (!started) {
        stats.AddBad(s.type, BadReason::kNoTime, item.line);
        continue;
      }
      t = last_t;
    }
    ++stats.used;
    if (const auto* g = std::get_if<Gga>(&s.data)) {
      any_gga = true;
      MarineFix fix;
      fix.t_ns = t;
      fix.lat_deg = g->lat_deg;
      fix.lon_deg = g->lon_deg;
      if (g->altitude_msl_m && g->geoid_separation_m) {
        fix.height_m = *g->altitude_msl_m + *g->geoid_separation_m;
      }
      if (g->hdop) {
        SetSigmasFromHdop(*g->hdop, g->kind, &fix);
      } else {
        SetAssumedSigmas(&fix);
      }
      fix.source = s.talker;
      log.fixes.push_back(fix);
    } else if (const auto* r = std::get_if<Rmc>(&s.data)) {
      MarineFix fix;
      fix.t_ns = t;
      fix.lat_deg = r->lat_deg;
      fix.lon_deg = r->lon_deg;
      SetAssumedSigmas(&fix);
      fix.source = s.talker;
      rmc_fixes.push_back(fix);
      if (r->cog_deg && r->sog_m_s) {
        log.records.courses.push_back({t, *r->cog_deg, *r->sog_m_s, s.talker});
      }
    } else if (const auto* v = std::get_if<Vtg>(&s.data)) {
      log.records.courses.push_back({t, v->cog_deg, v->sog_m_s, s.talker});
    } else if (const auto* h = std::get_if<Hdt>(&s.data)) {
      log.records.headings.push_back({t, h->heading_deg, false, s.talker});
    } else if (const auto* th = std::get_if<Ths>(&s.data)) {
      log.records.headings.push_back({t, th->heading_deg, false, s.talker});
    } else if (const auto* gst = std::get_if<Gst>(&s.data)) {
      gst_at[t] = *gst;
    }
  }
  if (!any_gga) log.fixes = std::move(rmc_fixes);
  // GST: the receiver's own sigmas for the fix of its epoch.
  for (MarineFix& fix : log.fixes) {
    const auto it = gst_at.find(fix.t_ns);
    if (it == gst_at.end()) continue;
    fix.sigma_north_m = it->second.sigma_lat_m;
    fix.sigma_east_m = it->second.sigma_lon_m;
    fix.sigma_up_m = it->second.sigma_alt_m;
    fix.sigma_source = FixSigmaSource::kReceiver;
  }
  return log;
}

}  // namespace skerry::nmea0183
