#!/usr/bin/env bash
# The main job on your own KITTI odometry / SemanticKITTI sequence directory
# (velodyne/, optional labels/ or predictions/, calib.txt, times.txt, ground
# truth found as semlio_kitti documents): runs both presets, compares, plots.
#   scripts/run_kitti.sh SEQUENCE_DIR [OUT] [--labels labels|predictions|none] [--loop on] ...
# Extra options go to semlio_kitti unchanged; with --loop on each preset's
# poses.txt is the loop-closed trajectory (poses_odom.txt the odometry) and
# the plot shows both.
set -euo pipefail
cd "$(dirname "$0")/.."
SEQ=${1:?usage: scripts/run_kitti.sh SEQUENCE_DIR [OUT] [semlio_kitti options...]}
OUT=${2:-results/kitti}
shift $(( $# >= 2 ? 2 : 1 ))
BUILD_DIR=${BUILD_DIR:-build}

scripts/install_deps.sh python3-matplotlib
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release > /dev/null
cmake --build "$BUILD_DIR" -j "$(nproc)" --target semlio_kitti semlio_eval
for preset in baseline full; do
  "$BUILD_DIR/examples/semlio_kitti" --sequence "$SEQ" --preset "$preset" --out "$OUT/$preset" --quiet --overwrite "$@"
done
/usr/bin/python3 scripts/compare_reports.py "$OUT/baseline/report.json" "$OUT/full/report.json"
GT=()
if [ -f "$SEQ/poses.txt" ]; then GT=(--gt "$SEQ/poses.txt"); fi
ODOM=()
if ! cmp -s "$OUT/full/poses.txt" "$OUT/full/poses_odom.txt"; then
  ODOM=("baseline-odometry=$OUT/baseline/poses_odom.txt" "full-odometry=$OUT/full/poses_odom.txt")
fi
/usr/bin/python3 scripts/plot_trajectories.py "$OUT/trajectories.png" "${GT[@]}" \
  "baseline=$OUT/baseline/poses.txt" "full=$OUT/full/poses.txt" "${ODOM[@]}" --title "$SEQ"
echo "== wrote $OUT/{baseline,full}/ and $OUT/trajectories.png"
