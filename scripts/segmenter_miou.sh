#!/usr/bin/env bash
# Measures GeometricSegmenter's IoU against exact labels: the simulator's on
# every world and, when given, real SemanticKITTI ground truth; prints
# markdown tables for the README.
#
#   scripts/segmenter_miou.sh [FRAMES] [SEED] [KITTI_DIR [LABELS_DIR]]
#
# FRAMES (default 20) frames per world, spread over the drive (every 10th
# frame of a FRAMES*10-frame drive), light traffic, seed SEED (default 1).
# KITTI_DIR: a KITTI / SemanticKITTI sequence folder (velodyne/*.bin) whose
# labels are in KITTI_DIR/labels or LABELS_DIR (e.g. tests/data/kitti/
# sequences/00 with tests/data/kitti/semantickitti_00_labels, or a full
# SemanticKITTI sequence of the shared data); every labelled scan is scored.
# mIoU follows SemanticKITTI's rules (eval/miou.hpp) over the 19 learning
# classes; "ground" merges road, parking, sidewalk, other-ground and terrain
# into one class, "pole/trunk" merges pole and trunk; the coarse classes are
# issue #38's six (examples/segment/segment_eval.hpp).
# Prints: the summary row per world; with KITTI_DIR the per-class tables per
# real scan; then one per-class table (19 and coarse classes) with a column
# for the real scans (pooled) and one per world.
# Environment: BUILD_DIR (default build-segment), JOBS (default 2),
# SKIP_BUILD=1 (use BUILD_DIR as built).
set -euo pipefail
cd "$(dirname "$0")/.."

FRAMES=${1:-20}
SEED=${2:-1}
KITTI_DIR=${3:-}
LABELS_DIR=${4:-}
BUILD_DIR=${BUILD_DIR:-build-segment}
JOBS=${JOBS:-2}
if [ -z "${SKIP_BUILD:-}" ]; then
  cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release > /dev/null
  cmake --build "$BUILD_DIR" -j "$JOBS" --target semlio_segment_eval > /dev/null
fi
BIN="$BUILD_DIR/examples/semlio_segment_eval"
WORLDS=(urban rural highway aliased)

echo "| world | mIoU | ground IoU | building IoU | vegetation IoU | pole/trunk IoU | car IoU |"
echo "|---|---|---|---|---|---|---|"
for world in "${WORLDS[@]}"; do
  "$BIN" --world "$world" --frames "$FRAMES" --seed "$SEED" --markdown
done

tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
cols=()
names=()
if [ -n "$KITTI_DIR" ]; then
  real=("$BIN" --sequence "$KITTI_DIR")
  [ -n "$LABELS_DIR" ] && real+=(--labels-dir "$LABELS_DIR")
  echo
  echo "Real scans ($KITTI_DIR), per scan and pooled:"
  echo
  "${real[@]}" --markdown
  "${real[@]}" --tsv > "$tmp/real.tsv"
  cols+=("$tmp/real.tsv")
  names+=("real (pooled)")
fi
for world in "${WORLDS[@]}"; do
  "$BIN" --world "$world" --frames "$FRAMES" --seed "$SEED" --tsv > "$tmp/$world.tsv"
  cols+=("$tmp/$world.tsv")
  names+=("$world")
done
# One row per class: the first column of every TSV is the same class list.
echo
echo "Per class (IoU; - = class absent from truth and prediction):"
echo
header="| class |"
rule="|---|"
for n in "${names[@]}"; do
  header+=" $n |"
  rule+="---|"
done
echo "$header"
echo "$rule"
paste "${cols[@]}" | awk -F'\t' '{
  row = "| " $1 " |"
  for (i = 2; i <= NF; i += 2) row = row " " $i " |"
  if ($1 ~ /mIoU/) { row = "| **" $1 "** |"; for (i = 2; i <= NF; i += 2) row = row " **" $i "** |" }
  print row
}'
