#!/usr/bin/env bash
# Lidar-inertial with loops vs without (issue 7, step 9 of METHOD.md; not CI):
# a simulated urban drive that revisits its streets, with distortion, run
# through semlio_kitti --imu oxts (IMU deskew) twice:
#   --loop on : the LIO feeds the keyframe graph with velocity/bias states,
#               IMU factors between keyframes and loop closures (poses.txt);
#               poses_odom.txt of the same run is the LIO's own trajectory;
#   --loop off: the LIO alone.
# Optionally (LIDAR=1) lidar-only --loop on on the same drive, for reference.
#   scripts/lio_loop_accuracy.sh                 # 600 frames, seed 1
#   FRAMES=900 SEED=2 scripts/lio_loop_accuracy.sh
#   FRAMES=1000 TRAFFIC=heavy scripts/lio_loop_accuracy.sh   # a harder drive
# Environment: FRAMES (600), SEED (1), WORLD (urban), TRAFFIC (light),
# PRESET (full), LABELS (labels),
# BUILD_DIR (build), OUT (results/lio_loop[_<WORLD>][_<TRAFFIC>]_<FRAMES>_<SEED>,
# the parts in brackets when not the default), DRIVE (reuse a
# simulated drive), SKIP_BUILD=1 (use BUILD_DIR as built), KEEP_SCANS=1,
# IMU_SCALE (the keyframe graph's imu_information_scale; unset: SlamConfig's
# default), LIDAR_SCALE (slam.inertial_lidar_information_scale, the lidar
# information's scale in the keyframe graph; unset: the default) and
# GRAVITY_GAUGE (true|false: the graph's 4-DoF gauge, i.e. it
# estimates the gravity direction; unset: the default), all passed to the
# --loop on run as YAML keys slam.imu_information_scale /
# slam.inertial_lidar_information_scale / slam.inertial_gravity_gauge
# (OUT/lio_loop_on.yaml). The weighting before issue 7's last point:
# IMU_SCALE=1e-6 LIDAR_SCALE=1. REUSE_OFF=1 keeps an
# existing OUT/lio_loop_off (the --loop off run does not depend on them).
#   IMU_SCALE=1e-6 GRAVITY_GAUGE=false SKIP_BUILD=1 BUILD_DIR=build-lio \
#     DRIVE=/tmp/drive KEEP_SCANS=1 OUT=/tmp/out_1e-6_6dof scripts/lio_loop_accuracy.sh
# Prints the ATE of every run; the numbers are reported, not judged.
set -euo pipefail
cd "$(dirname "$0")/.."
FRAMES=${FRAMES:-600}
SEED=${SEED:-1}
WORLD=${WORLD:-urban}
TRAFFIC=${TRAFFIC:-light}
PRESET=${PRESET:-full}
LABELS=${LABELS:-labels}
BUILD_DIR=${BUILD_DIR:-build}
TAG=""
if [ "$WORLD" != urban ]; then TAG="${TAG}_$WORLD"; fi
if [ "$TRAFFIC" != light ]; then TAG="${TAG}_$TRAFFIC"; fi
OUT=${OUT:-results/lio_loop${TAG}_${FRAMES}_${SEED}}
DRIVE=${DRIVE:-$OUT/drive}

if [ -z "${SKIP_BUILD:-}" ]; then
  cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release > /dev/null
  cmake --build "$BUILD_DIR" -j "$(nproc)" --target semlio_simulate semlio_kitti
fi
if [ ! -f "$DRIVE/sim.json" ] || [ ! -d "$DRIVE/velodyne" ]; then
  "$BUILD_DIR/examples/semlio_simulate" --world "$WORLD" --traffic "$TRAFFIC" --frames "$FRAMES" --seed "$SEED" --revisit \
    --distortion on --out "$DRIVE"
fi

# The detectors' default loop time gap (30 s): FRAMES >= 600 lets the
# revisit drive's return to its start (its last seconds) close a loop.
mkdir -p "$OUT"
run() {  # run NAME ARGS...
  local name=$1
  shift
  "$BUILD_DIR/examples/semlio_kitti" --sequence "$DRIVE" --labels "$LABELS" --preset "$PRESET" \
    --out "$OUT/$name" --quiet "$@"
}
LOOP_ON_CONFIG=()
rm -f "$OUT/lio_loop_on.yaml"  # a stale one would be reported as this run's settings
if [ -n "${IMU_SCALE:-}" ] || [ -n "${LIDAR_SCALE:-}" ] || [ -n "${GRAVITY_GAUGE:-}" ]; then
  {
    echo "slam:"
    if [ -n "${IMU_SCALE:-}" ]; then echo "  imu_information_scale: $IMU_SCALE"; fi
    if [ -n "${LIDAR_SCALE:-}" ]; then echo "  inertial_lidar_information_scale: $LIDAR_SCALE"; fi
    if [ -n "${GRAVITY_GAUGE:-}" ]; then echo "  inertial_gravity_gauge: $GRAVITY_GAUGE"; fi
  } > "$OUT/lio_loop_on.yaml"
  LOOP_ON_CONFIG=(--config "$OUT/lio_loop_on.yaml")
fi
run lio_loop_on --imu oxts --deskew on --loop on "${LOOP_ON_CONFIG[@]}"
if [ -z "${REUSE_OFF:-}" ] || [ ! -f "$OUT/lio_loop_off/report.json" ]; then
  run lio_loop_off --imu oxts --deskew on --loop off
fi
if [ -n "${LIDAR:-}" ]; then run lidar_loop_on --imu none --deskew on --loop on; fi

/usr/bin/python3 - "$OUT" <<'PY'
import json, os, sys
out = sys.argv[1]
def rep(name):
    with open(f"{out}/{name}/report.json") as f:
        return json.load(f)
on, off = rep("lio_loop_on"), rep("lio_loop_off")
ev = on["evaluation"]
a_on = ev["ate_all_frames"]["rmse_m"]
a_odom = ev["ate_all_frames_odometry"]["rmse_m"]
a_off = off["evaluation"]["ate_all_frames"]["rmse_m"]
loop, imu = on["loop"], on.get("imu", {})
print(f"== drive: {on['last_frame'] - on['first_frame'] + 1} frames, revisit, distortion on; LIO initialised at frame "
      f"{imu.get('initialized_at_frame', -1)}, IMU fallbacks {imu.get('fallback_frames', 0)}")
print(f"== loops: {loop['accepted']} accepted, {loop['verified']} verified, {loop['candidates']} candidates; "
      f"graph {loop['graph']['nodes']} nodes, {loop['graph']['factors']} factors, "
      f"{imu.get('graph_imu_factors', 0)} IMU factors; full solves {loop['graph']['full_solve_ms_total']:.0f} ms in total")
print(f"== ATE RMSE (all frames) lidar-inertial, --loop off:                  {a_off:.3f} m")
print(f"== ATE RMSE (all frames) lidar-inertial odometry of the --loop on run: {a_odom:.3f} m")
print(f"== ATE RMSE (all frames) lidar-inertial + keyframe graph + loops:      {a_on:.3f} m")
print(f"== ratio loops / no loops: {a_on / a_off if a_off > 0 else float('nan'):.3f}")
cfg = f"{out}/lio_loop_on.yaml"
print("== --loop on settings: " + (open(cfg).read().replace("\n", " ").strip() if os.path.exists(cfg) else "defaults"))
if os.path.exists(f"{out}/lidar_loop_on/report.json"):
    li = rep("lidar_loop_on")["evaluation"]
    print(f"== lidar-only (CV deskew) --loop on: {li['ate_all_frames']['rmse_m']:.3f} m, "
          f"odometry {li['ate_all_frames_odometry']['rmse_m']:.3f} m")
PY
if [ -z "${KEEP_SCANS:-}" ] && [ "$DRIVE" = "$OUT/drive" ]; then rm -rf "$DRIVE/velodyne"; fi
