#include "skerry/io/csv_reader.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <utility>

#include "skerry/core/input_error.h"

namespace skerry {
namespace {

std::string_view Trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

bool IsBlank(const std::string& s) { return Trim(s).empty(); }

std::string Quote(const std::string& s) { return "\"" + s + "\""; }

std::string JoinNames(const std::vector<std::string>& names, char delimiter) {
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (i > 0) out += delimiter;
    out += names[i];
  }
  return out;
}

}  // namespace

bool ParseDouble(std::string_view text, double* value) {
  text = Trim(text);
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  if (text.empty()) return false;
  // from_chars would accept "nan"/"inf" and hex forms need a flag; a leading sign after '+' is
  // not a number either.
  if (text.front() == '+') return false;
  double v = 0.0;
  const auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || ptr != text.data() + text.size()) return false;
  if (!std::isfinite(v)) return false;
  *value = v;
  return true;
}

bool ParseSecondsToNs(std::string_view text, TimeNs* t_ns) {
  text = Trim(text);
  if (text.find_first_of("eE") != std::string_view::npos) {
    double seconds = 0.0;
    if (!ParseDouble(text, &seconds) || std::fabs(seconds) > 9.2e9) return false;
    *t_ns = SecondsToNs(seconds);
    return true;
  }
  bool negative = false;
  if (!text.empty() && (text.front() == '-' || text.front() == '+')) {
    negative = text.front() == '-';
    text.remove_prefix(1);
  }
  const std::size_t dot = text.find('.');
  const std::string_view int_part = text.substr(0, dot);
  const std::string_view frac_part =
      dot == std::string_view::npos ? std::string_view() : text.substr(dot + 1);
  if (int_part.empty() && frac_part.empty()) return false;
  for (char c : int_part) {
    if (c < '0' || c > '9') return false;
  }
  for (char c : frac_part) {
    if (c < '0' || c > '9') return false;
  }
  // int64 ns holds +-9.22e9 s; reject anything with more than 10 integer digits outright.
  std::size_t first_nonzero = int_part.find_first_not_of('0');
  if (first_nonzero != std::string_view::npos && int_part.size() - first_nonzero > 10) return false;
  std::int64_t seconds = 0;
  for (char c : int_part) seconds = seconds * 10 + (c - '0');
  std::int64_t nanos = 0;
  for (std::size_t i = 0; i < 9; ++i) {
    nanos = nanos * 10 + (i < frac_part.size() ? frac_part[i] - '0' : 0);
  }
  if (frac_part.size() > 9 && frac_part[9] >= '5') nanos += 1;  // round half up on the 10th digit
  constexpr std::int64_t kMaxSeconds = std::numeric_limits<std::int64_t>::max() / 1000000000 - 1;
  if (seconds > kMaxSeconds) return false;
  const std::int64_t total = seconds * 1000000000 + nanos;
  *t_ns = negative ? -total : total;
  return true;
}

void AppendSeconds(TimeNs t_ns, std::string* out) {
  const bool negative = t_ns < 0;
  // Work on the magnitude as unsigned so INT64_MIN is representable.
  const std::uint64_t mag =
      negative ? static_cast<std::uint64_t>(-(t_ns + 1)) + 1 : static_cast<std::uint64_t>(t_ns);
  char buf[32];
  char* end = buf;
  if (negative) *end++ = '-';
  end = std::to_chars(end, buf + sizeof(buf), mag / 1000000000ULL).ptr;
  *end++ = '.';
  // The nine decimals, zero-padded.
  std::uint64_t nanos = mag % 1000000000ULL;
  for (int i = 8; i >= 0; --i, nanos /= 10) end[i] = static_cast<char>('0' + nanos % 10);
  out->append(buf, end + 9);
}

std::string FormatSeconds(TimeNs t_ns) {
  std::string out;
  AppendSeconds(t_ns, &out);
  return out;
}

void AppendDouble(double value, std::string* out) {
  // to_chars with a precision is printf's %.17g to the byte (the standard says so), and a few
  // times faster than printf.
  char buf[40];
  const std::to_chars_result r =
      std::to_chars(buf, buf + sizeof(buf), value, std::chars_format::general, 17);
  out->append(buf, r.ptr);
}

std::string FormatDouble(double value) {
  std::string out;
  AppendDouble(value, &out);
  return out;
}

CsvReader::CsvReader(const std::string& path,
                     std::vector<std::string> columns,
                     const CsvOptions& options,
                     std::vector<std::string> optional_columns)
    : file_(path), options_(options), in_(path), names_(std::move(columns)) {
  required_count_ = names_.size();
  if (!in_) throw InputError(file_, 0, "", "cannot open file");
  if (!options_.header) return;
  std::string header;
  if (!ReadLine(&header)) throw InputError(file_, 0, "", "empty file: missing header row");
  std::string_view h = Trim(header);
  if (!h.empty() && h.front() == '#') h.remove_prefix(1);
  std::vector<std::string> got;
  Split(std::string(h), &got);
  std::vector<std::string> with_optional = names_;
  with_optional.insert(with_optional.end(), optional_columns.begin(), optional_columns.end());
  if (got == names_) return;
  if (!optional_columns.empty() && got == with_optional) {
    names_ = std::move(with_optional);
    return;
  }
  std::string expected = Quote(JoinNames(names_, options_.delimiter));
  if (!optional_columns.empty()) {
    expected += " or " + Quote(JoinNames(with_optional, options_.delimiter));
  }
  // Name the first column that differs, so the message points at the culprit.
  std::string field = "header";
  for (std::size_t i = 0; i < with_optional.size(); ++i) {
    if (i >= got.size() || got[i] != with_optional[i]) {
      field = with_optional[i];
      break;
    }
  }
  throw InputError(file_, line_, field,
                   "unexpected header " + Quote(std::string(h)) + ", expected " + expected);
}

bool CsvReader::ReadLine(std::string* line) {
  while (std::getline(in_, *line)) {
    ++line_;
    if (!line->empty() && line->back() == '\r') line->pop_back();
    if (IsBlank(*line)) continue;
    if (options_.skip_comments && Trim(*line).front() == '#') continue;
    return true;
  }
  return false;
}

void CsvReader::Split(const std::string& line, std::vector<std::string>* fields) const {
  // The strings of the previous row are written over, not made anew: a row of numbers longer
  // than the small-string buffer then costs no allocation.
  std::size_t count = 0;
  const auto put = [fields, &count](std::string_view piece) {
    if (count < fields->size()) {
      (*fields)[count].assign(piece.data(), piece.size());
    } else {
      fields->emplace_back(piece);
    }
    ++count;
  };
  if (options_.delimiter == ' ') {
    std::size_t i = 0;
    while (i < line.size()) {
      while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
      if (i >= line.size()) break;
      std::size_t j = i;
      while (j < line.size() && line[j] != ' ' && line[j] != '\t') ++j;
      put(std::string_view(line).substr(i, j - i));
      i = j;
    }
  } else {
    std::size_t start = 0;
    while (true) {
      const std::size_t pos = line.find(options_.delimiter, start);
      const std::string_view piece = std::string_view(line).substr(
          start, pos == std::string::npos ? std::string::npos : pos - start);
      put(Trim(piece));
      if (pos == std::string::npos) break;
      start = pos + 1;
    }
  }
  fields->resize(count);
}

std::int64_t CsvReader::bytes_read() {
  const std::streampos pos = in_.tellg();
  return pos < 0 ? -1 : static_cast<std::int64_t>(pos);
}

std::size_t CsvReader::RowsAtMost() const {
  // Not a pipe: reading one through would take its rows from the reader.
  std::error_code error;
  if (!std::filesystem::is_regular_file(file_, error)) return 0;
  std::FILE* f = std::fopen(file_.c_str(), "rb");
  if (f == nullptr) return 0;
  std::vector<char> buffer(1 << 20);
  std::size_t lines = 0, bytes = 0, got = 0;
  char last = '\n';
  while ((got = std::fread(buffer.data(), 1, buffer.size(), f)) > 0) {
    // memchr is vectorised: a few times faster here than std::count.
    const char* end = buffer.data() + got;
    for (const char* p = buffer.data();
         (p = static_cast<const char*>(std::memchr(p, '\n', end - p))) != nullptr; ++p) {
      ++lines;
    }
    bytes += got;
    last = buffer[got - 1];
  }
  std::fclose(f);
  if (last != '\n') ++lines;  // a last line without its line end
  const std::size_t columns = std::max<std::size_t>(names_.size(), 1);
  return std::min(lines, (bytes + 1) / columns);
}

bool CsvReader::Next() {
  if (!ReadLine(&raw_line_)) return false;
  Split(raw_line_, &fields_);
  const std::size_t n = names_.size();
  if (fields_.size() < n) {
    Fail(static_cast<int>(fields_.size()), "truncated row: " + std::to_string(fields_.size()) +
                                               " of " + std::to_string(n) + " fields");
  }
  if (fields_.size() > n) {
    FailField("columns", "too many fields: " + std::to_string(fields_.size()) + ", expected " +
                             std::to_string(n));
  }
  return true;
}

const std::string& CsvReader::GetString(int col) const { return fields_.at(col); }

double CsvReader::GetDouble(int col) const {
  const std::string& s = GetString(col);
  double v = 0.0;
  if (ParseDouble(s, &v)) return v;
  if (s.empty()) Fail(col, "empty field, expected a number");
  double inf_or_nan = 0.0;
  // Distinguish "not a number at all" from "a non-finite number" in the message.
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), inf_or_nan);
  if (ec == std::errc() && ptr == s.data() + s.size() && !std::isfinite(inf_or_nan)) {
    Fail(col, "non-finite value " + Quote(s));
  }
  if (ec == std::errc::result_out_of_range) Fail(col, "value out of range " + Quote(s));
  Fail(col, "not a number: " + Quote(s));
}

std::optional<double> CsvReader::GetOptionalDouble(int col) const {
  if (IsEmpty(col)) return std::nullopt;
  return GetDouble(col);
}

std::int64_t CsvReader::GetInt64(int col) const {
  const std::string& s = GetString(col);
  std::int64_t v = 0;
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || ec != std::errc() || ptr != s.data() + s.size()) {
    Fail(col, "not an integer: " + Quote(s));
  }
  return v;
}

TimeNs CsvReader::GetTimeNs(int col) const {
  const std::string& s = GetString(col);
  TimeNs t = 0;
  if (!ParseSecondsToNs(s, &t)) Fail(col, "not a time in seconds: " + Quote(s));
  return t;
}

TimeNs CsvReader::GetIncreasingTimeNs(int col) {
  const TimeNs t = GetTimeNs(col);
  CheckIncreasing(col, t);
  return t;
}

void CsvReader::CheckIncreasing(int col, TimeNs t_ns) {
  if (has_last_time_ && t_ns <= last_time_ns_) {
    Fail(col, "time " + FormatSeconds(t_ns) +
                  " s does not increase (previous row: " + FormatSeconds(last_time_ns_) + " s)");
  }
  has_last_time_ = true;
  last_time_ns_ = t_ns;
}

void CsvReader::Fail(int col, const std::string& message) const {
  FailField(col >= 0 && col < column_count() ? names_[col] : "column " + std::to_string(col + 1),
            message);
}

void CsvReader::FailField(const std::string& field, const std::string& message) const {
  throw InputError(file_, line_, field, message);
}

}  // namespace skerry
