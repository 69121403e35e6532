#!/usr/bin/env bash
# Builds GTSAM from its public source into a cache folder, for the peer benchmark only: never
# part of skerry's build, tests or CI. Release, system Eigen, no TBB (one thread, as skerry's
# benchmarks), no tests, examples or wrappers; the libraries gtsam and gtsam_unstable (its
# IncrementalFixedLagSmoother) are installed into $CACHE/install.
#
#   bench/peers/gtsam/build_gtsam.sh            # clone the pinned commit, configure, build
#   GTSAM_SOURCE=/path/to/gtsam bench/peers/gtsam/build_gtsam.sh   # an existing checkout
#
# Environment: SKERRY_PEER_CACHE (default ~/.cache/skerry-peers), GTSAM_SOURCE (a git
# repository to clone, or a plain exported tree of GTSAM_COMMIT used as it is; default: clone
# GTSAM_URL), GTSAM_COMMIT (default below), JOBS.
set -euo pipefail

GTSAM_URL=${GTSAM_URL:-https://github.com/borglab/gtsam.git}
# 4.3a0 (develop, 2024-10-23): the version the peer figures in docs/results.md were measured with.
GTSAM_COMMIT=${GTSAM_COMMIT:-0ffe6c930302ebd297484e65e6e8d467c91d26b0}
CACHE=${SKERRY_PEER_CACHE:-$HOME/.cache/skerry-peers}
JOBS=${JOBS:-$(nproc)}
src="$CACHE/gtsam-src"
build="$CACHE/gtsam-build"
install="$CACHE/install"

if [[ -f "$install/lib/cmake/GTSAM/GTSAMConfig.cmake" && -f "$CACHE/gtsam.commit" &&
      "$(cat "$CACHE/gtsam.commit")" == "$GTSAM_COMMIT" ]]; then
  echo "GTSAM $GTSAM_COMMIT already installed in $install"
  exit 0
fi

for pkg in cmake ninja-build g++ libeigen3-dev libboost-all-dev git; do
  if ! dpkg -s "$pkg" > /dev/null 2>&1; then
    echo "build_gtsam.sh: Debian package $pkg is missing (apt-get install $pkg)" >&2
    exit 1
  fi
done

mkdir -p "$CACHE"
if [[ -n "${GTSAM_SOURCE:-}" && -f "$GTSAM_SOURCE/CMakeLists.txt" && ! -e "$GTSAM_SOURCE/.git" ]]; then
  src="$GTSAM_SOURCE"  # an exported tree of GTSAM_COMMIT: used as it is
else
  if [[ ! -d "$src/.git" ]]; then
    rm -rf "$src"
    git clone --quiet "${GTSAM_SOURCE:-$GTSAM_URL}" "$src"
  fi
  git -C "$src" checkout --quiet --detach "$GTSAM_COMMIT"
fi

cmake -S "$src" -B "$build" -G Ninja \
  -DCMAKE_BUILD_TYPE=Release \
  -DCMAKE_INSTALL_PREFIX="$install" \
  -DGTSAM_BUILD_TESTS=OFF \
  -DGTSAM_BUILD_EXAMPLES_ALWAYS=OFF \
  -DGTSAM_BUILD_TIMING_ALWAYS=OFF \
  -DGTSAM_BUILD_UNSTABLE=ON \
  -DGTSAM_UNSTABLE_BUILD_PYTHON=OFF \
  -DGTSAM_BUILD_PYTHON=OFF \
  -DGTSAM_INSTALL_MATLAB_TOOLBOX=OFF \
  -DGTSAM_WITH_TBB=OFF \
  -DGTSAM_USE_SYSTEM_EIGEN=ON \
  -DGTSAM_USE_SYSTEM_METIS=OFF \
  -DGTSAM_BUILD_WITH_MARCH_NATIVE=OFF \
  -DGTSAM_ENABLE_BOOST_SERIALIZATION=OFF \
  -DGTSAM_POSE3_EXPMAP=ON \
  -DGTSAM_ROT3_EXPMAP=ON
cmake --build "$build" -j "$JOBS" --target gtsam gtsam_unstable
cmake --install "$build" --component Unspecified > /dev/null 2>&1 || cmake --build "$build" --target install
echo "$GTSAM_COMMIT" > "$CACHE/gtsam.commit"
echo "GTSAM $GTSAM_COMMIT installed in $install"
