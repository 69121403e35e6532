#!/usr/bin/env bash
# The spread of a skyline scenario's 20 minutes without GNSS over what one run does not vary:
# the world (the simulator's seed: waves, IMU, GNSS, frames) and where the estimator's map grid
# falls on the DEM's raster (`skyline.dem_spacing_m`: 0 for the default, half the raster's cell
# since stop 66 (`skyline.dem_oversampling`); or a spacing of its own, e.g. a few per mille off
# the raster's cell, which moves every node of the map against the raster's by up to a cell).
# One run is one draw: on Lake Constance (seed 1) the window's mean error was 3.8 m on the
# raster's cell and 4.5-5.2 m with the grid 0.2-0.3 % finer or coarser; over seeds 1-3 and those
# three spacings, 3.8-10.7 m, median 7.5 m (docs/results.md, stop 64); with the default map at
# half the cell, 2.8-6.0 m over seeds 1-3 (stop 66).
# For each seed, simulates, then runs the window once per spacing, and evaluates the span without
# GNSS (60-1260 s, `skerry evaluate --from 60`). Prints a row per run and the median, min and max
# of the mean horizontal error, the max and the heading RMSE.
#   bash bench/skyline/spread.sh SCENARIO [OUT_DIR] [SEEDS] [SPACINGS]
#   e.g. bash bench/skyline/spread.sh bench/figures/lake-constance-skyline.yaml results/spread \
#          "1 2 3" "0 62.667 63.0"      # 0: the default (half the raster's cell)
#   SKERRY=PATH ...                     # another skerry binary
# Needs a build (scripts/build.sh). About 5 minutes to simulate a forward camera's scenario on two
# cores and 1-2 minutes a window run.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
skerry="${SKERRY:-$root/build/apps/skerry}"
scenario="${1:?usage: spread.sh SCENARIO [OUT_DIR] [SEEDS] [SPACINGS]}"
out="${2:-$root/results/skyline-spread}"
seeds="${3:-1 2 3}"
spacings="${4:-0}"
from_s="${FROM_S:-60}"
mkdir -p "$out"
rows="$out/rows.tsv"
: > "$rows"
for seed in $seeds; do
  data="$out/seed$seed.data"
  if [[ ! -f "$data/dataset.yaml" ]]; then
    "$skerry" simulate --scenario "$scenario" --seed "$seed" --out "$data" --overwrite > /dev/null
  fi
  for spacing in $spacings; do
    run="$out/seed$seed-spacing$spacing.run"
    # The default preset with the map's spacing changed (0: the default, half the raster's cell).
    "$skerry" run --dataset "$data" --set "skyline.dem_spacing_m=$spacing" --out "$run" \
      --overwrite > "$run.log"
    "$skerry" evaluate --estimate "$run/states.csv" --groundtruth "$data/groundtruth.tum" \
      --from "$from_s" --json "$run/evaluate.json" > /dev/null
    python3 - "$run/evaluate.json" "$seed" "$spacing" >> "$rows" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))["span"]
print("\t".join([sys.argv[2], sys.argv[3], "%.2f" % s["horizontal_mean_m"],
                 "%.2f" % s["horizontal_max_m"], "%.4f" % s["heading_rmse_deg"],
                 "%.2f" % s["growth"], "%.2f" % s["anees_horizontal"]]))
PY
    tail -n 1 "$rows"
  done
done
python3 - "$rows" <<'PY'
import statistics, sys
rows = [l.split("\t") for l in open(sys.argv[1]).read().splitlines() if l]
print("| seed | map spacing m (0: the default, half the raster's cell) | horizontal mean m | max m | heading RMSE deg | growth | horizontal ANEES |")
print("|---|---|---|---|---|---|---|")
for r in rows:
    print("| " + " | ".join(r) + " |")
for name, col in (("horizontal mean m", 2), ("max m", 3), ("heading RMSE deg", 4)):
    v = [float(r[col]) for r in rows]
    print("%s over %d runs: median %.4g, min %.4g, max %.4g" %
          (name, len(v), statistics.median(v), min(v), max(v)))
PY
