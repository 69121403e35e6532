#pragma once
// A fixture for tests that write a dataset folder, break one line of one file and expect the
// loader's InputError on that file, line and field.

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/test_util.h"
#include "skerry/io/dataset.h"

namespace skerry::testing {

class DatasetFolderTest : public ::testing::Test {
 protected:
  /// A fresh folder named `prefix` + the test's name.
  void MakeDir(const std::string& prefix) {
    dir_ = FreshDir(prefix + ::testing::UnitTest::GetInstance()->current_test_info()->name());
  }
  void ReplaceLine(const std::string& file, int line, const std::string& text) {
    std::vector<std::string> lines = ReadLines(dir_ + "/" + file);
    lines.at(line - 1) = text;
    WriteLines(dir_ + "/" + file, lines);
  }
  void ExpectError(const std::string& file, int line, const std::string& field) {
    ExpectInputError([&] { LoadDataset(dir_); }, file, line, field);
  }
  std::string dir_;
};

}  // namespace skerry::testing
