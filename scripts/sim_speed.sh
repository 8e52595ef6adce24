#!/usr/bin/env bash
# Measures semlio_simulate's speed: builds it (Release) and times one drive.
#
#   scripts/sim_speed.sh [FRAMES] [extra semlio_simulate arguments...]
#
# Environment: BUILD_DIR (default /tmp/semlio-build-sim-speed), OUT_DIR
# (default /tmp/semlio-sim-speed-out, removed and rewritten), JOBS (build
# parallelism, default 2), WORLD (default urban).
# Prints wall time, user+sys CPU time, frames/s and points/frame. The speed
# target: a 1000-frame urban drive (~120k points/frame) in <= 180 s on the
# 2-core reference machine.
set -euo pipefail

FRAMES="${1:-1000}"
shift || true
SRC_DIR="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BUILD_DIR="${BUILD_DIR:-/tmp/semlio-build-sim-speed}"
OUT_DIR="${OUT_DIR:-/tmp/semlio-sim-speed-out}"
JOBS="${JOBS:-2}"
WORLD="${WORLD:-urban}"

cmake -S "$SRC_DIR" -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$BUILD_DIR" -j"$JOBS" --target semlio_simulate >/dev/null
BIN="$(find "$BUILD_DIR" -type f -name semlio_simulate -perm -u+x | head -n 1)"
[ -n "$BIN" ] || { echo "semlio_simulate not found under $BUILD_DIR" >&2; exit 1; }

rm -rf "$OUT_DIR"
TIMES="$(mktemp)"
LOG="$(mktemp)"
trap 'rm -f "$TIMES" "$LOG"' EXIT
# GNU time when available (peak memory too); bash's own timer otherwise.
if [ -x /usr/bin/time ]; then
  /usr/bin/time -f "%e %U %S %M" -o "$TIMES" "$BIN" --world "$WORLD" --frames "$FRAMES" --out "$OUT_DIR" "$@" >"$LOG"
  read -r WALL USER SYS MAXRSS <"$TIMES"
else
  TIMEFORMAT="%R %U %S"
  { time "$BIN" --world "$WORLD" --frames "$FRAMES" --out "$OUT_DIR" "$@" >"$LOG"; } 2>"$TIMES"
  read -r WALL USER SYS <"$TIMES"
  MAXRSS="n/a"
fi
cat "$LOG"
POINTS="$(sed -n 's/^wrote \([0-9]*\) frames (\([0-9]*\) points.*/\2/p' "$LOG")"
awk -v f="$FRAMES" -v w="$WALL" -v u="$USER" -v s="$SYS" -v p="${POINTS:-0}" -v m="$MAXRSS" 'BEGIN {
  cpu = u + s;
  printf "frames           %d\n", f;
  printf "wall time        %.1f s\n", w;
  printf "CPU time         %.1f s (user %.1f + sys %.1f)\n", cpu, u, s;
  printf "frames/s (wall)  %.2f\n", f / w;
  printf "frames/s (CPU)   %.2f\n", f / cpu;
  printf "points/frame     %.0f\n", p / f;
  printf "peak RSS         %s kB\n", m;
  # Setup (world, traffic, label calibration) is a fixed cost: only a
  # 1000-frame run measures the target directly.
  if (f == 1000) printf "target <= 180 s for 1000 frames on 2 unloaded cores: CPU/2 = %.0f s -> %s\n", cpu / 2, (cpu / 2 <= 180 ? "met" : "NOT met");
}'
