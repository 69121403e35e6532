#!/usr/bin/env bash
# Installs the built skerry into build/install, builds examples/embed against it the way an
# outside project would, and runs it. Needs scripts/build.sh to have run.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

prefix="$PWD/build/install"
rm -rf "$prefix"
cmake --install build --prefix "$prefix" >/dev/null
cmake -S examples/embed -B build/embed -G Ninja -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_PREFIX_PATH="$prefix" >/dev/null
cmake --build build/embed -j"$(nproc)"
# skerry was configured for the default prefix, so point it at the installed data; the example
# prints the scenario file it loaded, which must be the installed one.
SKERRY_SCENARIO_DIR="$prefix/share/skerry/scenarios" \
  SKERRY_PRESET_DIR="$prefix/share/skerry/presets" \
  timeout 300 build/embed/skerry_embed | tee build/embed/output.txt
grep -qxF "scenario file: $prefix/share/skerry/scenarios/harbour.yaml" build/embed/output.txt
echo "check_embed: examples/embed built against the installed skerry and ran"
