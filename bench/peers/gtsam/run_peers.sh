#!/usr/bin/env bash
# The GTSAM peer benchmark in one command (bench/peers/gtsam/README.md): builds GTSAM and the
# client into a cache if needed, simulates the scenarios with skerry, runs skerry's window and
# batch and the client's GTSAM runs on each, evaluates all with `skerry evaluate` and prints one
# Markdown table per scenario. Opt-in only: never part of skerry's build, tests or CI.
#
#   bench/peers/gtsam/run_peers.sh [--scenarios harbour,open-sea,harbour-consumer,FILE.yaml] [--seed 1]
#       [--modes isam2,isam2:keyframe,batch-fixed-lag,batch-lm] [--skip SCENARIO:RUN,...]
#       [--skerry PATH] [--repeats N] [-- CLIENT_OPTION...]
#
# A run is MODE (isam2, batch-fixed-lag, batch-lm) with the client's default update policy
# (every fix), or MODE:keyframe (--update-every-keyframe) / MODE:fix (--update-every-fix).
# --skip leaves runs out, e.g. --skip open-sea:batch-fixed-lag (the table says so). Options after
# `--` go to every client run (e.g. -- --isam2-factorization qr). --repeats (default 3): every
# estimator runs N times, interleaved; times and ratios are the medians over the repeats.
#
# Environment: SKERRY_PEER_CACHE (default ~/.cache/skerry-peers; GTSAM in install/, the client
# in client-build/, datasets and results in runs/), JOBS (compile jobs, default 1), and those of
# build_gtsam.sh. Everything runs under `nice -n 10`, one thing at a time.
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
repo=$(cd "$here/../../.." && pwd)
CACHE=${SKERRY_PEER_CACHE:-$HOME/.cache/skerry-peers}
export SKERRY_PEER_CACHE=$CACHE
JOBS=${JOBS:-1}
scenarios=harbour,open-sea,harbour-consumer
seed=1
modes=isam2,isam2:keyframe,batch-fixed-lag,batch-lm
skip=
skerry="$repo/build/apps/skerry"
repeats=3
client_options=()

while [[ $# -gt 0 ]]; do
  case "$1" in
    --scenarios) scenarios=$2; shift 2 ;;
    --seed) seed=$2; shift 2 ;;
    --modes) modes=$2; shift 2 ;;
    --skip) skip=$2; shift 2 ;;
    --skerry) skerry=$2; shift 2 ;;
    --repeats) repeats=$2; shift 2 ;;
    --) shift; client_options=("$@"); break ;;
    -h|--help) sed -n 2,19p "${BASH_SOURCE[0]}"; exit 0 ;;
    *) echo "run_peers.sh: unknown argument $1" >&2; exit 2 ;;
  esac
done

if [[ ! "$repeats" =~ ^[1-9][0-9]*$ ]]; then
  echo "run_peers.sh: --repeats $repeats: a whole number from 1" >&2
  exit 2
fi
IFS=, read -r -a scenario_list <<< "$scenarios"
IFS=, read -r -a mode_list <<< "$modes"
for run in "${mode_list[@]}"; do
  if [[ ! "$run" =~ ^(isam2|batch-fixed-lag|batch-lm)(:keyframe|:fix)?$ ]]; then
    echo "run_peers.sh: --modes $run: isam2, batch-fixed-lag or batch-lm, :keyframe or :fix" >&2
    exit 2
  fi
done

if [[ ! -x "$skerry" ]]; then
  echo "run_peers.sh: $skerry not found: build skerry first (cmake --build build)" >&2
  exit 2
fi

# 1. GTSAM (build_gtsam.sh returns at once when the pinned commit is installed) and the client.
JOBS=$JOBS nice -n 10 bash "$here/build_gtsam.sh"
client_build="$CACHE/client-build"
cmake -S "$here" -B "$client_build" -DCMAKE_BUILD_TYPE=Release \
  -DGTSAM_DIR="$CACHE/install/lib/cmake/GTSAM" > "$CACHE/client-configure.log"
nice -n 10 cmake --build "$client_build" -j "$JOBS" > "$CACHE/client-build.log"
peer="$client_build/gtsam_peer"
export LD_LIBRARY_PATH="$CACHE/install/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"

skerry_commit=$(git -C "$repo" rev-parse --short HEAD 2>/dev/null || echo unknown)
if [[ -n "$(git -C "$repo" status --porcelain --untracked-files=no 2>/dev/null)" ]]; then
  skerry_commit="$skerry_commit (with uncommitted changes)"
fi
gtsam_commit=$(cat "$CACHE/gtsam.commit" 2>/dev/null || echo unknown)

runs="$CACHE/runs"
mkdir -p "$runs"
echo "# GTSAM peer benchmark"
echo
echo "skerry $skerry_commit, GTSAM ${gtsam_commit:0:12}, seed $seed, $(date -u +%Y-%m-%dT%H:%MZ)"
echo "client options: ${client_options[*]:-(defaults)}"
echo "load before: $(uptime)"

for scenario in "${scenario_list[@]}"; do
  # A scenario is a name skerry knows or a scenario file (bench/figures/mems-900.yaml): its runs
  # are named after the file.
  label=$(basename "$scenario" .yaml)
  data="$runs/$label-$seed"
  out="$runs/$label-$seed-results"
  rm -rf "$out"
  mkdir -p "$out"
  rm -rf "$data"
  nice -n 10 "$skerry" simulate --scenario "$scenario" --seed "$seed" --out "$data" \
    > "$out/simulate.log" 2>&1 || { cat "$out/simulate.log" >&2; exit 1; }
  events=()  # scenarios without jumps or outages have no events.csv
  [[ -f "$data/events.csv" ]] && events=(--events "$data/events.csv")

  # Every estimator runs `repeats` times, interleaved (skerry's window and batch, then each client
  # run, then again), so that the ratios are measured in the same stretch of the machine's time:
  # repeat 1 writes into $out (its trajectories are the ones evaluated: every run is
  # deterministic), repeat k > 1 into $out/repeat-k (times only). peer_table.py takes medians.
  for ((rep = 1; rep <= repeats; rep++)); do
    dir=$out
    if ((rep > 1)); then
      dir="$out/repeat-$rep"
      mkdir -p "$dir"
    fi
    # skerry's sliding window and batch (their own timing is in summary.json / updates.csv),
    # with the client's models: the client does not estimate the gyro's calibration either.
    nice -n 10 "$skerry" run -q --overwrite --dataset "$data" --out "$dir/skerry-run" \
      --set estimate_gyro_calibration=false \
      > "$dir/skerry-run.log" 2>&1 || echo "skerry run failed on $scenario (see $dir)" >&2
    nice -n 10 "$skerry" smooth -q --overwrite --dataset "$data" --out "$dir/skerry-smooth" \
      --set estimate_gyro_calibration=false \
      > "$dir/skerry-smooth.log" 2>&1 || echo "skerry smooth failed on $scenario (see $dir)" >&2
    # ... and as a user runs them, with the default preset: it estimates the gyro's calibration
    # too (9 more numbers in every step), which the client does not.
    nice -n 10 "$skerry" run -q --overwrite --dataset "$data" --out "$dir/skerry-run-default" \
      > "$dir/skerry-run-default.log" 2>&1 ||
      echo "skerry run (default) failed on $scenario (see $dir)" >&2
    nice -n 10 "$skerry" smooth -q --overwrite --dataset "$data" \
      --out "$dir/skerry-smooth-default" > "$dir/skerry-smooth-default.log" 2>&1 ||
      echo "skerry smooth (default) failed on $scenario (see $dir)" >&2
    for run in "${mode_list[@]}"; do
      mode=${run%%:*}
      policy=()
      case "$run" in
        *:keyframe) policy=(--update-every-keyframe) ;;
        *:fix) policy=(--update-every-fix) ;;
      esac
      stem="$dir/gtsam-${run/:/-}"
      if [[ ",$skip," == *",$label:$run,"* ]]; then
        echo "--skip $label:$run" > "$stem.skipped"
        continue
      fi
      nice -n 10 "$peer" --dataset "$data" --mode "$mode" "${policy[@]}" \
        "${client_options[@]}" --out "$stem.tum" --json "$stem.json" > "$stem.log" 2>&1 ||
        echo "gtsam_peer $run failed on $scenario (see $stem.log)" >&2
    done
    # Only repeat 1's trajectories are kept and evaluated.
    if ((rep > 1)); then
      rm -f "$dir"/*.tum "$dir"/*/trajectory.tum "$dir"/*/states.csv "$dir"/*/covariances.csv
    fi
  done
  for name in skerry-run skerry-smooth skerry-run-default skerry-smooth-default; do
    if [[ -f "$out/$name/trajectory.tum" ]]; then
      "$skerry" evaluate --estimate "$out/$name/trajectory.tum" \
        --groundtruth "$data/groundtruth.tum" "${events[@]}" \
        --json "$out/$name.eval.json" > /dev/null 2>&1 || true
    fi
  done
  for run in "${mode_list[@]}"; do
    stem="$out/gtsam-${run/:/-}"
    if [[ -f "$stem.tum" ]]; then
      "$skerry" evaluate --estimate "$stem.tum" --groundtruth "$data/groundtruth.tum" \
        "${events[@]}" --json "$stem.eval.json" > /dev/null 2>&1 || true
    fi
  done

  echo
  echo "## $label (seed $seed)"
  echo
  echo "load after its runs: $(uptime)"
  echo
  python3 "$here/peer_table.py" "$out" "${mode_list[@]}"
done
echo
echo "load after: $(uptime)"
