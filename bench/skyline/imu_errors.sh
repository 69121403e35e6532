#!/usr/bin/env bash
# Which of the IMU's errors that skerry does not model makes a skyline run's dead reckoning
# overconfident: one scenario simulated with each group of them taken out in turn, the window
# run on each with the default preset, and the span without GNSS evaluated (60 s to the end).
#   all           the scenario as it is (tactical grade: gyro 50 ppm / 0.1 mrad, accelerometer
#                 300 ppm / 0.1 mrad, a Gauss-Markov bias instability; docs/simulator.md)
#   no-gyro-sm    the gyro's scale factor and misalignment at 0
#   no-accel-sm   the accelerometer's scale factor and misalignment at 0
#   random-walk   the bias instability off: the biases wander as the datasheet's random walk, the
#                 estimator's own model (another draw of them: not the same biases as `all`)
#   matched       `skerry simulate --matched`: only what the estimator models
# The camera frames, waves and GNSS are the same draw in every variant (their own random
# streams). Prints a Markdown table: horizontal mean / max (m), heading RMSE, growth (last / first
# 5 minutes) and horizontal ANEES.
#   bash bench/skyline/imu_errors.sh [SCENARIO] [OUT_DIR] [SEED]
#   e.g. bash bench/skyline/imu_errors.sh bench/figures/cote-dazur-skyline.yaml results/imu 2
# About 4 minutes per variant on two cores (simulating the frames, then the window).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
skerry="${SKERRY:-$root/build/apps/skerry}"
scenario="$(realpath "${1:-$root/bench/figures/cote-dazur-skyline.yaml}")"
out="${2:-$root/results/skyline-imu-errors}"
seed="${3:-2}"
mkdir -p "$out"
dem_dir="$(dirname "$scenario")"

# The scenario with extra keys under `imu:` and its DEM's path made absolute (the copy lives
# elsewhere).
variant() {  # name keys...
  local name="$1"; shift
  python3 - "$scenario" "$dem_dir" "$out/$name.yaml" "$@" <<'PY'
import os, re, sys
src, dem_dir, dst, keys = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4:]
lines = open(src).read().splitlines()
text = []
for l in lines:
    m = re.match(r"^(\s+file:\s*)(\S+\.(hgt|tif|tiff|vrt))\s*$", l)
    if m and not os.path.isabs(m.group(2)):
        l = m.group(1) + os.path.normpath(os.path.join(dem_dir, m.group(2)))
    text.append(l)
    if l.startswith("imu:"):
        text.extend("  " + k for k in keys)
if not any(l.startswith("imu:") for l in lines) and keys:
    sys.exit("imu_errors.sh: the scenario has no imu: block")
open(dst, "w").write("\n".join(text) + "\n")
PY
}
variant all
variant no-gyro-sm "scale_factor_ppm: {gyro: 0}" "misalignment_mrad: {gyro: 0}"
variant no-accel-sm "scale_factor_ppm: {accel: 0}" "misalignment_mrad: {accel: 0}"
variant random-walk "bias_instability: {gyro_rad_s: 0, accel_m_s2: 0, tau_s: 0}"

echo "| IMU errors in the data | horizontal mean / max m | heading RMSE | growth | horizontal ANEES |"
echo "|---|---|---|---|---|"
for name in all no-gyro-sm no-accel-sm random-walk matched; do
  data="$out/$name.data"
  run="$out/$name.run"
  if [[ ! -f "$data/dataset.yaml" ]]; then
    if [[ "$name" == matched ]]; then
      "$skerry" simulate --scenario "$out/all.yaml" --seed "$seed" --matched --out "$data" \
        --overwrite > /dev/null
    else
      "$skerry" simulate --scenario "$out/$name.yaml" --seed "$seed" --out "$data" \
        --overwrite > /dev/null
    fi
  fi
  "$skerry" run --dataset "$data" --out "$run" --overwrite -q
  "$skerry" evaluate --estimate "$run/states.csv" --groundtruth "$data/groundtruth.tum" \
    --from 60 --json "$run/evaluate.json" > /dev/null
  python3 - "$run/evaluate.json" "$name" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))["span"]
print("| %s | %.2f / %.2f | %.4f° | %.2fx | %.2f |" % (
    sys.argv[2], s["horizontal_mean_m"], s["horizontal_max_m"], s["heading_rmse_deg"],
    s["growth"], s["anees_horizontal"]))
PY
done
