#!/usr/bin/env bash
# Conformance of semlio's bag writers (include/semlio/io/bag/rosbag1_writer.hpp,
# mcap_writer.hpp) against the reference readers: simulates short drives with
# semlio_simulate --bag/--mcap and checks
#   - the ROS 1 bag with Debian's python3-rosbag (/usr/bin/python3): topics,
#     types, md5sums, message definitions (re-hashed with genpy), stamps, and
#     every message against the KITTI-layout drive of the same run
#     (scripts/check_sim_bags_rosbag.py);
#   - the MCAP file with npm's @mcap/core (McapIndexedReader and
#     McapStreamReader, CRCs validated) and @foxglove/cdr, the same way
#     (scripts/check_sim_bags_mcap.cjs).
# Cases: VLP-16 (Velodyne layout, ring+time, zstd), OS1-64 (Ouster layout,
# ring+time), OS0-128 without ring/time and uncompressed MCAP, VLP-32C with
# time only, HDL-64E (KITTI's default). Exits 1 on any mismatch.
#
#   scripts/check_sim_bags.sh [FRAMES]      (default 12 frames per case)
#
# Environment: BUILD_DIR (default build; semlio_simulate is built there unless
# SKIP_BUILD=1), OUT (scratch dir, default a mktemp dir, removed at exit),
# NODE_DIR (a folder whose node_modules holds @mcap/core, @foxglove/cdr and
# @foxglove/wasm-zstd; default scripts/fixtures, installed there with `npm ci`
# from its package.json when missing).
set -euo pipefail
cd "$(dirname "$0")/.."
FRAMES=${1:-12}
BUILD_DIR=${BUILD_DIR:-build}
NODE_DIR=${NODE_DIR:-scripts/fixtures}

if [ -z "${SKIP_BUILD:-}" ]; then
  cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release > /dev/null
  cmake --build "$BUILD_DIR" -j "$(nproc)" --target semlio_simulate > /dev/null
fi
SIM="$BUILD_DIR/examples/semlio_simulate"
[ -x "$SIM" ] || { echo "check_sim_bags: $SIM not found (set BUILD_DIR)" >&2; exit 1; }
# The reference readers: Debian's rosbag (installed here when missing) and
# Node.js (nodejs from NodeSource or Debian ships npm with it).
/usr/bin/python3 -c "import rosbag, genpy, sensor_msgs.msg, numpy" 2>/dev/null ||
  scripts/install_deps.sh python3-rosbag python3-genpy python3-sensor-msgs python3-numpy
command -v node > /dev/null || scripts/install_deps.sh nodejs npm
if [ ! -d "$NODE_DIR/node_modules/@mcap/core" ] || [ ! -d "$NODE_DIR/node_modules/@foxglove/cdr" ] ||
   [ ! -d "$NODE_DIR/node_modules/@foxglove/wasm-zstd" ]; then
  [ -f "$NODE_DIR/package.json" ] || { echo "check_sim_bags: no $NODE_DIR/package.json to install the MCAP readers from" >&2; exit 1; }
  (cd "$NODE_DIR" && npm ci --no-audit --no-fund > /dev/null)
fi

if [ -z "${OUT:-}" ]; then
  OUT=$(mktemp -d /tmp/semlio-check-sim-bags.XXXXXX)
  trap 'rm -rf "$OUT"' EXIT
fi
mkdir -p "$OUT"

status=0
run_case() {  # NAME SENSOR FIELDS [extra semlio_simulate args...]
  local name=$1 sensor=$2 fields=$3
  shift 3
  local dir="$OUT/$name"
  rm -rf "$dir"
  mkdir -p "$dir"
  "$SIM" --sensor "$sensor" --world urban --traffic heavy --frames "$FRAMES" --seed 3 --threads 2 \
    --out "$dir/drive" --bag "$dir/drive.bag" --mcap "$dir/drive.mcap" --fields "$fields" "$@" > "$dir/sim.log" 2>&1 ||
    { echo "FAIL $name: semlio_simulate failed:"; cat "$dir/sim.log"; status=1; return; }
  echo "== $name ($sensor, fields $fields $*)"
  /usr/bin/python3 scripts/check_sim_bags_rosbag.py "$dir/drive.bag" "$dir/drive" "$sensor" "$fields" || status=1
  node scripts/check_sim_bags_mcap.cjs "$dir/drive.mcap" "$dir/drive" "$sensor" "$fields" "$NODE_DIR" || status=1
}
run_case vlp16 vlp16 ring,time
run_case os1-64 os1-64 ring,time
run_case os0-128_bare os0-128 none --mcap-compression none
run_case vlp32c_time vlp32c time
run_case hdl64e hdl64e ring,time --distortion on
if [ "$status" -ne 0 ]; then
  echo "check_sim_bags: FAILED"
  exit 1
fi
echo "check_sim_bags: all cases passed"
