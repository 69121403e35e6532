#pragma once
/// \file
/// The one reader of delimited text in skerry (CSV, and whitespace-separated TUM), and the
/// matching number formatting for writers.
///
/// The reader tracks file and line, checks the header row against the expected column names,
/// requires every row to have exactly the header's number of fields, and parses numbers strictly
/// (the whole field must be a finite number). Every problem raises InputError(file, line, column
/// name, what is wrong).

#include <cstdint>
#include <fstream>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "skerry/core/time.h"

namespace skerry {

struct CsvOptions {
  /// Field separator; ' ' means "one or more spaces or tabs" (TUM).
  char delimiter = ',';
  /// Whether the first non-blank line is a header naming the columns. A leading '#' on the
  /// header is ignored (EuRoC writes `#timestamp [ns],...`); names are compared after trimming.
  bool header = true;
  /// Lines whose first non-blank character is '#' are skipped (TUM comments).
  bool skip_comments = false;
};

class CsvReader {
 public:
  /// Opens `path` and, with a header, checks it reads `columns` or `columns` followed by all of
  /// `optional_columns`. Without a header, rows must have exactly `columns.size()` fields and the
  /// names are used in error messages only. Throws InputError when the file cannot be opened, is
  /// empty or its header does not match.
  CsvReader(const std::string& path,
            std::vector<std::string> columns,
            const CsvOptions& options = CsvOptions(),
            std::vector<std::string> optional_columns = {});

  /// Advances to the next data row (blank lines are skipped). False at the end of the file.
  /// Throws InputError if the row has the wrong number of fields (field: the first missing
  /// column for a truncated row, "columns" for a row with too many).
  bool Next();

  const std::string& file() const { return file_; }
  /// 1-based line number of the current row.
  int line() const { return line_; }
  /// Bytes of the file read so far (-1 if unknown): with the file's size, how far a streamed
  /// read has come.
  std::int64_t bytes_read();
  /// At most how many rows the file holds: its lines, and no more than one per column_count()
  /// bytes (every field takes at least its delimiter or line end): blank lines by the thousand
  /// ask for little room. 0 if it is not a regular file (a pipe would lose its rows to the
  /// count) or cannot be read again.
  /// Reads the file through once more, at the speed of a memory scan when it is cached: a reader
  /// of a large file reserves its rows with it, and its vector never grows by doubling (a moment
  /// with the old and the new buffer both alive, and up to twice the room kept after).
  std::size_t RowsAtMost() const;
  /// Number of columns of every row (required + optional ones present in the header).
  int column_count() const { return static_cast<int>(names_.size()); }
  bool has_optional_columns() const { return names_.size() > required_count_; }
  const std::string& column_name(int col) const { return names_.at(col); }
  /// The current row's text (without line terminator).
  const std::string& raw_line() const { return raw_line_; }

  /// The raw (trimmed) text of a field.
  const std::string& GetString(int col) const;
  bool IsEmpty(int col) const { return GetString(col).empty(); }
  /// A finite double; the whole field must be the number.
  double GetDouble(int col) const;
  /// Empty field -> nullopt; otherwise as GetDouble.
  std::optional<double> GetOptionalDouble(int col) const;
  /// A decimal integer (e.g. EuRoC nanosecond stamps).
  std::int64_t GetInt64(int col) const;
  /// Decimal seconds converted exactly to nanoseconds (see ParseSecondsToNs).
  TimeNs GetTimeNs(int col) const;
  /// As GetTimeNs, and the time must be strictly greater than that of the previous row read
  /// through this function.
  TimeNs GetIncreasingTimeNs(int col);
  /// Throws InputError on column `col` unless t_ns is strictly greater than the time given to
  /// the previous call (of this or GetIncreasingTimeNs); then remembers it.
  void CheckIncreasing(int col, TimeNs t_ns);

  /// Throws InputError(file, current line, column name, message).
  [[noreturn]] void Fail(int col, const std::string& message) const;
  /// Throws InputError(file, current line, field, message).
  [[noreturn]] void FailField(const std::string& field, const std::string& message) const;

 private:
  bool ReadLine(std::string* line);
  void Split(const std::string& line, std::vector<std::string>* fields) const;

  std::string file_;
  CsvOptions options_;
  std::ifstream in_;
  std::vector<std::string> names_;
  std::size_t required_count_ = 0;
  int line_ = 0;
  std::string raw_line_;
  std::vector<std::string> fields_;
  bool has_last_time_ = false;
  TimeNs last_time_ns_ = 0;
};

/// Parses a finite double from the whole of `text` (an optional leading '+' is allowed).
/// Returns false on anything else, including NaN, Inf and out-of-range values.
bool ParseDouble(std::string_view text, double* value);

/// Parses decimal seconds into nanoseconds without going through a double, so that 9-decimal
/// stamps such as `1403715273.262142976` survive exactly. More than 9 decimals are rounded to
/// the nearest ns; exponent forms (`1.5e3`) go through a double. False if not a finite number or
/// out of the int64 ns range.
bool ParseSecondsToNs(std::string_view text, TimeNs* t_ns);

/// Nanoseconds as decimal seconds with exactly 9 decimals (exact, no floating point).
std::string FormatSeconds(TimeNs t_ns);

/// A double with 17 significant digits (round-trips exactly): the text of printf's `%.17g`.
std::string FormatDouble(double value);

/// FormatSeconds and FormatDouble appended to `out`: what a writer of many rows uses, a line at
/// a time into one buffer, without a string per number.
void AppendSeconds(TimeNs t_ns, std::string* out);
void AppendDouble(double value, std::string* out);

}  // namespace skerry
