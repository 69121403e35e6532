#!/usr/bin/env bash
# Configures (Ninja, Release) into ./build and builds everything. Extra arguments go to the
# configure step, e.g. scripts/build.sh -DSKERRY_BUILD_BENCH=OFF.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release "$@"
cmake --build build -j"$(nproc)"
