#!/usr/bin/env bash
# The hand-held OS0 must-holds on the BALM keyframes (shared data, balm_os0/):
# beam table detected and reported, no frame lost or rejected, median
# keyframe-to-keyframe difference to the reference poses within 5 cm /
# 0.5 deg, ATE over the 60 keyframes at most 0.10 m.
#
# Usage: scripts/balm_os0.sh PATH_TO_balm_os0 [OUT_DIR]
#   Environment: SENSOR_YAML (default: the sensor section written below:
#   profile auto = detect the beam table, platform hand_held), PRESET
#   (baseline | full, default baseline), CXX (default g++).
#
# The sensor settings come from the library (BeamDetector, resolve_sensor,
# settings_for_sensor with the hand-held motion profile): nothing here is
# tuned to this recording. semlio_kitti does not read the YAML's sensor
# section yet, so the run goes through scripts/balm_os0_odometry.cpp, built
# here against include/ (about 1-4 minutes). Evaluation:
# scripts/balm_os0_eval.py (pure Python). Exit 0 when every must-hold passes.
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
# yaml-cpp and Eigen headers (Debian: libyaml-cpp-dev, libeigen3-dev; scripts/install_deps.sh).
driver="$out/balm_os0_odometry"
"${CXX:-g++}" -O2 -DNDEBUG -std=c++20 -I "$root/include" -I "$root/examples/common" -isystem /usr/include/eigen3 \
  "$root/scripts/balm_os0_odometry.cpp" -o "$driver" -lyaml-cpp
SECONDS=0
"$driver" "$seq" "$yaml" "$out" "${PRESET:-baseline}"
echo "run: $(ls "$seq"/velodyne/*.bin | wc -l) keyframes in ${SECONDS} s, outputs in $out"
# /usr/bin/python3 or any python3: the evaluation needs only the standard library.
python3 "$root/scripts/balm_os0_eval.py" "$seq/poses.txt" "$out/poses.txt" "$out/status.txt" "$out/sensor.txt"
