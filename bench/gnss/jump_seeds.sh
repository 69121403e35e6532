#!/usr/bin/env bash
# A receiver's jump on a consumer-grade (MEMS) harbour run, with and without the window's jump
# test (gnss.jump_test, docs/estimator.md, *Jumps*): SCENARIO seeds 1..N, by default
# harbour-consumer (a 14.5 m jump at 200-220 s, a 120 s outage at 360-480 s; also
# bench/gnss/long-jump.yaml, a 5 m jump for 90 s), the window (`skerry run`) and the batch
# (`skerry smooth`) with the default preset and with the same preset and `gnss.jump_test: false`.
# One row per seed and setting: heading RMSE over the run, horizontal RMSE and max over 0-360 s
# (the jump and everything before the outage), fixes refused as the jump, re-acquisitions (of
# them, on the receiver back from a jump the window had followed).
#   bash bench/gnss/jump_seeds.sh [OUT_DIR] [N_SEEDS] [SCENARIO]
# Needs a build (scripts/build.sh); about 10 s per seed on one core.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
skerry="${SKERRY:-$root/build/apps/skerry}"
out="${1:-$root/results/gnss-jump}"
seeds="${2:-6}"
scenario="${3:-harbour-consumer}"
mkdir -p "$out"

row() {  # seed setting estimator dir dataset
  "$skerry" evaluate --estimate "$4/states.csv" --groundtruth "$5/groundtruth.tum" \
    --from 0 --to 360 --json "$4/eval.json" > /dev/null
  python3 - "$1" "$2" "$3" "$4" <<'PY'
import json, sys
seed, setting, est, d = sys.argv[1:5]
ev = json.load(open(d + "/eval.json"))
g = json.load(open(d + "/summary.json"))["solver"].get("gnss", {})
sp = ev["span"]
print(f"| {seed} | {setting} | {est} | {ev['heading_deg']['rmse']:.2f} | "
      f"{sp['horizontal_rmse_m']:.2f} / {sp['horizontal_max_m']:.1f} | "
      f"{g.get('rejected_as_jump', '-')} | {g.get('accepted_on_reacquisition', '-')} "
      f"({g.get('reacquired_back_from_jump', '-')}) |")
PY
}

echo "| seed | jump test | estimator | heading RMSE deg | horizontal RMSE / max 0-360 s (m) | fixes refused as the jump | re-acquisitions (back from a jump) |"
echo "|---|---|---|---|---|---|---|"
for s in $(seq 1 "$seeds"); do
  d="$out/$(basename "$scenario" .yaml)-s$s"
  [ -f "$d/dataset.yaml" ] || "$skerry" simulate --scenario "$scenario" --seed "$s" --out "$d" \
    --overwrite > /dev/null
  for setting in on off; do
    set=(--set "gnss.jump_test=$([ "$setting" = on ] && echo true || echo false)")
    "$skerry" run --dataset "$d" "${set[@]}" --out "$out/w-$s-$setting" --overwrite -q
    "$skerry" smooth --dataset "$d" "${set[@]}" --out "$out/b-$s-$setting" --overwrite -q
    row "$s" "$setting" window "$out/w-$s-$setting" "$d"
    row "$s" "$setting" batch "$out/b-$s-$setting" "$d"
  done
done
