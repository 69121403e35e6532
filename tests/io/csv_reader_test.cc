#include "skerry/io/csv_reader.h"

#include <gtest/gtest.h>

#include <cmath>

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
