#!/usr/bin/env bash
# Runs every libFuzzer target of tests/fuzz for a bounded time each, as many at once as there are
# cores, on the sanitizer build (scripts/sanitize.sh --build makes it when missing).
#   bash scripts/fuzz.sh [SECONDS_PER_TARGET]     (default 30)
# Corpora grow in build-asan/fuzz/corpus/NAME, seeded from tests/fuzz/corpus/NAME and, when
# ../shared/data is there, from real files. A crash, timeout, leak or sanitizer report leaves its
# input in build-asan/fuzz/crashes/NAME and fails the script: copy it into
# tests/fuzz/corpus/NAME (the replay test fuzz.NAME then runs it in every build) and fix it.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
seconds=${1:-30}

[[ -d build-asan ]] || bash scripts/sanitize.sh --build
cmake --build build-asan -j"$(nproc)" >/dev/null

shared=../shared/data
root=build-asan/fuzz
mkdir -p "$root"
# Real files, cut to their first lines: the fuzzer mutates lines, not megabytes.
seed_real() {
  local target=$1 prefix=$2 file=$3 lines=${4:-12}
  [[ -f $file ]] || return 0
  { printf '%b' "$prefix"; head -n "$lines" "$file"; } > "$root/corpus/$target/real-$(basename "$file")"
}

export ASAN_OPTIONS="halt_on_error=1:detect_leaks=1"
export LSAN_OPTIONS="suppressions=$PWD/tests/sanitizer/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1:suppressions=$PWD/tests/sanitizer/ubsan.supp"
export SKERRY_FUZZ_TMP=$PWD/$root

# One fuzz target: its corpus seeded, run for `seconds`, its line of the table in $root/NAME.row,
# and NAME.failed beside it when it crashed or reported anything.
fuzz_one() {
  local fuzzer=$1 name corpus crashes log start status execs found
  name=$(basename "$fuzzer" _fuzzer)
  corpus=$root/corpus/$name crashes=$root/crashes/$name
  mkdir -p "$corpus" "$crashes"
  rm -f "$root/$name.failed" "$root/$name.row"
  cp -n tests/fuzz/corpus/"$name"/* "$corpus"/ 2>/dev/null || true
  case $name in
    importers)
      seed_real importers '\x00' "$shared/euroc_v1_01/imu0_data.csv"
      seed_real importers '\x01' "$shared/husky/imu_data.csv"
      seed_real importers '\x01' "$shared/husky/fix.csv" ;;
    trajectory) seed_real trajectory '\x02' "$shared/euroc_v1_01/V1_01_easy.csv" ;;
  esac
  log=$root/$name.log
  start=$(date +%s)
  status=0
  "$fuzzer" "$corpus" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
    -max_len=8192 -artifact_prefix="$crashes/" -print_final_stats=1 > "$log" 2>&1 || status=$?
  execs=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' || echo 0)
  found=$(find "$crashes" -type f | wc -l)
  printf '%-16s %10s %8s %8s %s\n' "$name" "$execs" "$(ls "$corpus" | wc -l)" "$found" \
    "$(($(date +%s) - start))" > "$root/$name.row"
  if ((status != 0 || found > 0)); then touch "$root/$name.failed"; fi
  return 0
}

# The targets run side by side, one per core (each is single-threaded and keeps its temporary
# files in a folder of its own process, fuzz_files.h); the table comes out in target order.
jobs=$(nproc)
fuzzers=(build-asan/tests/fuzz/*_fuzzer)
running=0
for fuzzer in "${fuzzers[@]}"; do
  if ((running >= jobs)); then
    wait -n || true  # a target's own failure is in its .failed file, read below
    running=$((running - 1))
  fi
  fuzz_one "$fuzzer" &
  running=$((running + 1))
done
wait || true

failed=()
printf '%-16s %10s %8s %8s %s\n' target executions corpus crashes time_s
for fuzzer in "${fuzzers[@]}"; do
  name=$(basename "$fuzzer" _fuzzer)
  if [[ -f "$root/$name.row" ]]; then
    cat "$root/$name.row"
  else
    echo "$name: no result (the run of this target stopped before its end)"
    touch "$root/$name.failed"
  fi
  if [[ -e "$root/$name.failed" ]]; then
    failed+=("$name")
    grep -m 20 -E 'ERROR|SUMMARY|terminate|what\(\)|#[0-9] ' "$root/$name.log" | head -20 >&2 || true
  fi
done
if ((${#failed[@]} > 0)); then
  echo "fuzz.sh: crashes in: ${failed[*]} (inputs in $root/crashes/, logs in $root/)" >&2
  exit 1
fi
echo "fuzz.sh: no crash in $seconds s per target"
