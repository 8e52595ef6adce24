#!/usr/bin/env bash
# Accuracy of both presets on a simulated drive (issue 5's must-hold runs):
#   scripts/accuracy_sim.sh [FRAMES] [TRAFFIC] [LABELS] [SEED]
# defaults: 1000 frames, no traffic, exact labels (labels/), seed 1.
# Use TRAFFIC=heavy LABELS=predictions for the full-vs-baseline comparison.
# Prints the side-by-side table and writes results/accuracy_<...>/.
# Environment: BUILD_DIR (build), OUT, SKIP_BUILD=1 (use BUILD_DIR as built;
# CI runs a 30-frame version this way).
set -euo pipefail
cd "$(dirname "$0")/.."
FRAMES=${1:-1000}
TRAFFIC=${2:-none}
LABELS=${3:-labels}
SEED=${4:-1}
BUILD_DIR=${BUILD_DIR:-build}
OUT=${OUT:-results/accuracy_${FRAMES}_${TRAFFIC}_${LABELS}_${SEED}}

if [ -z "${SKIP_BUILD:-}" ]; then
  scripts/install_deps.sh
  cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release > /dev/null
  cmake --build "$BUILD_DIR" -j "$(nproc)" --target semlio_simulate semlio_kitti
fi
"$BUILD_DIR/examples/semlio_simulate" --world urban --traffic "$TRAFFIC" --frames "$FRAMES" --seed "$SEED" --out "$OUT/drive"
for preset in baseline full; do
  "$BUILD_DIR/examples/semlio_kitti" --sequence "$OUT/drive" --labels "$LABELS" --preset "$preset" --out "$OUT/$preset" --quiet --overwrite
done
/usr/bin/python3 scripts/compare_reports.py "$OUT/baseline/report.json" "$OUT/full/report.json"
rm -rf "$OUT/drive/velodyne"  # 2+ GB of scans; the rest of the drive is kept
