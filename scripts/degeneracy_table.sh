#!/usr/bin/env bash
# Degeneracy flag rates, `baseline` and `full` side by side, on the same
# frames (the must-hold of the weak-direction criterion, solve/gauss_newton.hpp):
#   scripts/degeneracy_table.sh SNIPPET_PCD_DIR KITTI_RAW_DRIVE_DIR
#     SNIPPET_PCD_DIR      a folder of PCD scans, e.g. the 22-frame KITTI raw snippet
#     KITTI_RAW_DRIVE_DIR  a KITTI raw drive (velodyne_points/data/*.bin), e.g.
#                          2011_09_26_drive_0009_sync (51 frames)
# Runs semlio_kitti with both presets on the two real folders, on the main
# job's simulated drive (urban, heavy traffic, predicted labels, as
# scripts/demo.sh) and on a simulated highway, then prints per run: frames
# solved, frames flagged degenerate, and -- when report.json has them
# (SolveReport::normalized_eigenvalues, the weakest direction =
# SolveReport::eigenvectors.col(0)) -- the smallest normalised eigenvalue
# (median, min) and how many flagged frames are weakest along the direction
# of travel (|cos| > 0.9 between the weakest direction's translation and the
# scan's forward axis x). Then the synthetic corridor, tunnel, single wall and
# open field of tests/solve/test_degeneracy.cpp, if the area test executable
# semlio_tests_solve_solve is built (-DSEMLIO_AREA_TESTS=ON).
# Environment: BUILD_DIR (default build); OUT (results/degeneracy_table);
# SKIP_BUILD=1 (use BUILD_DIR as built); LABELS_REAL (geometric: the
# geometric segmenter's labels, so `full` weighs its terms; none: unlabelled);
# DEMO_FRAMES (300), HIGHWAY_FRAMES (150), SEED (1); SKIP_SIM=1 (real frames only).
set -euo pipefail
cd "$(dirname "$0")/.."
SNIPPET=${1:?usage: scripts/degeneracy_table.sh SNIPPET_PCD_DIR KITTI_RAW_DRIVE_DIR}
DRIVE=${2:?usage: scripts/degeneracy_table.sh SNIPPET_PCD_DIR KITTI_RAW_DRIVE_DIR}
BUILD_DIR=${BUILD_DIR:-build}
OUT=${OUT:-results/degeneracy_table}
LABELS_REAL=${LABELS_REAL:-geometric}
DEMO_FRAMES=${DEMO_FRAMES:-300}
HIGHWAY_FRAMES=${HIGHWAY_FRAMES:-150}
SEED=${SEED:-1}
BIN="$BUILD_DIR/examples"

if [ ! -d "$DRIVE/velodyne_points/data" ]; then
  echo "$DRIVE: no velodyne_points/data/ (expected a KITTI raw drive folder)"
  exit 2
fi
if ! ls "$SNIPPET"/*.pcd > /dev/null 2>&1; then
  echo "$SNIPPET: no .pcd files"
  exit 2
fi
if [ -z "${SKIP_BUILD:-}" ]; then
  scripts/install_deps.sh
  cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release > /dev/null
  cmake --build "$BUILD_DIR" -j "$(nproc)" --target semlio_convert semlio_kitti semlio_simulate
fi

rm -rf "$OUT" && mkdir -p "$OUT/snippet/velodyne" "$OUT/drive/velodyne"
# The real folders in KITTI odometry layout (velodyne/NNNNNN.bin, times.txt at 10 Hz).
mapfile -t pcds < <(ls "$SNIPPET"/*.pcd | sort)
for i in "${!pcds[@]}"; do
  "$BIN/semlio_convert" "${pcds[$i]}" "$OUT/snippet/velodyne/$(printf %06d "$i").bin" > /dev/null
done
mapfile -t bins < <(ls "$DRIVE"/velodyne_points/data/*.bin | sort)
for i in "${!bins[@]}"; do
  ln -s "$(realpath "${bins[$i]}")" "$OUT/drive/velodyne/$(printf %06d "$i").bin"
done
/usr/bin/python3 -c "[print(f'{0.1*i:.6f}') for i in range(${#pcds[@]})]" > "$OUT/snippet/times.txt"
/usr/bin/python3 -c "[print(f'{0.1*i:.6f}') for i in range(${#bins[@]})]" > "$OUT/drive/times.txt"

runs=()
run() {  # NAME SEQUENCE LABELS EXTRA...
  local name=$1 seq=$2 labels=$3
  shift 3
  for preset in baseline full; do
    "$BIN/semlio_kitti" --sequence "$seq" --labels "$labels" --preset "$preset" --map off --quiet \
      --out "$OUT/run_${name}_$preset" --overwrite "$@" > "$OUT/run_${name}_$preset.log" 2>&1 ||
      { echo "semlio_kitti failed on $name ($preset), see $OUT/run_${name}_$preset.log"; exit 1; }
  done
  runs+=("$name")
}
run "kitti_snippet_22" "$OUT/snippet" "$LABELS_REAL" --kitti-correction on
run "kitti_raw_0009_51" "$OUT/drive" "$LABELS_REAL" --kitti-correction on
if [ -z "${SKIP_SIM:-}" ]; then
  "$BIN/semlio_simulate" --world urban --traffic heavy --frames "$DEMO_FRAMES" --seed "$SEED" --out "$OUT/sim_urban" > /dev/null
  run "sim_urban_demo" "$OUT/sim_urban" predictions
  rm -rf "$OUT/sim_urban/velodyne"
  "$BIN/semlio_simulate" --world highway --traffic light --frames "$HIGHWAY_FRAMES" --seed "$SEED" --out "$OUT/sim_highway" > /dev/null
  run "sim_highway" "$OUT/sim_highway" predictions
  rm -rf "$OUT/sim_highway/velodyne"
fi

SYNTH=""
for t in "$BUILD_DIR/tests/semlio_tests_solve_solve" "$BUILD_DIR/tests/semlio_tests"; do
  if [ -x "$t" ]; then
    "$t" "[degeneracy]" -r junit -o "$OUT/synthetic.xml" > /dev/null 2>&1 || true
    SYNTH="$OUT/synthetic.xml"
    break
  fi
done

/usr/bin/python3 - "$OUT" "$SYNTH" "${runs[@]}" << 'EOF'
import json
import statistics
import sys
import xml.etree.ElementTree as ET

out, synth, names = sys.argv[1], sys.argv[2], sys.argv[3:]
print(f"{'frames':22}{'preset':>9}{'solved':>8}{'flagged':>9}{'along x':>9}{'min mu median':>15}{'min mu min':>12}")
for name in names:
    for preset in ("baseline", "full"):
        frames = json.load(open(f"{out}/run_{name}_{preset}/report.json"))["frames"]
        solved = [f for f in frames if f["status"] in ("tracked", "degenerate")]
        flagged = [f for f in solved if f["degenerate_directions"] > 0]
        mus = [min(f["normalized_eigenvalues"]) for f in solved if "normalized_eigenvalues" in f]
        along = "-"
        if solved and all("weakest_direction" in f for f in solved):
            def along_x(f):
                t = f["weakest_direction"][:3]
                n = sum(c * c for c in f["weakest_direction"]) ** 0.5
                return n > 0 and abs(t[0]) / n > 0.9
            along = str(sum(1 for f in flagged if along_x(f)))
        med = f"{statistics.median(mus):.3f}" if mus else "-"
        low = f"{min(mus):.3f}" if mus else "-"
        print(f"{name:22}{preset:>9}{len(solved):>8}{len(flagged):>9}{along:>9}{med:>15}{low:>12}")
if synth:
    print("\nsynthetic scenes (tests/solve/test_degeneracy.cpp, exact point-to-plane terms):")
    for case in ET.parse(synth).getroot().iter("testcase"):
        ok = case.find("failure") is None and case.find("error") is None
        print(f"  {'pass' if ok else 'FAIL'}  {case.get('name')}")
else:
    print("\n(synthetic scenes: build semlio_tests_solve_solve with -DSEMLIO_AREA_TESTS=ON to list them here)")
EOF
