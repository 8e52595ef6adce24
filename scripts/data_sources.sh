#!/usr/bin/env bash
# Odometry on data from outside the simulator's KITTI layout, against the
# data-sources issue's bounds, and the page that shows it:
#   - a real KITTI raw drive read as published, lidar only and with its OXTS
#     IMU (scripts/kitti_raw_drive.sh): path length within 1 % of the OXTS
#     one, ATE <= 0.15 m;
#   - the real hand-held OS0-class keyframes of balm_os0 (scripts/balm_os0.sh
#     through semlio_run): beam table detected, no frame lost, median
#     keyframe-to-keyframe difference <= 5 cm / 0.5 deg, ATE <= 0.10 m;
#   - simulated urban drives with heavy traffic per sensor, each as a KITTI
#     folder, a ROS 1 bag and an MCAP file with ring and time fields and a
#     ROS 1 bag without them (scripts/accuracy_sensors_bags.sh): KITTI t_err
#     VLP-16 <= 1.0 %, OS1-64 and OS0-128 <= 0.5 %.
# Writes docs/data_sources.md (PAGE) and the README block between
# <!-- sources:begin --> and <!-- sources:end --> (README; empty: leave it).
#
#   scripts/data_sources.sh KITTI_RAW_DRIVE BALM_OS0_DIR [FRAMES]
#     KITTI_RAW_DRIVE: a YYYY_MM_DD_drive_NNNN_sync folder as published
#     BALM_OS0_DIR: the balm_os0 folder (velodyne/, times.txt, poses.txt);
#       "-" leaves that part out
#     FRAMES: simulated frames per sensor (default 1000; about 40 minutes
#       on one core of the 2-core reference machine for all three sensors)
# Environment: BUILD_DIR (build), SKIP_BUILD=1, OUT (results/data_sources),
# PAGE (docs/data_sources.md), README (README.md), SENSORS (as
# accuracy_sensors_bags.sh), SKIP_SENSORS=1 (reuse OUT/sensors).
# Exit 0 when the runs finished, whatever the verdicts (the page shows them).
set -euo pipefail
cd "$(dirname "$0")/.."
DRIVE=${1:?usage: scripts/data_sources.sh KITTI_RAW_DRIVE BALM_OS0_DIR [FRAMES]}
BALM=${2:?usage: scripts/data_sources.sh KITTI_RAW_DRIVE BALM_OS0_DIR [FRAMES]}
FRAMES=${3:-1000}
BUILD_DIR=${BUILD_DIR:-build}
OUT=${OUT:-results/data_sources}
PAGE=${PAGE:-docs/data_sources.md}
README=${README-README.md}

if [[ -z "${SKIP_BUILD:-}" ]]; then
  scripts/install_deps.sh python3-numpy
  cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release > /dev/null
  cmake --build "$BUILD_DIR" -j "$(nproc)" --target semlio_run semlio_simulate > /dev/null
fi
[[ -x "$BUILD_DIR/examples/semlio_run" ]] || { echo "data_sources.sh: $BUILD_DIR/examples/semlio_run missing" >&2; exit 1; }
mkdir -p "$OUT"
SECONDS=0

echo "== KITTI raw drive as published: $DRIVE"
SKIP_BUILD=1 BUILD_DIR="$BUILD_DIR" OUT="$OUT/drive" REPORT_ONLY=1 scripts/kitti_raw_drive.sh "$DRIVE" | tee "$OUT/drive.txt"

if [[ "$BALM" != - ]]; then
  for preset in baseline full; do
    echo "== balm_os0, $preset"
    # The evaluation exits 1 when a must-hold fails; the page shows which.
    PRESET=$preset SEMLIO_RUN="$BUILD_DIR/examples/semlio_run" scripts/balm_os0.sh "$BALM" "$OUT/balm_$preset" |
      tee "$OUT/balm_$preset.txt" || true
  done
fi

if [[ -z "${SKIP_SENSORS:-}" ]]; then
  echo "== simulated sensors, $FRAMES frames each"
  SKIP_BUILD=1 BUILD_DIR="$BUILD_DIR" OUT="$OUT/sensors" REPORT_ONLY=1 scripts/accuracy_sensors_bags.sh "$FRAMES" |
    tee "$OUT/sensors.txt"
fi

/usr/bin/python3 scripts/data_sources_page.py "$OUT" "$(basename "$DRIVE")" "$PAGE" "$README" "$SECONDS"
echo "data_sources.sh: wrote $PAGE${README:+ and the README block} in ${SECONDS} s"
