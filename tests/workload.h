// How much work a test does: all of it in an ordinary build, less under the sanitizers.
//
// Under AddressSanitizer + UndefinedBehaviorSanitizer (scripts/sanitize.sh) skerry runs about
// 3x slower than in Release (docs/robustness.md, "Sanitizers"). The sanitizers look for memory
// errors, leaks and undefined behaviour along the code a test runs; a test whose cost is statistics
// over many seeds or hours of simulated time runs the same code on one seed or a shorter run there,
// so that the whole suite fits in CI. Requirements that are statistics over the full workload
// (medians over seeds, Monte-Carlo consistency) are checked in the ordinary build only (the test
// returns before them when !kFullWorkload); every check that holds for any workload stays on.

#pragma once

namespace skerry {
namespace test {

#if defined(__SANITIZE_ADDRESS__)  // gcc
inline constexpr bool kFullWorkload = false;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)  // clang
inline constexpr bool kFullWorkload = false;
#else
inline constexpr bool kFullWorkload = true;
#endif
#else
inline constexpr bool kFullWorkload = true;
#endif

/// `full` in an ordinary build, `sanitized` under the sanitizers (seeds, repetitions, seconds).
template <typename T>
constexpr T Workload(T full, T sanitized) {
  return kFullWorkload ? full : sanitized;
}

}  // namespace test
}  // namespace skerry
