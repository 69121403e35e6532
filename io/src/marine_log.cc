#include "skerry/io/marine_log.h"

#include <cmath>
#include <sstream>

namespace skerry {

const char* FixSigmaSourceName(FixSigmaSource source) {
  switch (source) {
    case FixSigmaSource::kReceiver:
      return "receiver";
    case FixSigmaSource::kHdop:
      return "hdop";
    case FixSigmaSource::kAssumed:
      return "assumed";
  }
  return "?";
}

double UereM(FixKind kind) {
  switch (kind) {
    case FixKind::kAutonomous:
      return 4.0;
    case FixKind::kDifferential:
      return 1.0;
    case FixKind::kRtkFloat:
      return 0.3;
    case FixKind::kRtkFixed:
      return 0.02;
  }
  return 4.0;
}

void SetSigmasFromHdop(double hdop, FixKind kind, MarineFix* fix) {
  const double drms_m = hdop * UereM(kind);
  fix->sigma_east_m = drms_m / std::sqrt(2.0);
  fix->sigma_north_m = fix->sigma_east_m;
  fix->sigma_up_m = 1.5 * drms_m;
  fix->sigma_source = FixSigmaSource::kHdop;
}

void SetAssumedSigmas(MarineFix* fix) {
  fix->sigma_east_m = kAssumedSigmaHorizontalM;
  fix->sigma_north_m = kAssumedSigmaHorizontalM;
  fix->sigma_up_m = kAssumedSigmaVerticalM;
  fix->sigma_source = FixSigmaSource::kAssumed;
}

const char* BadReasonName(BadReason reason) {
  switch (reason) {
    case BadReason::kNotASentence:
      return "not a sentence";
    case BadReason::kChecksumMismatch:
      return "checksum mismatch";
    case BadReason::kMissingChecksum:
      return "missing checksum";
    case BadReason::kTruncated:
      return "truncated";
    case BadReason::kFieldCount:
      return "wrong field count";
    case BadReason::kBadNumber:
      return "unparseable field";
    case BadReason::kEmptyField:
      return "empty field";
    case BadReason::kInvalidFix:
      return "invalid fix or mode";
    case BadReason::kTimeBackwards:
      return "time going backwards";
    case BadReason::kNoTime:
      return "no time or date yet";
    case BadReason::kMalformedJson:
      return "malformed JSON";
    case BadReason::kMissingField:
      return "missing field";
    case BadReason::kNonFinite:
      return "non-finite number";
    case BadReason::kOutOfRange:
      return "out of range";
    case BadReason::kMagneticNoVariation:
      return "magnetic without variation";
  }
  return "?";
}

void MarineLogStats::AddBad(const std::string& type, BadReason reason, int line) {
  Bad& b = bad[{type, reason}];
  ++b.count;
  if (static_cast<int>(b.first_lines.size()) < kLinesKept) b.first_lines.push_back(line);
}

void MarineLogStats::AddIgnored(const std::string& type) {
  ++ignored;
  ++ignored_by_type[type];
}

int MarineLogStats::BadCount() const {
  int n = 0;
  for (const auto& [key, b] : bad) n += b.count;
  return n;
}

int MarineLogStats::BadCount(BadReason reason) const {
  int n = 0;
  for (const auto& [key, b] : bad) {
    if (key.second == reason) n += b.count;
  }
  return n;
}

int MarineLogStats::BadCount(const std::string& type, BadReason reason) const {
  const auto it = bad.find({type, reason});
  return it == bad.end() ? 0 : it->second.count;
}

std::string DescribeStats(const MarineLogStats& stats) {
  std::ostringstream out;
  out << "  " << stats.lines << " lines read, " << stats.used << " used, " << stats.ignored
      << " of types not used, " << stats.BadCount() << " bad\n";
  if (!stats.ignored_by_type.empty()) {
    out << "  not used:";
    for (const auto& [type, n] : stats.ignored_by_type) out << ' ' << type << " x" << n;
    out << '\n';
  }
  for (const auto& [key, b] : stats.bad) {
    out << "  bad " << key.first << ": " << BadReasonName(key.second) << " x" << b.count
        << " (line";
    if (b.first_lines.size() > 1) out << 's';
    for (std::size_t i = 0; i < b.first_lines.size(); ++i) {
      out << (i == 0 ? " " : ", ") << b.first_lines[i];
    }
    if (b.count > static_cast<int>(b.first_lines.size())) out << ", ...";
    out << ")\n";
  }
  return out.str();
}

}  // namespace skerry
