#pragma once
// Helpers shared by the core tests.

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "skerry/core/input_error.h"

namespace skerry::testing {

/// A fresh, empty scratch folder under the test binary directory, unique to the running test
/// (ctest runs tests in parallel processes).
inline std::string FreshDir(const std::string& name) {
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  // Outside a test (SetUpTestSuite), a folder of this process: ctest runs every test of a
  // suite in its own process, in parallel, and each runs the suite's set-up.
  const std::string test = info == nullptr
                               ? "process-" + std::to_string(getpid()) + "/"
                               : std::string(info->test_suite_name()) + "." + info->name() + "/";
  const std::filesystem::path dir = std::filesystem::path(SKERRY_TEST_TMP_DIR) / (test + name);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

inline void WriteText(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  ASSERT_TRUE(out) << path;
  out << text;
}

inline std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

inline std::vector<std::string> ReadLines(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

inline void WriteLines(const std::string& path, const std::vector<std::string>& lines) {
  std::ofstream out(path);
  for (const std::string& line : lines) out << line << '\n';
}

/// Runs `f` and expects an InputError whose file ends with `file_suffix`, on `line`, for `field`.
inline void ExpectInputError(const std::function<void()>& f,
                             const std::string& file_suffix,
                             int line,
                             const std::string& field) {
  try {
    f();
    ADD_FAILURE() << "no InputError thrown (expected " << file_suffix << ":" << line << ": "
                  << field << ")";
  } catch (const InputError& e) {
    const std::string& file = e.file();
    EXPECT_TRUE(file.size() >= file_suffix.size() &&
                file.compare(file.size() - file_suffix.size(), file_suffix.size(), file_suffix) ==
                    0)
        << "file " << file << ", message: " << e.what();
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_EQ(e.field(), field) << e.what();
  }
}

}  // namespace skerry::testing
