#!/usr/bin/env bash
# Builds and runs the association benchmarks (bench/frontend/bench_association.cpp)
# on real KITTI (kitti_*), simulated urban (sim_*) and synthetic street
# (street_*) inputs and prints, from that one run, the cost ratios the
# front-end issue targets:
#   NormalConsistency / NearestK            (target <= 2.0, stretch <= 1.5)
#   NormalConsistencyReference / NormalConsistency   (target >= 10)
# and, reported beside them, one frame on the odometry's path (NearestCache,
# 5 Gauss-Newton poses) with the map's axes warm and just rebuilt.
# Ratios use CPU time (robust on a shared machine). Extra arguments go to the
# association benchmark binary (e.g. --benchmark_min_time=1). Then runs
# bench_gauss_newton (one Gauss-Newton iteration, residual accumulation and
# search-structure builds on the real KITTI pair; the same extra arguments)
# unless NO_GN=1.
# Environment: BUILD_DIR (default build-bench), JOBS (default 2), SKIP_BUILD=1
# (use BUILD_DIR as built; CI runs a short version this way).
set -euo pipefail
cd "$(dirname "$0")/.."

BUILD_DIR=${BUILD_DIR:-build-bench}
JOBS=${JOBS:-2}
if [[ -z "${SKIP_BUILD:-}" ]]; then
  cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release -DSEMLIO_BUILD_BENCHMARKS=ON >/dev/null
  cmake --build "$BUILD_DIR" -j "$JOBS" --target bench_association bench_gauss_newton >/dev/null
fi

json=$(mktemp)
trap 'rm -f "$json"' EXIT
"$BUILD_DIR/bench/bench_association" --benchmark_out="$json" --benchmark_out_format=json "$@"

python3 - "$json" <<'PY'
import json, sys
# With --benchmark_repetitions the medians are used (also under
# --benchmark_report_aggregates_only), else the single iteration rows.
benchmarks = json.load(open(sys.argv[1]))["benchmarks"]
medians = {b["run_name"]: b for b in benchmarks if b.get("aggregate_name") == "median"}
runs = medians or {b["name"]: b for b in benchmarks if b.get("run_type", "iteration") == "iteration"}
def cpu_ms(name):
    b = runs.get(name)
    if b is None:
        return None
    scale = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}[b["time_unit"]]
    return b["cpu_time"] * scale
print()
print("Association cost ratios (CPU time, " + ("medians of the repetitions" if medians else "one run") + ")")
print(f"{'input':<10}{'scene':<18}{'NearestK ms':>13}{'NormalCons. ms':>16}{'Reference ms':>14}{'NC/NearestK':>13}{'Ref/NC':>9}")
ok = True
rows = 0
scenes = [("real", "kitti_surfaces"), ("real", "kitti_corners"), ("real", "kitti_dense"),
          ("simulated", "sim_surfaces"), ("simulated", "sim_corners"),
          ("synthetic", "street_surfaces"), ("synthetic", "street_corners")]
for kind, scene in scenes:
    nk, nc, ref = (cpu_ms(f"{a}/{scene}") for a in ("NearestK", "NormalConsistency", "NormalConsistencyReference"))
    if nk is None or nc is None:
        continue
    rows += 1
    r1 = nc / nk
    r2 = ref / nc if ref is not None else float("nan")
    ok = ok and r1 <= 2.0 and (ref is None or r2 >= 10.0)
    ref_s = f"{ref:14.2f}" if ref is not None else f"{'-':>14}"
    print(f"{kind:<10}{scene:<18}{nk:13.2f}{nc:16.2f}{ref_s}{r1:13.2f}{r2:9.1f}")
if rows == 0:
    print("no association rows in the benchmark output (filtered out?)")
print("targets: NC/NearestK <= 2.0 (stretch 1.5), Ref/NC >= 10 ->", "met" if ok and rows > 0 else "NOT met")
print()
print("One frame on the odometry's path (set_scan + 5 Gauss-Newton associations with a NearestCache),")
print("map axes warm / map just rebuilt (as after a keyframe); reported, not judged against the targets")
print(f"{'input':<10}{'scene':<18}{'NK warm ms':>12}{'NC warm ms':>12}{'ratio':>8}{'NK cold ms':>12}{'NC cold ms':>12}{'ratio':>8}")
for kind, scene in scenes:
    vals = [cpu_ms(f"{a}/{t}{scene}") for t in ("frame_", "frame_cold_map_") for a in ("NearestK", "NormalConsistency")]
    if any(v is None for v in vals):
        continue
    print(f"{kind:<10}{scene:<18}{vals[0]:12.2f}{vals[1]:12.2f}{vals[1] / vals[0]:8.2f}"
          f"{vals[2]:12.2f}{vals[3]:12.2f}{vals[3] / vals[2]:8.2f}")
ref, fast = cpu_ms("DownsampleLabelled/reference/merged_map"), cpu_ms("DownsampleLabelled/radix/merged_map")
if ref is not None and fast is not None:
    print(f"map rebuild voxel downsampling, merged map input: reference {ref:.1f} ms, radix {fast:.1f} ms, "
          f"speed-up {ref / fast:.2f}x")
PY

if [[ "${NO_GN:-0}" != 1 ]]; then
  echo
  echo "Gauss-Newton iteration, accumulation and search-structure builds (real KITTI pair)"
  "$BUILD_DIR/bench/bench_gauss_newton" "$@"
fi
