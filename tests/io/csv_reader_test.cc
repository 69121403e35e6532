#include "skerry/io/csv_reader.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "core/test_util.h"
#include "skerry/core/input_error.h"

namespace skerry {
namespace {

using testing::ExpectInputError;
using testing::FreshDir;
using testing::WriteText;

TEST(InputErrorTest, MessageFormat) {
  EXPECT_STREQ(InputError("a/imu.csv", 12, "ax", "not a number").what(),
               "a/imu.csv:12: ax: not a number");
  EXPECT_STREQ(InputError("d.yaml", 0, "sensors.imu", "missing").what(),
               "d.yaml: sensors.imu: missing");
  const InputError e("f.csv", 3, "t", "x");
  EXPECT_EQ(e.file(), "f.csv");
  EXPECT_EQ(e.line(), 3);
  EXPECT_EQ(e.field(), "t");
}

TEST(ParseTest, SecondsAreExactToTheNanosecond) {
  TimeNs t = 0;
  ASSERT_TRUE(ParseSecondsToNs("1403715273.262142976", &t));
  EXPECT_EQ(t, 1403715273262142976LL);
  ASSERT_TRUE(ParseSecondsToNs("1432235497.988949", &t));
  EXPECT_EQ(t, 1432235497988949000LL);
  ASSERT_TRUE(ParseSecondsToNs("-0.5", &t));
  EXPECT_EQ(t, -500000000);
  ASSERT_TRUE(ParseSecondsToNs("12", &t));
  EXPECT_EQ(t, 12000000000LL);
  ASSERT_TRUE(ParseSecondsToNs("0.0000000015", &t));  // 10th decimal rounds
  EXPECT_EQ(t, 2);
  ASSERT_TRUE(ParseSecondsToNs("1.5e3", &t));
  EXPECT_EQ(t, 1500000000000LL);
  for (const char* bad : {"", ".", "-", "1.2.3", "abc", "nan", "inf", "1,5", "12345678901.0"}) {
    EXPECT_FALSE(ParseSecondsToNs(bad, &t)) << bad;
  }
}

TEST(ParseTest, FormatSecondsRoundTrips) {
  for (TimeNs t : {0LL, 1LL, -1LL, 1403715273262142976LL, -1999999999LL, 5000000000LL}) {
    TimeNs back = 0;
    ASSERT_TRUE(ParseSecondsToNs(FormatSeconds(t), &back)) << FormatSeconds(t);
    EXPECT_EQ(back, t);
  }
  EXPECT_EQ(FormatSeconds(1500000000), "1.500000000");
  EXPECT_EQ(FormatSeconds(-1), "-0.000000001");
}

TEST(ParseTest, DoublesAreStrict) {
  double v = 0.0;
  ASSERT_TRUE(ParseDouble("1.7e-4", &v));
  EXPECT_EQ(v, 1.7e-4);
  ASSERT_TRUE(ParseDouble("+2", &v));
  EXPECT_EQ(v, 2.0);
  ASSERT_TRUE(ParseDouble(FormatDouble(0.1), &v));
  EXPECT_EQ(v, 0.1);
  for (const char* bad : {"", "nan", "NaN", "inf", "-inf", "1.0x", "1 2", "abc", "++1", "1e999"}) {
    EXPECT_FALSE(ParseDouble(bad, &v)) << bad;
  }
}

// The writers' numbers: printf's %.17g to the byte (the files are what they were when printf
// wrote them), exact 9-decimal seconds.
TEST(FormatTest, AppendDoubleIsPrintfsPercent17g) {
  std::vector<double> values = {0.0,
                                -0.0,
                                0.1,
                                1.0 / 3.0,
                                -9.80665,
                                1e-5,
                                1e-4,
                                9.9999999999999995e-05,
                                1e16,
                                1e17,
                                123456789012345678.0,
                                5e-324,
                                2.2250738585072014e-308,
                                1.7976931348623157e308,
                                std::nextafter(1.0, 2.0),
                                1403715273.262142976};
  double x = 0.73;
  for (int k = 0; k < 2000; ++k) {  // a deterministic spread over magnitudes and digits
    x = std::fmod(x * 997.0 + 0.123456789, 1.0);
    values.push_back((k % 2 ? -1.0 : 1.0) * x * std::pow(10.0, k % 41 - 20));
  }
  for (double v : values) {
    char expected[40];
    std::snprintf(expected, sizeof(expected), "%.17g", v);
    std::string appended = "a,";
    AppendDouble(v, &appended);
    EXPECT_EQ(appended, std::string("a,") + expected);
    EXPECT_EQ(FormatDouble(v), expected);
  }
  for (TimeNs t : std::vector<TimeNs>{0, 7, -1, 999999999, 1000000000, -1999999999,
                                      1403715273262142976LL, std::numeric_limits<TimeNs>::max(),
                                      std::numeric_limits<TimeNs>::min()}) {
    char expected[48];
    const std::uint64_t mag =
        t < 0 ? static_cast<std::uint64_t>(-(t + 1)) + 1 : static_cast<std::uint64_t>(t);
    std::snprintf(expected, sizeof(expected), "%s%llu.%09llu", t < 0 ? "-" : "",
                  static_cast<unsigned long long>(mag / 1000000000ULL),
                  static_cast<unsigned long long>(mag % 1000000000ULL));
    std::string appended = "x";
    AppendSeconds(t, &appended);
    EXPECT_EQ(appended, std::string("x") + expected);
  }
}

class CsvReaderTest : public ::testing::Test {
 protected:
  std::string Write(const std::string& text) {
    const std::string path = FreshDir("csv_reader") + "/data.csv";
    WriteText(path, text);
    return path;
  }
};

TEST_F(CsvReaderTest, ReadsRowsAndTracksLines) {
  const std::string path = Write("t,a,b\n1.0,2,3\n\n2.5,-4e1,5\n");
  CsvReader reader(path, {"t", "a", "b"});
  ASSERT_TRUE(reader.Next());
  EXPECT_EQ(reader.line(), 2);
  EXPECT_EQ(reader.GetIncreasingTimeNs(0), 1000000000);
  EXPECT_EQ(reader.GetDouble(1), 2.0);
  ASSERT_TRUE(reader.Next());
  EXPECT_EQ(reader.line(), 4);  // the blank line is skipped but counted
  EXPECT_EQ(reader.GetDouble(1), -40.0);
  EXPECT_FALSE(reader.Next());
}

// A row's fields are its own: the strings of a longer row before are written over, not kept.
TEST_F(CsvReaderTest, FieldsAreTheCurrentRows) {
  const std::string path = Write("t,a,b\n1.0,-0.0012345678901234567,long text here\n2,3,x\n");
  CsvReader reader(path, {"t", "a", "b"});
  ASSERT_TRUE(reader.Next());
  EXPECT_EQ(reader.GetString(2), "long text here");
  ASSERT_TRUE(reader.Next());
  EXPECT_EQ(reader.GetString(1), "3");
  EXPECT_EQ(reader.GetDouble(1), 3.0);
  EXPECT_EQ(reader.GetString(2), "x");
}

// RowsAtMost: the lines (a last one without its line end counted), no more than one a
// column_count() bytes; 0 for a file that cannot be read.
TEST_F(CsvReaderTest, RowsAtMostBoundsTheRows) {
  EXPECT_EQ(CsvReader(Write("t,a\n1,2\n3,4\n"), {"t", "a"}).RowsAtMost(), 3u);
  EXPECT_EQ(CsvReader(Write("t,a\n1,2\n3,4"), {"t", "a"}).RowsAtMost(), 3u);
  // 1000 blank lines: (1008 + 1) bytes / 2 columns.
  EXPECT_EQ(CsvReader(Write("t,a\n" + std::string(1000, '\n') + "1,2\n"), {"t", "a"}).RowsAtMost(),
            504u);
  const std::string path = Write("t,a\n1,2\n");
  CsvReader reader(path, {"t", "a"});
  std::remove(path.c_str());
  EXPECT_EQ(reader.RowsAtMost(), 0u);
  ASSERT_TRUE(reader.Next());  // the open stream still reads
}

TEST_F(CsvReaderTest, TruncatedRowNamesFirstMissingColumn) {
  const std::string path = Write("t,a,b\n1.0,2,3\n2.0,2\n");
  CsvReader reader(path, {"t", "a", "b"});
  ASSERT_TRUE(reader.Next());
  ExpectInputError([&] { reader.Next(); }, "data.csv", 3, "b");
}

TEST_F(CsvReaderTest, TooManyFields) {
  const std::string path = Write("t,a,b\n1.0,2,3,\n");
  CsvReader reader(path, {"t", "a", "b"});
  ExpectInputError([&] { reader.Next(); }, "data.csv", 2, "columns");
}

TEST_F(CsvReaderTest, BadValuesNameTheirColumn) {
  const std::string path = Write("t,a,b\n1.0,nan,x\n1.0,inf,1\n");
  CsvReader reader(path, {"t", "a", "b"});
  ASSERT_TRUE(reader.Next());
  ExpectInputError([&] { reader.GetDouble(1); }, "data.csv", 2, "a");
  ExpectInputError([&] { reader.GetDouble(2); }, "data.csv", 2, "b");
  reader.GetIncreasingTimeNs(0);
  ASSERT_TRUE(reader.Next());
  ExpectInputError([&] { reader.GetDouble(1); }, "data.csv", 3, "a");
  ExpectInputError([&] { reader.GetIncreasingTimeNs(0); }, "data.csv", 3, "t");
}

TEST_F(CsvReaderTest, HeaderMustMatch) {
  const std::string path = Write("t,a,c\n1,2,3\n");
  ExpectInputError([&] { CsvReader reader(path, {"t", "a", "b"}); }, "data.csv", 1, "b");
  ExpectInputError([&] { CsvReader reader(Write(""), {"t"}); }, "data.csv", 0, "");
  ExpectInputError([&] { CsvReader reader(path + ".missing", {"t"}); }, "data.csv.missing", 0, "");
}

TEST_F(CsvReaderTest, OptionalColumnsAndCommentedHeader) {
  const std::string path = Write("#t, a ,x,y\r\n1,2,,\r\n");
  CsvReader reader(path, {"t", "a"}, CsvOptions(), {"x", "y"});
  EXPECT_TRUE(reader.has_optional_columns());
  ASSERT_TRUE(reader.Next());
  EXPECT_FALSE(reader.GetOptionalDouble(2).has_value());
  EXPECT_EQ(reader.GetDouble(1), 2.0);
}

TEST_F(CsvReaderTest, WhitespaceSeparatedWithComments) {
  const std::string path = Write("# comment\n1 2\t 3\n  # another\n2 3 4\n");
  CsvOptions options;
  options.delimiter = ' ';
  options.header = false;
  options.skip_comments = true;
  CsvReader reader(path, {"t", "x", "y"}, options);
  ASSERT_TRUE(reader.Next());
  EXPECT_EQ(reader.line(), 2);
  EXPECT_EQ(reader.GetDouble(2), 3.0);
  ASSERT_TRUE(reader.Next());
  EXPECT_EQ(reader.line(), 4);
}

}  // namespace
}  // namespace skerry
