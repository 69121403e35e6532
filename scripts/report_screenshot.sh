#!/usr/bin/env bash
# Makes the README's picture: the harbour comparison of four presets over 10 seeds, its report,
# and a headless-Chromium screenshot of it in docs/img/report.png.
#   bash scripts/report_screenshot.sh [OUT_DIR]   (default results/compare-harbour)
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
out=${1:-results/compare-harbour}
skerry=build/apps/skerry
[[ -x $skerry ]] || bash scripts/build.sh

"$skerry" compare --dataset harbour --seeds 10 \
  --config default --config lm-dense-schur --config dogleg-sparse --config short-window-no-gate \
  --out "$out"
"$skerry" report --run "$out" --out "$out/report.html"

profile=$(mktemp -d)
trap 'rm -rf "$profile"' EXIT
mkdir -p docs/img
chromium --headless --no-sandbox --disable-gpu --disable-quic --no-first-run \
  --disable-background-networking --disable-component-update --disable-sync --hide-scrollbars \
  --user-data-dir="$profile" --window-size=1400,4500 --virtual-time-budget=10000 \
  --screenshot="$PWD/docs/img/report.png" "file://$(realpath "$out/report.html")" 2>/dev/null
echo "docs/img/report.png from $out/report.html"
