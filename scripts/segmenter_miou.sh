#!/usr/bin/env bash
# Measures GeometricSegmenter's mIoU against the simulator's exact labels on
# every world and prints a markdown table for the README.
#
#   scripts/segmenter_miou.sh [FRAMES] [SEED]
#
# FRAMES (default 20) frames per world, spread over the drive (every 10th
# frame of a FRAMES*10-frame drive), light traffic, seed SEED (default 1).
# mIoU follows SemanticKITTI's rules (eval/miou.hpp) over the 19 learning
# classes; "ground" merges road, parking, sidewalk, other-ground and terrain
# into one class, "pole/trunk" merges pole and trunk.
# Environment: BUILD_DIR (default build-segment), JOBS (default 2),
# SKIP_BUILD=1 (use BUILD_DIR as built).
set -euo pipefail
cd "$(dirname "$0")/.."

FRAMES=${1:-20}
SEED=${2:-1}
BUILD_DIR=${BUILD_DIR:-build-segment}
JOBS=${JOBS:-2}
if [ -z "${SKIP_BUILD:-}" ]; then
  cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release > /dev/null
  cmake --build "$BUILD_DIR" -j "$JOBS" --target semlio_segment_eval > /dev/null
fi
BIN="$BUILD_DIR/examples/semlio_segment_eval"

echo "| world | mIoU | ground IoU | building IoU | vegetation IoU | pole/trunk IoU | car IoU |"
echo "|---|---|---|---|---|---|---|"
for world in urban rural highway aliased; do
  "$BIN" --world "$world" --frames "$FRAMES" --seed "$SEED" --markdown
done
