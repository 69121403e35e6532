// AtomicFile: a file appears whole under its name or not at all (io/atomic_file.h).

#include "skerry/io/atomic_file.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>

#include "core/test_util.h"
#include "skerry/core/input_error.h"

namespace skerry {
namespace {

namespace fs = std::filesystem;
using testing::FreshDir;
using testing::ReadText;
using testing::WriteText;

size_t CountEntries(const std::string& dir) {
  size_t n = 0;
  for (const auto& e : fs::directory_iterator(dir)) n += e.is_regular_file();
  return n;
}

TEST(AtomicFile, NothingUnderTheNameUntilCommit) {
  const std::string dir = FreshDir("atomic-commit");
  const std::string path = dir + "/states.csv";
  AtomicFile file(path);
  file.stream() << "t,x\n1,2\n";
  EXPECT_FALSE(fs::exists(path));  // the text is in the temporary only
  file.Commit();
  EXPECT_EQ(ReadText(path), "t,x\n1,2\n");
  EXPECT_EQ(CountEntries(dir), 1u);  // no temporary left beside it
}

TEST(AtomicFile, AbandonedWriteLeavesThePreviousFileAndNoTemporary) {
  const std::string dir = FreshDir("atomic-abandon");
  const std::string path = dir + "/summary.json";
  WriteText(path, "{\"old\": true}\n");
  try {
    AtomicFile file(path);
    file.stream() << "{\"new\": ";
    throw std::runtime_error("the writer failed half-way");
  } catch (const std::runtime_error&) {
  }
  EXPECT_EQ(ReadText(path), "{\"old\": true}\n");
  EXPECT_EQ(CountEntries(dir), 1u);
}

TEST(AtomicFile, CommitReplacesAnOlderFile) {
  const std::string dir = FreshDir("atomic-replace");
  const std::string path = dir + "/a.txt";
  WriteText(path, "old and longer than the new text\n");
  WriteFileAtomically(path, "new\n");
  EXPECT_EQ(ReadText(path), "new\n");
}

TEST(AtomicFile, AFolderThatIsNotThereNamesThePath) {
  const std::string path = FreshDir("atomic-missing") + "/no/such/folder/x.csv";
  try {
    AtomicFile file(path);
    FAIL() << "opened a file in a folder that does not exist";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), path);
  }
}

TEST(AtomicFile, AFailedWriteThrowsAndLeavesTheTargetAlone) {
  const std::string dir = FreshDir("atomic-failed");
  const std::string path = dir + "/x.csv";
  WriteText(path, "complete\n");
  AtomicFile file(path);
  file.stream() << "partial";
  file.stream().setstate(std::ios::badbit);  // what a full disk does to the stream
  EXPECT_THROW(file.Commit(), InputError);
  EXPECT_EQ(ReadText(path), "complete\n");
  EXPECT_EQ(CountEntries(dir), 1u);
}

}  // namespace
}  // namespace skerry
