#!/usr/bin/env bash
# The orthophoto read by window (geo::OrthophotoOptions::on_disk, docs/lidar_aerial.md): the
# harbour's turn run (config/scenarios/harbour-lidar-enter-turn-drift.yaml, tactical IMU, seed 1)
# run as simulated, then with its photo inside a 40000 x 40000 pixel canvas (a GDAL VRT, 1.6
# gigapixels, no-data around the photo: a county's mosaic), which a reader that holds the whole
# image refuses (more than 2^28 pixels). Prints per run the peak memory (GNU time), the map's
# construction time and the accuracy, medians over RUNS runs.
#   bash bench/lidar/ortho_on_disk.sh [OUT_DIR] [RUNS]   # RUNS: default 3
#   SKERRY=PATH bash bench/lidar/ortho_on_disk.sh ...    # another skerry binary
# Needs a build (scripts/build.sh), GNU time (/usr/bin/time) and gdal_translate. About 30 s a run.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../.." && pwd)"
skerry="${SKERRY:-$root/build/apps/skerry}"
out="${1:-$root/results/ortho-on-disk}"
runs="${2:-3}"
mkdir -p "$out"
sed "s/^  grade: .*/  grade: tactical/" "$root/config/scenarios/harbour-lidar-enter-turn-drift.yaml" \
  > "$out/turn.yaml"
"$skerry" simulate --scenario "$out/turn.yaml" --seed 1 --out "$out/photo.data" --overwrite > /dev/null
rm -rf "$out/canvas.data"
cp -r "$out/photo.data" "$out/canvas.data"
(cd "$out/canvas.data" &&
  gdal_translate -q -of VRT -a_srs orthophoto.prj -a_nodata 0 \
    -srcwin -15000 -15000 40000 40000 orthophoto.png canvas.vrt &&
  sed -i 's|^\(    file: \).*orthophoto.png$|\1canvas.vrt|' dataset.yaml &&
  grep -q 'file: canvas.vrt' dataset.yaml)
for data in photo canvas; do
  for k in $(seq 1 "$runs"); do
    /usr/bin/time -f '%M' -o "$out/$data.$k.kb" \
      "$skerry" run --dataset "$out/$data.data" --config lidar-harbour \
      --out "$out/$data.$k.run" --overwrite -q
  done
done
python3 - "$out" "$runs" <<'PY'
import json, statistics, sys
out, runs = sys.argv[1], int(sys.argv[2])
print(f"{'orthophoto':<34} {'peak MB':>8} {'map s':>6} {'heading RMSE':>13} {'horizontal RMSE':>16}")
for data, label in (("photo", "as simulated (2709 x 3764 px)"),
                    ("canvas", "in a 40000 x 40000 px canvas")):
    kb, map_s, head, hor = [], [], [], []
    for k in range(1, runs + 1):
        kb.append(int(open(f"{out}/{data}.{k}.kb").read().split()[-1]))
        s = json.load(open(f"{out}/{data}.{k}.run/summary.json"))
        map_s.append(s["solver"]["sensors"]["lidar"]["frontend"]["map_s"])
        head.append(s["accuracy"]["heading_deg"]["rmse"])
        hor.append(s["accuracy"]["horizontal_m"]["rmse"])
    m = statistics.median
    print(f"{label:<34} {m(kb) / 1024:8.0f} {m(map_s):6.2f} {m(head):12.3f}° {m(hor):14.3f} m")
PY
