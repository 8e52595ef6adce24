#!/usr/bin/env bash
# Is reading ever the bottleneck? Reading + decoding real KITTI scans from a
# ROS 1 bag (lz4 chunks) and an MCAP file (zstd chunks) against the
# odometry's own frame rate on the same CPU core (issue #37's must-hold:
# reading >= 10x the odometry's frame rate on one core).
#
#   scripts/read_speed.sh [KITTI_RAW_DRIVE]
#
# KITTI_RAW_DRIVE: a KITTI raw drive folder as published (e.g. a downloaded
# 2011_09_26_drive_0009_sync, 51 scans), converted to
# the KITTI layout with semlio_convert; without it, the 3-scan drive of
# tests/data (2 tracked frames a pass: a small sample, say so when quoting).
#
# On one core (taskset -c ${CORE:-1}), one process at a time:
#   1. bench_bag_read (BM_Ros1BagReadDecode/1) and bench_mcap_read
#      (BM_McapReadDecode/crc:1): next() -- file read, decompression, copy --
#      then PointCloud2 -> Scan, per scan, over the three real KITTI raw scans
#      of tests/data/bags (about 118 000 points each); and the same scans as
#      rosbag2's MCAP storage writes them with each preset
#      (BM_McapReadDecodeRosbag2/default|zstd_fast|zstd_small);
#   2. bench_frame_time: the odometry's thread CPU time per frame on the real
#      drive (scans read before the clock starts), baseline and full preset,
#      median over the frames after the first of each of REPEAT passes;
#   3. the ratio (scans read per second) / (frames processed per second).
# The verdict is informational: speed targets are not CTest entries.
# Environment: BUILD_DIR (build), OUT (results/read_speed), CORE (1),
# REPEAT (3), SKIP_BUILD=1 (use BUILD_DIR as built), PAGE (a markdown file to
# write the tables to, e.g. docs/read_speed.md), README (a README whose
# <!-- read_speed:begin --> block gets the reading table, e.g. README.md).
set -euo pipefail
cd "$(dirname "$0")/.."
DRIVE=${1:-}
BUILD_DIR=${BUILD_DIR:-build}
OUT=${OUT:-results/read_speed}
CORE=${CORE:-1}
REPEAT=${REPEAT:-3}

scripts/install_deps.sh python3-numpy
if [[ -z "${SKIP_BUILD:-}" ]]; then
  cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release -DSEMLIO_BUILD_BENCHMARKS=ON > /dev/null
  cmake --build "$BUILD_DIR" -j 2 --target semlio_convert bench_frame_time bench_bag_read bench_mcap_read
fi
for b in bench_bag_read bench_mcap_read bench_frame_time; do
  [[ -x "$BUILD_DIR/bench/$b" ]] || { echo "read_speed.sh: $BUILD_DIR/bench/$b missing (the bag benchmarks need libbz2, liblz4, libzstd)" >&2; exit 1; }
done
mkdir -p "$OUT"

if [[ -n "$DRIVE" ]]; then
  drive_name=$(basename "$DRIVE")
else
  DRIVE=$(ls -d tests/data/kitti_raw/*/*_sync | head -n 1)
  drive_name="$(basename "$DRIVE") (the 3 scans of tests/data)"
fi
"$BUILD_DIR/examples/semlio_convert" --input "$DRIVE" --format kitti-raw --out "$OUT/sequence" --overwrite > /dev/null

load_before="load average (1, 5, 15 min) before: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "== cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//'), core $CORE; $load_before on $(nproc) cores"
taskset -c "$CORE" "$BUILD_DIR/bench/bench_bag_read" --benchmark_filter='BM_Ros1BagReadDecode/1$' \
  --benchmark_min_time=2 --benchmark_format=json > "$OUT/bag.json" 2> /dev/null
taskset -c "$CORE" "$BUILD_DIR/bench/bench_mcap_read" --benchmark_filter='BM_McapReadDecode/crc:1$' \
  --benchmark_min_time=2 --benchmark_format=json > "$OUT/mcap.json" 2> /dev/null
for preset in default zstd_fast zstd_small; do
  taskset -c "$CORE" "$BUILD_DIR/bench/bench_mcap_read" --benchmark_filter="BM_McapReadDecodeRosbag2/$preset\$" \
    --benchmark_min_time=2 --benchmark_format=json > "$OUT/mcap_$preset.json" 2> /dev/null
done
for preset in baseline full; do
  taskset -c "$CORE" "$BUILD_DIR/bench/bench_frame_time" --sequence "$OUT/sequence" --preset "$preset" \
    --labels none --repeat "$REPEAT" > "$OUT/frame_time_$preset.txt"
done

cpu="$(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2- | sed 's/^ *//')"
load="$load_before; after: $(cut -d' ' -f1-3 /proc/loadavg) on $(nproc) cores"
/usr/bin/python3 - "$OUT" "$drive_name" "$cpu" "${PAGE:-}" "$load" "${README:-}" << 'EOF'
import json, sys
import numpy as np
out, drive, cpu, page, load, readme = sys.argv[1:7]

def rate(name):  # scans per second (CPU time) of the one benchmark in the file
    b = json.load(open(f"{out}/{name}.json"))["benchmarks"]
    return b[0]["items_per_second"]

reads = [("ROS 1 bag, lz4 chunks (`python3-rosbag`)", rate("bag")),
         ("MCAP, zstd level 3 chunks with CRCs (`@mcap/core`)", rate("mcap")),
         ("MCAP as `ros2 bag record -s mcap` writes it: zstd level 1, chunk CRCs", rate("mcap_default")),
         ("MCAP, rosbag2 preset `zstd_fast`: zstd level -5, no chunk CRCs", rate("mcap_zstd_fast")),
         ("MCAP, rosbag2 preset `zstd_small`: zstd level 19, chunk CRCs", rate("mcap_zstd_small"))]
frames = {}
for preset in ("baseline", "full"):
    a = np.loadtxt(f"{out}/frame_time_{preset}.txt", ndmin=2)
    a = a[a[:, 0] != 0]  # frame 0 of each pass initialises the map
    frames[preset] = (float(np.median(a[:, 3])), len(a))
L = [f"Odometry on `{drive}`, median thread CPU time per frame (frames after the first), one core of {cpu}:", "",
     "| preset | ms per frame | frames/s | frames |", "|---|---|---|---|"]
for preset, (ms, n) in frames.items():
    L.append(f"| {preset} | {ms:.1f} | {1000.0 / ms:.1f} | {n} |")
L += ["", "Reading and decoding the three real KITTI scans of `tests/data/bags` (about 118 000 points each) "
      "into scans, CPU time on the same core, and how many times the odometry's frame rate that is "
      "(reading is never the bottleneck at >= 10x). The first two rows read the committed fixtures, written "
      "by the reference libraries; the rosbag2 rows read the same scans written by semlio's MCAP writer with "
      "the zstd level, chunk size and chunk CRC setting of each rosbag2 MCAP storage preset "
      "(`BM_McapReadDecodeRosbag2` in `bench/io/bench_mcap_read.cpp`):", ""]
R = ["| container | scans/s | ms per scan | x baseline's frame rate | x full's frame rate (default preset) |",
     "|---|---|---|---|---|"]
for name, r in reads:
    ratio = [r * frames[p][0] / 1000.0 for p in ("baseline", "full")]
    cells = [f"{x:.1f}x" + ("" if x >= 10.0 else " (< 10x)") for x in ratio]
    R.append(f"| {name} | {r:.0f} | {1000.0 / r:.2f} | {cells[0]} | {cells[1]} |")
L += R
text = "\n".join(L)
print(text)
if page:
    with open(page, "w") as f:
        f.write("# Reading speed\n\nMade by `scripts/read_speed.sh` (rerun it to check these numbers on your CPU). "
                "Most of an MCAP row's time is libzstd's own decompression (`perf record` on bench_mcap_read), "
                "which no reader can avoid on one core; it takes longer the higher the level the file was written "
                "with, and lz4 and zstd's negative levels decompress several times faster. The benchmarks count CPU "
                "time, so a busy machine moves these numbers less "
                f"than wall times, but it does move them ({load}).\n\n" + text + "\n")
if readme:
    sys.path.insert(0, "scripts")
    from page_util import replace_readme_block
    replace_readme_block(readme, "read_speed", "read_speed.sh", R)
EOF
