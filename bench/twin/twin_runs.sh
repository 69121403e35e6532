#!/usr/bin/env bash
# The figures of issue 15 (docs/results.md, "A digital twin"): skerry twin on a simulated
# recording whose models are known (identification against the simulator's parameters, the
# fidelity test, and a deliberately wrong twin with its GNSS noise doubled), on the real Husky
# and EuRoC V1_01 recordings before and after calibration, and on two real boat NMEA 2000 logs
# (no IMU: their GNSS statistics).
#
#   bash bench/twin/twin_runs.sh OUT [SKERRY]
#
# OUT receives one folder per case (each twin with its report.html) and summary.txt. About 25
# minutes on 2 cores.
set -euo pipefail
out=${1:?usage: twin_runs.sh OUT [SKERRY]}
here=$(cd "$(dirname "$0")/../.." && pwd)
skerry=${2:-$here/build/apps/skerry}
data=$here/../shared/data
mkdir -p "$out"
log=$out/summary.txt
: > "$log"
say() { echo "$@" | tee -a "$log"; }

# 1. A simulated recording in skerry's model world: white noise, one Gauss-Markov drift, a jump
#    and an outage; the simulator's parameters are in config/scenarios/harbour.yaml and the
#    default preset's drift (--matched).
"$skerry" simulate --scenario harbour --matched --seed 11 --out "$out/sim" --overwrite > /dev/null
say "== simulated harbour (matched), the twin of it"
"$skerry" twin --dataset "$out/sim" --out "$out/sim-twin" --overwrite 2>>"$out/stderr.txt" | tee -a "$log"

# 2. A deliberately wrong twin: the identified model with its GNSS white noise doubled.
python3 - "$out/sim-twin/twin.yaml" "$out/wrong-model.yaml" <<'PY'
import re, sys
text = open(sys.argv[1]).read()
model = text[text.index('\nmodel:'):]
def double(m):
    return f"{m.group(1)}{2 * float(m.group(2))}"
model = re.sub(r'(\n    white_sigma_horizontal_m: )([0-9.e+-]+)', double, model, count=1)
model = re.sub(r'(\n    white_sigma_vertical_m: )([0-9.e+-]+)', double, model, count=1)
end = re.search(r'\n[a-z_]+:', model[1:])
open(sys.argv[2], 'w').write(model[: end.start() + 1] if end else model)
PY
say "== the same recording, a twin with the GNSS white noise doubled"
"$skerry" twin --dataset "$out/sim" --out "$out/sim-wrong" --model "$out/wrong-model.yaml" \
  --overwrite 2>>"$out/stderr.txt" | tee -a "$log"

# 3. Real recordings: Husky (IMU + GPS) and EuRoC V1_01 (IMU, fixes from the Vicon truth with
#    0.5 m white noise), identified and calibrated.
"$skerry" import --format husky --input "$data/husky" --out "$out/husky" --overwrite > /dev/null
"$skerry" import --format euroc --input "$data/euroc_v1_01" --out "$out/euroc" \
  --fixes-rate 2 --fixes-sigma 0.5 --overwrite > /dev/null
for rec in husky euroc; do
  say "== $rec: identified, then calibrated"
  "$skerry" twin --dataset "$out/$rec" --out "$out/$rec-twin" --calibrate --overwrite 2>>"$out/stderr.txt" \
    | tee -a "$log"
done
# 4. A real marine log without IMU (NMEA 2000 from a Furuno receiver): its GNSS alone.
for log_name in figure8-fast wide-turn; do
  file=$(ls "$data"/boat/*-"$log_name".si.jsonl.gz | head -1)
  "$skerry" import --format nmea2000 "$file" --out "$out/boat-$log_name" --overwrite > /dev/null
  say "== boat $log_name (NMEA 2000, no IMU): identified, then calibrated"
  "$skerry" twin --dataset "$out/boat-$log_name" --out "$out/boat-$log_name-twin" --calibrate \
    --overwrite 2>>"$out/stderr.txt" | tee -a "$log"
done
# 5. One HTML page per twin: the test per block, the floor, the models, the runs.
for twin in sim-twin sim-wrong husky-twin euroc-twin boat-figure8-fast-twin boat-wide-turn-twin; do
  "$skerry" report --run "$out/$twin" --out "$out/$twin/report.html" > /dev/null
done
say "figures in $log; a report.html in each twin folder"
