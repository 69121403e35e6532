#pragma once
/// \file
/// A loop over indices on several threads: what the batch's chain solver (its factors' costs and
/// sensor blocks) and a camera frame's residual (its samples' horizon traces) share.

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <future>
#include <vector>

namespace skerry {

/// True on a thread while it runs a ParallelFor's body (the caller's thread included).
inline bool& InParallelFor() {
  thread_local bool inside = false;  // each thread's own: set by the work it runs
  return inside;
}

/// body(i) for every i in [0, count) on `threads` threads, this one among them, each taking the
/// next run of indices when it is free (a camera frame's block costs a thousand times an IMU
/// factor, so a fixed split would leave a thread idle; runs of about a 64th of a thread's share
/// keep the hand-out rare where the bodies are cheap). False when a body returned false (the
/// others may stop early). Which thread runs which index varies, so a body writes only to its own
/// index. Called from inside another ParallelFor's body (a frame's traces inside the batch's
/// parallel blocks), it runs on the calling thread alone: the outer loop already holds the
/// threads, and nesting would start threads times threads. A body's exception reaches the caller
/// once every thread has stopped.
template <typename Body>
bool ParallelFor(size_t count, int threads, const Body& body) {
  const size_t workers =
      InParallelFor() ? 1 : std::min(count, static_cast<size_t>(std::max(threads, 1)));
  if (workers <= 1) {
    for (size_t i = 0; i < count; ++i) {
      if (!body(i)) return false;
    }
    return true;
  }
  const size_t run = std::max<size_t>(1, count / (workers * 64));
  std::atomic<size_t> next{0};
  std::atomic<bool> ok{true};
  auto work = [&] {
    // The thread's flag set while it works and put back however the body leaves (an exception
    // goes on to the caller: the helpers' through their futures).
    struct Inside {
      bool was = InParallelFor();
      Inside() { InParallelFor() = true; }
      ~Inside() { InParallelFor() = was; }
    } inside;
    for (size_t begin = next.fetch_add(run); begin < count; begin = next.fetch_add(run)) {
      const size_t end = std::min(count, begin + run);
      for (size_t i = begin; i < end; ++i) {
        if (!ok.load(std::memory_order_relaxed)) return;
        if (!body(i)) ok = false;
      }
    }
  };
  std::vector<std::future<void>> helpers;
  helpers.reserve(workers - 1);
  for (size_t t = 1; t < workers; ++t) helpers.push_back(std::async(std::launch::async, work));
  work();
  for (std::future<void>& h : helpers) h.get();
  return ok;
}

}  // namespace skerry
