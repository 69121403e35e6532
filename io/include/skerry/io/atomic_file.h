#pragma once
/// \file
/// A file that is written whole or not at all. Text goes to a temporary beside the target
/// (`<path>.partial-<pid>`); Commit() checks the stream, flushes it to disk and renames the
/// temporary onto the target, which POSIX makes atomic. A process killed while writing leaves the
/// target as it was (absent, or the previous complete file) and a temporary no reader looks for;
/// destroyed without Commit (an exception, an early return), the temporary is removed.

#include <fstream>
#include <string>

namespace skerry {

class AtomicFile {
 public:
  /// Opens the temporary; throws InputError naming `path` when it cannot be created.
  explicit AtomicFile(std::string path);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  std::ofstream& stream() { return out_; }
  const std::string& path() const { return path_; }
  /// Makes the file appear under its name; throws InputError ("write failed") when any write
  /// failed (a full disk), leaving the target untouched.
  void Commit();

 private:
  std::string path_;
  std::string temporary_;
  std::ofstream out_;
  bool committed_ = false;
};

/// Writes `text` to `path` through an AtomicFile.
void WriteFileAtomically(const std::string& path, const std::string& text);

}  // namespace skerry
