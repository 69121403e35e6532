#!/usr/bin/env bash
# The whole test suite under AddressSanitizer + UndefinedBehaviorSanitizer (clang), and the
# libFuzzer binaries of tests/fuzz, from one build in ./build-asan: every file is compiled with
# -fsanitize=address,undefined, the readers also with libFuzzer's coverage instrumentation
# (tests/fuzz/CMakeLists.txt), so the fuzzers (scripts/fuzz.sh) run on the build the sanitized
# tests ran.
#   bash scripts/sanitize.sh            # configure, build, run every test (CI)
#   bash scripts/sanitize.sh --build    # configure and build only (what scripts/fuzz.sh needs)
# Every test runs; the ones whose cost is statistics over many seeds or hours of simulated time
# run a smaller workload in this build (tests/workload.h says how and why).
# Any sanitizer report fails the test it happens in (halt_on_error; UBSan does not recover).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

# UBSan skips Eigen's and Ceres' header templates (tests/sanitizer/ubsan_ignorelist.txt says why);
# ASan instruments everything.
flags="-fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer"
flags+=" -fsanitize-ignorelist=$PWD/tests/sanitizer/ubsan_ignorelist.txt"
# -O2, not the -O1 the sanitizers' manuals suggest: Eigen and Ceres need inlining, and at -O1
# the suite ran ~19x slower than Release (2 hours on 2 cores). No benchmarks (their figures
# would mean nothing here).
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_CXX_FLAGS="$flags" \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -g1 -DNDEBUG" \
  -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
  -DCMAKE_SHARED_LINKER_FLAGS="-fsanitize=address,undefined" \
  -DSKERRY_BUILD_BENCH=OFF -DSKERRY_FUZZ=ON -DSKERRY_TEST_TIMEOUT_SCALE=4
cmake --build build-asan -j"$(nproc)"
[[ ${1:-} == --build ]] && exit 0

# detect_leaks: the suite owns its memory; tests/sanitizer/lsan.supp would hold suppressions
# for leaks outside skerry (none needed so far).
export ASAN_OPTIONS="halt_on_error=1:detect_leaks=1:abort_on_error=0:strict_string_checks=1"
export LSAN_OPTIONS="suppressions=$PWD/tests/sanitizer/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:suppressions=$PWD/tests/sanitizer/ubsan.supp"
ctest --test-dir build-asan --output-on-failure -j"$(nproc)"
