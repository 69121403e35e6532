#include "skerry/io/atomic_file.h"

#include <fcntl.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>

#include "skerry/core/input_error.h"

namespace skerry {

namespace {

// Flushes a written file (or a folder's entry list) to the disk, so that a power cut after the
// rename cannot leave the new name pointing at data that never reached it.
void SyncToDisk(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY);
  if (fd < 0) return;  // best effort: the rename is what makes the file appear whole
  ::fsync(fd);
  ::close(fd);
}

}  // namespace

AtomicFile::AtomicFile(std::string path)
    : path_(std::move(path)),
      temporary_(path_ + ".partial-" + std::to_string(static_cast<long>(::getpid()))) {
  out_.open(temporary_, std::ios::binary | std::ios::trunc);
  if (!out_) throw InputError(path_, 0, "", "cannot open file for writing");
}

AtomicFile::~AtomicFile() {
  if (committed_) return;
  out_.close();
  std::remove(temporary_.c_str());
}

void AtomicFile::Commit() {
  out_.flush();
  const bool written = static_cast<bool>(out_);
  out_.close();
  if (!written || out_.fail()) {
    std::remove(temporary_.c_str());
    committed_ = true;
    throw InputError(path_, 0, "", "write failed (disk full?)");
  }
  SyncToDisk(temporary_);
  if (std::rename(temporary_.c_str(), path_.c_str()) != 0) {
    std::remove(temporary_.c_str());
    committed_ = true;
    throw InputError(path_, 0, "", "cannot move the written file into place");
  }
  committed_ = true;
  const std::filesystem::path folder = std::filesystem::path(path_).parent_path();
  SyncToDisk(folder.empty() ? "." : folder.string());
}

void WriteFileAtomically(const std::string& path, const std::string& text) {
  AtomicFile file(path);
  file.stream() << text;
  file.Commit();
}

}  // namespace skerry
