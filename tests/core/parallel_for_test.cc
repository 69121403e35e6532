#include "skerry/core/parallel_for.h"

#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

namespace skerry {
namespace {

TEST(ParallelFor, EveryIndexOnceOnTheThreadsAsked) {
  for (const size_t count : {0u, 1u, 5u, 1000u}) {
    for (const int threads : {-1, 0, 1, 3}) {
      std::vector<std::atomic<int>> seen(count);
      std::mutex mutex;
      std::set<std::thread::id> ids;
      ASSERT_TRUE(ParallelFor(count, threads, [&](size_t i) {
        ++seen[i];
        const std::lock_guard<std::mutex> lock(mutex);
        ids.insert(std::this_thread::get_id());
        return true;
      }));
      for (size_t i = 0; i < count; ++i) EXPECT_EQ(seen[i], 1) << count << " " << threads;
      EXPECT_LE(ids.size(), static_cast<size_t>(std::max(threads, 1)));
      if (count == 0 || threads <= 1) {
        EXPECT_TRUE(ids.empty() || (ids.size() == 1 && *ids.begin() == std::this_thread::get_id()));
      }
    }
  }
  EXPECT_FALSE(InParallelFor());  // the flag is put back on the caller's thread
}

TEST(ParallelFor, AFailingBodyFailsTheLoop) {
  EXPECT_FALSE(ParallelFor(100, 3, [](size_t i) { return i != 57; }));
  EXPECT_FALSE(ParallelFor(100, 1, [](size_t i) { return i != 57; }));
  EXPECT_FALSE(InParallelFor());
  // A body that throws: the exception reaches the caller, whose thread is outside any loop
  // again (else every later loop on it would run alone).
  for (int repeat = 0; repeat < 20; ++repeat) {
    EXPECT_THROW(ParallelFor(100, 3,
                             [](size_t i) {
                               if (i == 57) throw std::runtime_error("frame 57");
                               return true;
                             }),
                 std::runtime_error);
    EXPECT_FALSE(InParallelFor());
  }
}

// A loop inside another's body runs on the thread that runs that body: the outer loop holds the
// threads it was given.
TEST(ParallelFor, ANestedLoopStaysOnItsCallersThread) {
  std::mutex mutex;
  std::vector<bool> inner_on_own_thread;
  ASSERT_TRUE(ParallelFor(4, 2, [&](size_t) {
    EXPECT_TRUE(InParallelFor());
    const std::thread::id outer = std::this_thread::get_id();
    std::set<std::thread::id> inner;
    std::mutex inner_mutex;
    ParallelFor(200, 4, [&](size_t) {
      const std::lock_guard<std::mutex> lock(inner_mutex);
      inner.insert(std::this_thread::get_id());
      return true;
    });
    const std::lock_guard<std::mutex> lock(mutex);
    inner_on_own_thread.push_back(inner.size() == 1 && *inner.begin() == outer);
    return true;
  }));
  ASSERT_EQ(inner_on_own_thread.size(), 4u);
  for (const bool b : inner_on_own_thread) EXPECT_TRUE(b);
}

}  // namespace
}  // namespace skerry
