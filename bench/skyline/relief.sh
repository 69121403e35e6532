#!/usr/bin/env bash
# A skyline scenario's 20 minutes without GNSS in worlds with and without the relief a DEM's
# footprint averages away (`skerry simulate --dem-relief`, sim/terrain_relief.h), the window run on
# each with the map plain and sharpened (`skyline.dem_sharpening`, geo/terrain_sharpening.h):
# what the crests a real raster loses cost the window, and what sharpening the map gives back
# (docs/results.md, stop 67).
# For each seed and relief gain, simulates once, then runs the window once per sharpening gain
# (footprint `skyline.dem_footprint_cells`, 0.75 by default) and evaluates the span without GNSS
# (60-1260 s). Prints a row per run and a Markdown table. A sharpening of `est` estimates the gain
# with the states instead (`skyline.dem_sharpening_sigma: 1`), `offset` a crest offset
# (`skyline.crest_offset_sigma_m: 5`; docs/results.md, stop 68).
#   bash bench/skyline/relief.sh SCENARIO [OUT_DIR] [SEEDS] [RELIEFS] [SHARPENINGS]
#   e.g. bash bench/skyline/relief.sh bench/figures/lake-constance-skyline.yaml results/relief \
#          "1 2 3" "0 1" "0 est"
#   SKERRY=PATH ...                     # another skerry binary
# Needs a build (scripts/build.sh). About 10 minutes to simulate a forward camera's scenario on one
# core and 2-3 minutes a window run.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
skerry="${SKERRY:-$root/build/apps/skerry}"
scenario="${1:?usage: relief.sh SCENARIO [OUT_DIR] [SEEDS] [RELIEFS] [SHARPENINGS]}"
out="${2:-$root/results/skyline-relief}"
seeds="${3:-1}"
reliefs="${4:-0 1}"
sharpenings="${5:-0 2}"
mkdir -p "$out"
rows="$out/rows.tsv"
: > "$rows"
for seed in $seeds; do
  for relief in $reliefs; do
    data="$out/seed$seed-relief$relief.data"
    if [[ ! -f "$data/dataset.yaml" ]]; then
      "$skerry" simulate --scenario "$scenario" --seed "$seed" --dem-relief "$relief" \
        --out "$data" --overwrite > /dev/null
    fi
    for sharpening in $sharpenings; do
      run="$out/seed$seed-relief$relief-sharpening$sharpening.run"
      case "$sharpening" in
        est) set_map="skyline.dem_sharpening_sigma=1" ;;
        offset) set_map="skyline.crest_offset_sigma_m=5" ;;
        *) set_map="skyline.dem_sharpening=$sharpening" ;;
      esac
      "$skerry" run --dataset "$data" --set "$set_map" --out "$run" --overwrite > "$run.log"
      "$skerry" evaluate --estimate "$run/states.csv" --groundtruth "$data/groundtruth.tum" \
        --from 60 --json "$run/evaluate.json" > /dev/null
      python3 - "$run/evaluate.json" "$seed" "$relief" "$sharpening" >> "$rows" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))["span"]
print("\t".join(sys.argv[2:5] + ["%.2f" % s["horizontal_mean_m"], "%.2f" % s["horizontal_max_m"],
                                 "%.4f" % s["heading_rmse_deg"], "%.2f" % s["growth"],
                                 "%.2f" % s["anees_horizontal"]]))
PY
      tail -n 1 "$rows"
    done
  done
done
python3 - "$rows" <<'PY'
import sys
rows = [l.split("\t") for l in open(sys.argv[1]).read().splitlines() if l]
print("| seed | world's relief | map's sharpening | horizontal mean m | max m | heading RMSE deg | growth | horizontal ANEES |")
print("|---|---|---|---|---|---|---|---|")
for r in rows:
    print("| " + " | ".join(r) + " |")
PY
