#!/usr/bin/env bash
# The test command: installs dependencies, builds, runs every test, checks the formatting,
# builds and runs examples/embed against an installed skerry, runs every test again under the
# sanitizers and every fuzz target for a bounded time. CI runs exactly this.
# A failed build stops at once; the checks after it all run, and any failure fails the run.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

scripts/setup.sh
scripts/build.sh

failed=()
phase() { echo "test.sh: $1 took $((SECONDS - start)) s"; start=$SECONDS; }
start=$SECONDS
ctest --test-dir build --output-on-failure -j2 || failed+=("ctest")
phase "the test suite"
scripts/check_format.sh || failed+=("check_format")
scripts/check_embed.sh || failed+=("check_embed")
phase "format and embed checks"
# The same suite under AddressSanitizer + UndefinedBehaviorSanitizer, then every fuzz target for
# 20 s on that build (docs/robustness.md).
scripts/sanitize.sh || failed+=("sanitize")
phase "the sanitizer build and suite"
scripts/fuzz.sh 20 || failed+=("fuzz")
phase "fuzzing"

if ((${#failed[@]} > 0)); then
  echo "test.sh: FAILED: ${failed[*]}" >&2
  exit 1
fi
echo "test.sh: all checks passed"
