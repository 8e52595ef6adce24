#!/usr/bin/env bash
# Per-frame time of semlio_kitti under several --config YAML files, both
# presets, on one KITTI-layout sequence, pinned to one core, with the runs
# alternated round by round: this machine's speed drifts by up to 20 % within
# minutes, so only runs taken in the same minutes compare.
#   scripts/frame_time_configs.sh SEQUENCE_DIR CONFIG.yaml...
# SEQUENCE_DIR: a KITTI-layout folder (velodyne/*.bin, times.txt), e.g. the
# real KITTI raw snippet as scripts/frame_time.sh converts it
# (results/frame_time/kitti_raw). A config file `{}` is the preset as shipped.
# Prints, per config and preset, the median / mean / p90 whole-frame time and
# the median solve time over the tracked frames of every round (wall clock of
# report.json; on an otherwise idle core it equals the CPU time), and the
# keyframe count of the last round.
# Environment: BUILD_DIR (build), OUT (results/frame_time_configs), ROUNDS (3),
# CORE (0), PRESETS ("baseline full"), LABELS (none), KITTI_CORRECTION (on),
# SKIP_BUILD=1 (use BUILD_DIR as built).
set -euo pipefail
cd "$(dirname "$0")/.."
SEQ=${1:?usage: scripts/frame_time_configs.sh SEQUENCE_DIR CONFIG.yaml...}
shift
[ "$#" -gt 0 ] || { echo "usage: scripts/frame_time_configs.sh SEQUENCE_DIR CONFIG.yaml..."; exit 2; }
BUILD_DIR=${BUILD_DIR:-build}
OUT=${OUT:-results/frame_time_configs}
ROUNDS=${ROUNDS:-3}
CORE=${CORE:-0}
PRESETS=${PRESETS:-baseline full}
LABELS=${LABELS:-none}
KITTI_CORRECTION=${KITTI_CORRECTION:-on}

scripts/install_deps.sh python3-numpy
if [ -z "${SKIP_BUILD:-}" ]; then
  cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release > /dev/null
  cmake --build "$BUILD_DIR" -j 2 --target semlio_kitti
fi
mkdir -p "$OUT"
echo "== load before the runs: $(cut -d' ' -f1-3 /proc/loadavg) (1/5/15 min) on $(nproc) cores"
for round in $(seq 1 "$ROUNDS"); do
  for config in "$@"; do
    name=$(basename "$config" .yaml)
    for preset in $PRESETS; do
      run="$OUT/${name}_${preset}_$round"
      if ! taskset -c "$CORE" "$BUILD_DIR/examples/semlio_kitti" --sequence "$SEQ" --labels "$LABELS" \
          --preset "$preset" --kitti-correction "$KITTI_CORRECTION" --config "$config" --out "$run" --quiet --overwrite \
          > "$run.log" 2>&1; then
        echo "semlio_kitti failed: $config, $preset (see $run.log)"
        tail -n 3 "$run.log"
        exit 1
      fi
    done
  done
done
for config in "$@"; do
  name=$(basename "$config" .yaml)
  for preset in $PRESETS; do
    /usr/bin/python3 - "$OUT" "$name" "$preset" "$ROUNDS" <<'PY'
import json
import sys
import numpy as np
out, name, preset, rounds = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
total, solve, keyframes = [], [], 0
for r in range(1, rounds + 1):
    report = json.load(open(f"{out}/{name}_{preset}_{r}/report.json"))
    frames = [f for f in report["frames"] if f.get("status") not in ("initialized", "skipped")]
    total += [f["timings_ms"]["total"] for f in frames]
    solve += [f["timings_ms"]["solve"] for f in frames]
    keyframes = report["keyframe_count"]
print(f"{name:14s} {preset:8s} frame median {np.median(total):6.2f} mean {np.mean(total):6.2f} "
      f"p90 {np.percentile(total, 90):6.2f} ms | solve median {np.median(solve):6.2f} ms | "
      f"{len(total)} frames, {keyframes} keyframes per run")
PY
  done
done
echo "== load after the runs: $(cut -d' ' -f1-3 /proc/loadavg)"
