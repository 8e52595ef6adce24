#!/usr/bin/env bash
# The hand-held OS0 must-holds on the BALM keyframes (shared data, balm_os0/):
# beam table detected and reported, no frame lost or rejected, median
# keyframe-to-keyframe difference to the reference poses within 5 cm /
# 0.5 deg, ATE over the 60 keyframes at most 0.10 m.
#
# Usage: scripts/balm_os0.sh PATH_TO_balm_os0 [OUT_DIR]
#   Environment: SENSOR_YAML (default: the sensor section written below:
#   profile auto = detect the beam table, platform hand_held), PRESET
#   (baseline | full, default baseline), SEMLIO_RUN (path of a semlio_run
#   binary: run through the tool), CXX (default g++).
#
# The sensor settings come from the library (BeamDetector, resolve_sensor,
# settings_for_sensor with the hand-held motion profile): nothing here is
# tuned to this recording. With SEMLIO_RUN set the run goes through
# semlio_run --sensor FILE.yaml; otherwise through
# scripts/balm_os0_odometry.cpp, built here against include/ (1-4 minutes),
# the same library calls (configure_sensor) without the tool. Evaluation:
# scripts/balm_os0_eval.py (pure Python; also OUT_DIR/evaluation.json). Exit 0
# when every must-hold passes.
set -euo pipefail
if [[ $# -lt 1 ]]; then
  echo "usage: $0 PATH_TO_balm_os0 [OUT_DIR]" >&2
  exit 2
fi
seq="$1"
out="${2:-$(mktemp -d /tmp/balm_os0.XXXXXX)}"
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
for f in times.txt poses.txt velodyne; do
  [[ -e "$seq/$f" ]] || { echo "$0: $seq/$f not found (a balm_os0 folder has velodyne/, times.txt, poses.txt)" >&2; exit 2; }
done
mkdir -p "$out"
yaml="${SENSOR_YAML:-$out/sensor.yaml}"
if [[ -z "${SENSOR_YAML:-}" ]]; then
  cat > "$yaml" <<'YAML'
sensor:
  profile: auto        # beams detected from the first three scans
  platform: hand_held  # how the sensor is carried: sets the correction gates
YAML
fi
if [[ -n "${SEMLIO_RUN:-}" ]]; then
  # The tool: semlio_run reads the sensor YAML (--sensor FILE.yaml) itself.
  # --kitti-correction off: the folder has the KITTI layout but not KITTI's
  # HDL-64E calibration.
  SECONDS=0
  "$SEMLIO_RUN" --input "$seq" --format kitti --sensor "$yaml" --kitti-correction off --labels none \
    --preset "${PRESET:-baseline}" --map off --quiet --out "$out/run" --overwrite
  echo "run: semlio_run, $(ls "$seq"/velodyne/*.bin | wc -l) keyframes in ${SECONDS} s, outputs in $out/run"
  cp "$out/run/poses_odom.txt" "$out/poses.txt"
  python3 - "$out/run/report.json" "$out/status.txt" "$out/sensor.txt" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))
with open(sys.argv[2], "w") as f:
    for fr in r["frames"]:
        f.write(fr["status"] + "\n")
with open(sys.argv[3], "w") as f:
    for k, v in r.get("sensor", {}).items():
        f.write(f"{k} {v}\n")
PY
else
  # yaml-cpp and Eigen headers (Debian: libyaml-cpp-dev, libeigen3-dev; scripts/install_deps.sh).
  driver="$out/balm_os0_odometry"
  "${CXX:-g++}" -O2 -DNDEBUG -std=c++20 -I "$root/include" -I "$root/examples/common" -isystem /usr/include/eigen3 \
    "$root/scripts/balm_os0_odometry.cpp" -o "$driver" -lyaml-cpp
  SECONDS=0
  "$driver" "$seq" "$yaml" "$out" "${PRESET:-baseline}"
  echo "run: scripts/balm_os0_odometry.cpp, $(ls "$seq"/velodyne/*.bin | wc -l) keyframes in ${SECONDS} s, outputs in $out"
fi
# /usr/bin/python3 or any python3: the evaluation needs only the standard library.
python3 "$root/scripts/balm_os0_eval.py" "$seq/poses.txt" "$out/poses.txt" "$out/status.txt" "$out/sensor.txt" \
  "$out/evaluation.json"
