#!/usr/bin/env bash
# The demo: simulates the harbour scenario and runs the sliding-window estimator on it.
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

scripts/setup.sh
scripts/build.sh
./build/apps/skerry simulate --scenario harbour --seed 1 --out results/harbour-data
./build/apps/skerry run --dataset results/harbour-data --out results/harbour-run
echo
echo "Simulated dataset: $PWD/results/harbour-data"
echo "Estimate:          $PWD/results/harbour-run"
ls results/harbour-run
