#!/usr/bin/env bash
# Issue 12's harbour runs: prior work's three runs with its two GNSS disturbances and the
# 10-minute GNSS-free tour, simulated (config/scenarios/harbour-lidar-*.yaml) and estimated by
# skerry's window with the LiDAR/aerial frontend (preset lidar-harbour); one table of position and
# heading errors against the simulator's truth (bench/lidar/harbour_eval.py).
#   bash bench/lidar/harbour_runs.sh [OUT_DIR] [SCENARIO...]
#   BASELINE=1 bash bench/lidar/harbour_runs.sh ...   # prior work's pipeline beside it
#   BATCH=1 bash bench/lidar/harbour_runs.sh ...      # and skerry's batch (skerry smooth)
#   SKERRY=PATH bash bench/lidar/harbour_runs.sh ...  # another skerry binary (default: the build's)
# Needs a build (scripts/build.sh). About 10 s per run and 40 s for the tour on one core; with
# BASELINE=1 prior work's matcher adds about 3 s per scan (5 minutes a run; the tour is left out).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
skerry="${SKERRY:-$root/build/apps/skerry}"
out="${1:-$root/results/lidar-harbour}"
shift || true
scenarios=("$@")
if [ ${#scenarios[@]} -eq 0 ]; then
  scenarios=(harbour-lidar-enter-starboard-drift harbour-lidar-enter-starboard-jump
             harbour-lidar-enter-turn-drift harbour-lidar-enter-turn-jump
             harbour-lidar-stationary-drift harbour-lidar-stationary-jump harbour-lidar-tour)
fi
mkdir -p "$out"
for s in "${scenarios[@]}"; do
  "$skerry" simulate --scenario "$s" --out "$out/$s.data" --overwrite > /dev/null
  "$skerry" run --dataset "$out/$s.data" --config lidar-harbour --out "$out/$s.run" --overwrite -q
  if [ "${BATCH:-0}" = 1 ]; then
    "$skerry" smooth --dataset "$out/$s.data" --config lidar-harbour --out "$out/$s.batch" \
      --overwrite -q
  fi
  if [ "${BASELINE:-0}" = 1 ] && [ "$s" != harbour-lidar-tour ]; then
    "$root/build/bench/skerry_harbour_baseline" --dataset "$out/$s.data" --out "$out/$s.baseline" \
      > /dev/null
  fi
done
python3 "$here/harbour_eval.py" "$out" "${scenarios[@]}"
