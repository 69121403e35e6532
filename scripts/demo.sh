#!/usr/bin/env bash
# The demo: simulates the harbour scenario, runs the sliding-window estimator on it and makes
# an HTML report of the run. Run again, it replaces its own results (--overwrite).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

scripts/setup.sh
scripts/build.sh
./build/apps/skerry simulate --scenario harbour --seed 1 --overwrite --out results/harbour-data
./build/apps/skerry run --dataset results/harbour-data --overwrite --out results/harbour-run
./build/apps/skerry report --run results/harbour-run --out results/harbour-run/report.html
echo
echo "Simulated dataset: $PWD/results/harbour-data"
echo "Estimate:          $PWD/results/harbour-run"
echo "Report:            $PWD/results/harbour-run/report.html (open it in a browser)"
ls results/harbour-run
