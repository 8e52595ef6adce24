#!/usr/bin/env bash
# Must-hold check of the back end (issue 6): on a long simulated drive the
# memory stays bounded (peak RSS printed; the places' data within its ceiling,
# slam.max_place_bytes; the keyframe store and resident set sampled every 250
# frames) and the per-frame time of the last 500 frames is less than 10 %
# above that of the first 500, loop-closure frames (a verification or a full
# graph solve ran) excluded.
#   scripts/long_run.sh             # 5000 frames
#   FRAMES=600 scripts/long_run.sh  # a short version (windows of FRAMES/5)
# Environment: FRAMES (5000), SEED (2), TRAFFIC (light), LABELS (labels),
# PRESET (full), LOOP (on), WINDOW (500, at most FRAMES/5), BUILD_DIR (build),
# OUT (results/long_run_<FRAMES>_<SEED>), DRIVE (reuse a simulated drive),
# KEEP_SCANS=1 (keep DRIVE/velodyne), SKIP_BUILD=1, REPORT=path/report.json
# (only analyse an existing semlio_kitti report, e.g. of loop_accuracy.sh).
# REPORT_ONLY=1: print every check but exit 0 whatever their verdict (CI's
# short runs, too short to decide them; a failing run still fails).
set -euo pipefail
cd "$(dirname "$0")/.."
FRAMES=${FRAMES:-5000}
SEED=${SEED:-2}
TRAFFIC=${TRAFFIC:-light}
LABELS=${LABELS:-labels}
PRESET=${PRESET:-full}
LOOP=${LOOP:-on}
WINDOW=${WINDOW:-500}
BUILD_DIR=${BUILD_DIR:-build}
OUT=${OUT:-results/long_run_${FRAMES}_${SEED}}
DRIVE=${DRIVE:-$OUT/drive}

REPORT=${REPORT:-}
RAN_DRIVE=
if [ -z "$REPORT" ]; then
  RAN_DRIVE=1
  if [ -z "${SKIP_BUILD:-}" ]; then
    cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release > /dev/null
    cmake --build "$BUILD_DIR" -j "$(nproc)" --target semlio_simulate semlio_kitti
  fi
  if [ ! -f "$DRIVE/sim.json" ] || [ ! -d "$DRIVE/velodyne" ]; then
    "$BUILD_DIR/examples/semlio_simulate" --world urban --traffic "$TRAFFIC" --frames "$FRAMES" --seed "$SEED" \
      --out "$DRIVE"
  fi
  "$BUILD_DIR/examples/semlio_kitti" --sequence "$DRIVE" --labels "$LABELS" --preset "$PRESET" --loop "$LOOP" \
    --out "$OUT/run" --quiet --overwrite
  REPORT=$OUT/run/report.json
fi

status=0
/usr/bin/python3 - "$REPORT" "$WINDOW" <<'PY' || status=$?
import json, os, statistics, sys
r = json.load(open(sys.argv[1]))
frames = r["frames"]
n = len(frames)
w = min(int(sys.argv[2]), n // 5)
# Thread CPU time when the report has it: wall time on a shared machine moves
# with the load of other processes between the first and the last window.
key = "cpu_ms" if frames and "cpu_ms" in frames[0] else "total_ms"
def window(fs):
    kept = [f[key] for f in fs
            if f["status"] != "skipped" and not f.get("loop_checked") and not f.get("loop_closed")]
    return kept, len(fs) - len(kept)
first, ex_first = window(frames[:w])
last, ex_last = window(frames[-w:])
def backend(fs):
    kept = [f["backend_ms"] for f in fs
            if f["status"] != "skipped" and not f.get("loop_checked") and not f.get("loop_closed")]
    return statistics.fmean(kept) if kept else 0.0
mem = r.get("memory", {})
loop = r.get("loop", {})
print(f"== {n} frames, {r['keyframe_count']} keyframes, loops accepted {loop.get('accepted', 0)} "
      f"of {loop.get('verified', 0)} verified")
print(f"== memory: peak RSS {mem.get('peak_rss_mb', 0):.0f} MB ({mem.get('peak_rss_before_map_mb', 0):.0f} MB before "
      f"the semantic map, whose build took {mem.get('map_build_mb', 0):.0f} MB); keyframe store "
      f"{mem.get('keyframe_store_mb', 0):.1f} MB ({mem.get('keyframe_store_bytes_per_keyframe', 0) / 1024:.0f} kB per keyframe)")
ceiling = mem.get("place_ceiling_mb", 0.0)
place_ok = True
if "places" in mem:
    print(f"== places: {mem['places']} at {mem['place_spacing_m']:.1f} m spacing after {mem['place_thinnings']} thinnings, "
          f"{mem['archived_keyframes']} keyframes archived; place data {mem['place_store_mb']:.1f} MB "
          f"(ceiling {ceiling:.0f} MB{'' if ceiling > 0 else ': none'})")
    trace = mem.get("trace", [])
    if trace:
        print("== keyframe store / place data / RSS / live heap by frame: " +
              ", ".join(f"{t['frames']}: {t['keyframe_store_mb']:.0f}/{t['place_store_mb']:.0f}/{t['rss_mb']:.0f}/"
                        f"{t.get('heap_live_mb', 0):.0f}" for t in trace) + " MB")
        if ceiling > 0:
            place_ok = all(t["place_store_mb"] <= ceiling + 1e-9 for t in trace)
    print(f"== place data within its ceiling at every sample: {'PASS' if place_ok else 'FAIL'}"
          if ceiling > 0 else "== no place ceiling configured: memory grows with the distinct road driven")
m1, m2 = statistics.median(first), statistics.median(last)
a1, a2 = statistics.fmean(first), statistics.fmean(last)
growth = (m2 - m1) / m1 * 100.0
print(f"== per-frame time measured as {'thread CPU time' if key == 'cpu_ms' else 'wall time'}")
print(f"== per-frame time, first {w} frames: median {m1:.1f} ms, mean {a1:.1f} ms ({ex_first} loop frames excluded)")
print(f"== per-frame time, last {w} frames:  median {m2:.1f} ms, mean {a2:.1f} ms ({ex_last} loop frames excluded)")
print(f"== of which back end (keyframe cloud, loop detection, graph window update): mean {backend(frames[:w]):.2f} ms "
      f"-> {backend(frames[-w:]):.2f} ms")
print(f"== growth of the median {growth:+.1f} % (mean {(a2 - a1) / a1 * 100.0:+.1f} %; must be < 10 %): "
      f"{'PASS' if growth < 10.0 else 'FAIL'}")
if "evaluation" in r:
    ev = r["evaluation"]
    print(f"== ATE RMSE {ev['ate_all_frames']['rmse_m']:.3f} m (odometry only {ev['ate_all_frames_odometry']['rmse_m']:.3f} m)")
sys.exit(0 if (growth < 10.0 and place_ok) or os.environ.get("REPORT_ONLY") else 1)
PY
# Only a drive this invocation ran on is cleaned up (REPORT= only analyses).
if [ -n "$RAN_DRIVE" ] && [ -z "${KEEP_SCANS:-}" ] && [ "$DRIVE" = "$OUT/drive" ] && [ -d "$DRIVE" ]; then
  rm -rf "$DRIVE/velodyne"
fi
exit $status
