#!/usr/bin/env bash
# Per-frame time of the odometry on one core (issue #5's speed target:
# whole-frame median <= 30 ms on real 120k-point KITTI scans).
#   scripts/frame_time.sh [KITTI_PCD_DIR]
# KITTI_PCD_DIR: a folder of real KITTI scans as PCD (e.g. the 22-frame KITTI
# raw snippet); converted to a KITTI layout with semlio_convert. Always also
# simulates a 300-frame urban drive (heavy traffic, predicted labels).
# For each sequence and preset (baseline, full) it runs, pinned to one core
# (taskset -c ${CORE:-0}):
#   1. semlio_kitti under /usr/bin/time: median / p90 whole-frame wall time and
#      median per stage, keyframes and non-keyframes apart, from report.json,
#      plus the process CPU time;
#   2. bench_frame_time: the same frames with the thread CPU time of each
#      frame (CLOCK_THREAD_CPUTIME_ID) -- on a shared, loaded machine the wall
#      time overstates the cost, the CPU time does not.
# Environment: BUILD_DIR (build), OUT (results/frame_time), FRAMES (300), CORE (0),
# REPEAT (3: passes of bench_frame_time over the frames, pooled into its
# medians: a single pass of 21 frames is a small sample),
# SKIP_BUILD=1 (use BUILD_DIR as built; CI runs a short version this way).
# On the real snippet each preset's summary ends with issue #5's verdict on this CPU.
set -euo pipefail
cd "$(dirname "$0")/.."
PCD_DIR=${1:-}
BUILD_DIR=${BUILD_DIR:-build}
OUT=${OUT:-results/frame_time}
FRAMES=${FRAMES:-300}
CORE=${CORE:-0}
REPEAT=${REPEAT:-3}

scripts/install_deps.sh python3-numpy
if [[ -z "${SKIP_BUILD:-}" ]]; then
  cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release > /dev/null
  cmake --build "$BUILD_DIR" -j 2 --target semlio_convert semlio_kitti semlio_simulate bench_frame_time
fi
BIN="$BUILD_DIR/examples"
BENCH="$BUILD_DIR/bench/bench_frame_time"
mkdir -p "$OUT"

sequences=()
if [[ -n "$PCD_DIR" ]]; then
  rm -rf "$OUT/kitti_raw" && mkdir -p "$OUT/kitti_raw/velodyne"
  mapfile -t files < <(ls "$PCD_DIR"/*.pcd | sort)
  for i in "${!files[@]}"; do
    "$BIN/semlio_convert" "${files[$i]}" "$OUT/kitti_raw/velodyne/$(printf %06d "$i").bin" > /dev/null
  done
  /usr/bin/python3 -c "import sys; [print(f'{0.1*i:.6f}') for i in range(${#files[@]})]" > "$OUT/kitti_raw/times.txt"
  sequences+=("kitti_raw")
fi
if [[ ! -d "$OUT/sim/velodyne" ]]; then
  echo "== simulating a $FRAMES-frame urban drive"
  "$BIN/semlio_simulate" --world urban --traffic heavy --frames "$FRAMES" --seed 1 --out "$OUT/sim" > /dev/null
fi
sequences+=("sim")

echo "== load before the runs: $(cut -d' ' -f1-3 /proc/loadavg) (1/5/15 min) on $(nproc) cores"
# Absolute times depend on the CPU (the same code read 30.6 ms on a 2.3 GHz
# Xeon VM and 20-21 ms on a 2.6 GHz EPYC VM): name it beside every number.
echo "== cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//'), $(grep -m1 'cpu MHz' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//') MHz"
for seq in "${sequences[@]}"; do
  labels=none
  correction=on
  if [[ "$seq" == sim ]]; then labels=predictions; correction=off; fi
  for preset in baseline full; do
    run="$OUT/run_${seq}_${preset}"
    /usr/bin/time -f "%U %S %e" -o "$run.time" taskset -c "$CORE" "$BIN/semlio_kitti" --sequence "$OUT/$seq" \
      --labels "$labels" --preset "$preset" --kitti-correction "$correction" --out "$run" --quiet --overwrite > "$run.log" 2>&1
    taskset -c "$CORE" "$BENCH" --sequence "$OUT/$seq" --preset "$preset" --labels "$labels" --repeat "$REPEAT" > "$run.cpu.txt"
    /usr/bin/python3 - "$seq" "$preset" "$run/report.json" "$run.time" "$run.cpu.txt" <<'PY'
import json, sys
import numpy as np
seq, preset, report, timefile, cpufile = sys.argv[1:6]
frames = json.load(open(report))["frames"]
frames = [f for f in frames if f.get("status") not in ("initialized", "skipped")]
def row(sel, name):
    if not sel:
        return f"  {name:13s} n=  0"
    t = lambda k: np.array([f["timings_ms"][k] for f in sel])
    tot = t("total")
    stages = " ".join(f"{k} {np.median(t(k)):6.2f}" for k in ("preprocess", "segment", "features", "solve", "scan_shapes", "associate", "linearize", "map"))
    return f"  {name:13s} n={len(sel):3d} wall median {np.median(tot):7.2f} p90 {np.percentile(tot, 90):7.2f} ms | median {stages}"
kf = [f for f in frames if f.get("keyframe")]
nkf = [f for f in frames if not f.get("keyframe")]
user, sys_s, wall = map(float, open(timefile).read().split()[-3:])
print(f"== {seq} / {preset}: {len(frames)} tracked frames; semlio_kitti process: CPU {user + sys_s:.1f} s, wall {wall:.1f} s")
print(row(frames, "all frames"))
print(row(kf, "keyframes"))
print(row(nkf, "non-keyframes"))
a = np.loadtxt(cpufile, ndmin=2)
a = a[a[:, 0] != 0]  # frame 0 of each pass initialises the map
if len(a):
    for name, m in (("all frames", np.ones(len(a), bool)), ("keyframes", a[:, 1] == 1), ("non-keyframes", a[:, 1] == 0)):
        if m.any():
            c = a[m, 3]
            print(f"  thread CPU {name:13s} median {np.median(c):7.2f} p90 {np.percentile(c, 90):7.2f} ms "
                  f"(wall of the same run: median {np.median(a[m, 2]):7.2f})")
    if seq == "kitti_raw":
        # Issue #5's bound, judged on the thread CPU time (the wall time of a
        # shared machine overstates it); informational, not an exit status.
        c = np.median(a[:, 3])
        verdict = "holds" if c <= 30.0 else "does NOT hold"
        print(f"  issue #5 (whole-frame median <= 30 ms, real KITTI, one core), {preset}: {c:.2f} ms -> {verdict} on this CPU")
PY
  done
done
echo "== load after the runs: $(cut -d' ' -f1-3 /proc/loadavg)"
