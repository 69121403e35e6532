#!/usr/bin/env bash
# The LiDAR's mounting calibrated against the map (sensors.lidar.calibrate, docs/lidar_aerial.md):
# the harbour's turn run (config/scenarios/harbour-lidar-enter-turn-drift.yaml) with a consumer and
# a tactical IMU, over several seeds, its dataset's T_b_l declared as simulated or 2 degrees and
# (0.3, -0.2) m off, estimated by skerry's window with the preset lidar-harbour, the mounting held
# or calibrated; one table of heading and position errors and of the mounting found
# (bench/lidar/mount_calibration.py).
#   bash bench/lidar/mount_calibration.sh [OUT_DIR] [SEEDS]   # SEEDS: default 4
#   BATCH=1 bash bench/lidar/mount_calibration.sh ...         # and skerry's batch, calibrated
#   SKERRY=PATH bash bench/lidar/mount_calibration.sh ...     # another skerry binary
# Needs a build (scripts/build.sh). About 10 s per run, 32 runs with 4 seeds, two at a time
# (4 minutes on two cores); BATCH=1 adds 16 batches of about 20 s.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
skerry="${SKERRY:-$root/build/apps/skerry}"
out="${1:-$root/results/lidar-mount}"
seeds="${2:-4}"
mkdir -p "$out"
# The preset with the LiDAR's mounting estimated under a prior of 3 degrees and 0.5 m.
{ cat "$root/config/presets/lidar-harbour.yaml"
  printf 'sensors:\n  lidar:\n    calibrate: true\n    extrinsic_prior_sigma_deg: 3\n    extrinsic_prior_sigma_m: 0.5\n'
} > "$out/calibrate.yaml"
jobs=()
for grade in consumer tactical; do
  sed "s/^  grade: .*/  grade: $grade/" "$root/config/scenarios/harbour-lidar-enter-turn-drift.yaml" \
    > "$out/turn-$grade.yaml"
  for seed in $(seq 1 "$seeds"); do
    d="$out/$grade-$seed"
    "$skerry" simulate --scenario "$out/turn-$grade.yaml" --seed "$seed" --out "$d.exact.data" \
      --overwrite > /dev/null
    rm -rf "$d.off.data"
    cp -r "$d.exact.data" "$d.off.data"
    python3 "$here/mount_calibration.py" --declare-off "$d.off.data/dataset.yaml"
    for declared in exact off; do
      for config in held calibrate; do
        c=lidar-harbour
        [ "$config" = calibrate ] && c="$out/calibrate.yaml"
        "$skerry" run --dataset "$d.$declared.data" --config "$c" --out "$d.$declared.$config.run" \
          --overwrite -q &
        jobs+=($!)
        if [ ${#jobs[@]} -ge 2 ]; then wait "${jobs[@]}"; jobs=(); fi
        if [ "${BATCH:-0}" = 1 ] && [ "$config" = calibrate ]; then
          "$skerry" smooth --dataset "$d.$declared.data" --config "$c" \
            --out "$d.$declared.calibrate.batch" --overwrite -q &
          jobs+=($!)
          if [ ${#jobs[@]} -ge 2 ]; then wait "${jobs[@]}"; jobs=(); fi
        fi
      done
    done
  done
done
wait
python3 "$here/mount_calibration.py" --table "$out" "$seeds"
