#pragma once
// Reads a text file line by line, plain or gzip-compressed (zlib reads either transparently).
// Private to skerry_io.

#include <string>

namespace skerry {

class TextLines {
 public:
  /// Opens `path`; throws InputError naming it when it cannot be opened.
  explicit TextLines(const std::string& path);
  ~TextLines();
  TextLines(const TextLines&) = delete;
  TextLines& operator=(const TextLines&) = delete;

  /// The next line without its line end (LF or CRLF); false at the end of the file. Throws
  /// InputError on a read error (a corrupt gzip stream).
  bool Next(std::string* line);
  /// 1-based number of the line Next returned last.
  int line() const { return line_; }

 private:
  std::string path_;
  void* file_ = nullptr;  // gzFile
  int line_ = 0;
};

}  // namespace skerry
