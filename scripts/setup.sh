#!/usr/bin/env bash
# Installs every build and test dependency of skerry from Debian 12 packages.
# Idempotent: when every package is already installed it returns at once, without apt-get.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

packages=(
  # toolchain
  cmake ninja-build g++ make git pkg-config
  # libraries
  libceres-dev libeigen3-dev libgeographiclib-dev libspdlog-dev libfmt-dev libyaml-cpp-dev
  libcli11-dev nlohmann-json3-dev zlib1g-dev
  # geodata (DEMs, orthophotos, CRSs; proj-data carries the EGM96 geoid grid), images, clouds
  libgdal-dev gdal-bin proj-data libopencv-dev libpcl-dev libnanoflann-dev
  # tests, benchmarks, format check
  libgtest-dev libgmock-dev libbenchmark-dev clang-format
  # peak memory of a whole command (bench/long_run.sh)
  time
  # the sanitizer suite and the fuzzers (scripts/sanitize.sh, scripts/fuzz.sh): clang with its
  # ASan/UBSan/libFuzzer runtimes, llvm-symbolizer for readable reports
  clang libclang-rt-dev llvm
  # HTML reports: Chart.js is embedded in the report; Chromium renders it in the tests
  libjs-chart.js chromium fonts-dejavu-core
  # skerry compare's GNU parallel runner, tested end to end
  parallel
)

# One dpkg-query for all: it prints the installed ones (and complains on stderr about the
# packages it has never heard of, which are missing too).
installed=$(dpkg-query -W -f='${db:Status-Abbrev} ${Package}\n' "${packages[@]}" 2>/dev/null |
  awk '$1 == "ii" { print $2 }' || true)
missing=()
for p in "${packages[@]}"; do
  grep -qxF -- "$p" <<<"$installed" || missing+=("$p")
done
if ((${#missing[@]} == 0)); then
  echo "setup: all ${#packages[@]} packages already installed"
  exit 0
fi

echo "setup: installing ${missing[*]}"
sudo_cmd=()
if ((EUID != 0)); then sudo_cmd=(sudo); fi
export DEBIAN_FRONTEND=noninteractive
"${sudo_cmd[@]}" apt-get update -q
"${sudo_cmd[@]}" apt-get install -y -q --no-install-recommends \
  -o DPkg::Lock::Timeout=300 "${missing[@]}"
