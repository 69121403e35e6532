#!/usr/bin/env bash
# The test command: installs dependencies, builds, runs every test, checks the formatting, and
# builds and runs examples/embed against an installed skerry. CI runs exactly this.
# A failed build stops at once; the three checks after it all run, and any failure fails the run.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

scripts/setup.sh
scripts/build.sh

failed=()
ctest --test-dir build --output-on-failure -j2 || failed+=("ctest")
scripts/check_format.sh || failed+=("check_format")
scripts/check_embed.sh || failed+=("check_embed")

if ((${#failed[@]} > 0)); then
  echo "test.sh: FAILED: ${failed[*]}" >&2
  exit 1
fi
echo "test.sh: all checks passed"
