#!/usr/bin/env bash
# The orthophoto read by window (geo::OrthophotoOptions::on_disk) and the map in tiles
# (lidar_aerial.map_tile_above_mcells, docs/lidar_aerial.md): the harbour's turn run
# (config/scenarios/harbour-lidar-enter-turn-drift.yaml, tactical IMU, seed 1) with its photo as
# simulated, then inside a 40000 x 40000 pixel canvas (a GDAL VRT, 1.6 gigapixels, no-data around
# the photo: a county's mosaic), which a reader that holds the whole image refuses (more than 2^28
# pixels), and resampled to 3 cm (a drone's mosaic: a tiled GeoTIFF of 14448 x 20075 pixels,
# read as block means of 4 x 4 pixels); each with one map of the track's box and with tiles.
# Prints per case the peak memory (GNU time), the tiles made, the time spent making maps and the
# accuracy, medians over RUNS runs.
#   bash bench/lidar/ortho_on_disk.sh [OUT_DIR] [RUNS]   # RUNS: default 3
#   SKERRY=PATH bash bench/lidar/ortho_on_disk.sh ...    # another skerry binary
# Needs a build (scripts/build.sh), GNU time (/usr/bin/time) and gdal_translate. About 10 s a run,
# six runs per round.
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
rm -rf "$out/drone.data"
cp -r "$out/photo.data" "$out/drone.data"
(cd "$out/drone.data" &&
  gdal_translate -q -of GTiff -tr 0.03 0.03 -r cubic -a_srs orthophoto.prj -co TILED=YES \
    -co COMPRESS=DEFLATE -co BIGTIFF=YES orthophoto.png mosaic.tif &&
  sed -i 's|^\(    file: \).*orthophoto.png$|\1mosaic.tif|' dataset.yaml &&
  grep -q 'file: mosaic.tif' dataset.yaml)
# The preset as it is (one map up to 16 million cells: the photo's box; tiles beyond: the
# canvas's), with tiles always, and with one map always.
python3 - "$root/config/presets/lidar-harbour.yaml" "$out" <<'PY'
import sys
preset, out = sys.argv[1], sys.argv[2]
text = open(preset).read()
assert "\nlidar_aerial:\n" in text
for name, value in (("tiles", 0), ("one-map", 1e9)):
    with open(f"{out}/{name}.yaml", "w") as f:
        f.write(text.replace("\nlidar_aerial:\n", f"\nlidar_aerial:\n  map_tile_above_mcells: {value}\n", 1))
PY
cases="photo:lidar-harbour photo:$out/tiles.yaml canvas:$out/one-map.yaml canvas:lidar-harbour
  drone:lidar-harbour drone:$out/tiles.yaml"
for k in $(seq 1 "$runs"); do
  i=0
  for c in $cases; do
    i=$((i + 1))
    /usr/bin/time -f '%M' -o "$out/case$i.$k.kb" \
      "$skerry" run --dataset "$out/${c%%:*}.data" --config "${c#*:}" \
      --out "$out/case$i.$k.run" --overwrite -q
  done
done
python3 - "$out" "$runs" <<'PY'
import json, statistics, sys
out, runs = sys.argv[1], int(sys.argv[2])
labels = ["photo as simulated (2709 x 3764 px), one map (the preset)",
          "photo as simulated, tiles",
          "photo in a 40000 x 40000 px canvas, one map",
          "photo in the canvas, tiles (the preset)",
          "photo at 3 cm (14448 x 20075 px), one map (the preset)",
          "photo at 3 cm, tiles"]
print(f"{'case':<58} {'peak MB':>8} {'tiles':>5} {'map s':>6} {'heading RMSE':>13} {'horizontal RMSE':>16}")
for i, label in enumerate(labels, start=1):
    kb, tiles, map_s, head, hor = [], [], [], [], []
    for k in range(1, runs + 1):
        kb.append(int(open(f"{out}/case{i}.{k}.kb").read().split()[-1]))
        s = json.load(open(f"{out}/case{i}.{k}.run/summary.json"))
        f = s["solver"]["sensors"]["lidar"]["frontend"]
        tiles.append(f["map_tiles"])
        map_s.append(f["map_s"])
        head.append(s["accuracy"]["heading_deg"]["rmse"])
        hor.append(s["accuracy"]["horizontal_m"]["rmse"])
    m = statistics.median
    print(f"{label:<58} {m(kb) / 1024:8.0f} {m(tiles):5.0f} {m(map_s):6.2f} {m(head):12.3f}° {m(hor):14.3f} m")
PY
