// A sensor stream's timing (stream_timing.h) on synthetic stamps of known rate, jitter and gaps.

#include "skerry/eval/stream_timing.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

namespace skerry {
namespace {

// A 100 Hz IMU with 0.2 ms of stamp jitter (intervals then scatter by sqrt(2) 0.2 ms) for 60 s,
// silent for 3 s from t = 20 s.
TEST(StreamTiming, HundredHertzWithJitterAndAThreeSecondGap) {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n01;
  std::vector<std::int64_t> stamps;
  const std::int64_t t0_ns = 1'700'000'000'000'000'000;
  int missing = 0;
  for (int k = 0; k < 6000; ++k) {
    if (k > 2000 && k < 2300) {
      ++missing;
      continue;
    }
    stamps.push_back(t0_ns + k * 10'000'000LL + std::llround(2e5 * n01(rng)));
  }
  ASSERT_EQ(missing, 299);
  const StreamTiming timing = AnalyseStreamTiming("imu", stamps);
  EXPECT_EQ(timing.name, "imu");
  EXPECT_EQ(timing.samples, 6000 - 299);
  EXPECT_NEAR(timing.duration_s, 59.99, 0.002);
  EXPECT_NEAR(timing.rate_hz, 100.0, 0.1);
  EXPECT_NEAR(timing.period_jitter_s, std::sqrt(2.0) * 2e-4, 0.15 * std::sqrt(2.0) * 2e-4);
  EXPECT_EQ(timing.gaps, 1);
  EXPECT_NEAR(timing.longest_gap_s, 3.0, 0.002);
  EXPECT_NEAR(timing.dropout_share, 299.0 / 6000.0, 1e-9);
  ASSERT_EQ(timing.gap_spans_s.size(), 1u);
  EXPECT_NEAR(timing.gap_spans_s[0].first, 20.0, 0.002);
  EXPECT_NEAR(timing.gap_spans_s[0].second, 23.0, 0.002);
}

// A 10 Hz stream missing single samples and a pair: gaps, counted by the epochs they stand for,
// but too short for gap_spans_s.
TEST(StreamTiming, ShortDropoutsAreGapsButNotSpans) {
  std::vector<std::int64_t> stamps;
  for (int k = 0; k < 1000; ++k) {
    if (k == 100 || k == 500 || k == 501) continue;
    stamps.push_back(k * 100'000'000LL);
  }
  const StreamTiming timing = AnalyseStreamTiming("gnss", stamps);
  EXPECT_NEAR(timing.rate_hz, 10.0, 1e-9);
  EXPECT_EQ(timing.period_jitter_s, 0.0);
  EXPECT_EQ(timing.gaps, 2);
  EXPECT_NEAR(timing.longest_gap_s, 0.3, 1e-9);
  EXPECT_NEAR(timing.dropout_share, 3.0 / 1000.0, 1e-12);
  EXPECT_TRUE(timing.gap_spans_s.empty());
}

TEST(StreamTiming, RejectsBadInput) {
  auto says = [](const std::vector<std::int64_t>& stamps, const std::string& what) {
    try {
      AnalyseStreamTiming("camera", stamps);
      ADD_FAILURE() << "no throw, expected " << what;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find("camera"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  };
  says({}, "0 stamps");
  says({5}, "1 stamps");
  says({0, 10, 20, 30, 40, 40, 50}, "stamp 5");
  says({0, 10, 20, 15}, "stamp 3");
}

}  // namespace
}  // namespace skerry
