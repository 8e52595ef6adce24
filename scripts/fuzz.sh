#!/usr/bin/env bash
# Fuzzes every reader harness of tests/fuzz/ with libFuzzer (clang,
# -fsanitize=fuzzer,address,undefined), one harness at a time (WORKERS
# processes each), and prints the executions and findings per reader.
# Crash inputs are saved into
# tests/fuzz/crashes/<reader>/, where the regular test build replays them
# (tests/fuzz/replay.cmake) -- commit them with the fix.
#
# Usage: scripts/fuzz.sh [SECONDS_PER_HARNESS] [HARNESS ...]
#   SECONDS_PER_HARNESS  -max_total_time of each run (default 60)
#   HARNESS              a subset (default: all the build holds): kitti_bin
#                        kitti_label kitti_calib kitti_times kitti_poses tum
#                        pcd ply oxts g2o ros1_pointcloud2 cdr_pointcloud2
#                        ros1_imu cdr_imu kitti_raw_calib kitti_raw_stamps
#                        scan_folder kitti_raw_drive settings_yaml, and with
#                        the bag libraries (bz2, lz4, zstd, sqlite3) rosbag1
#                        mcap sqlite_bag (SEMLIO_FUZZ_HARNESS=list prints them)
# The must-hold (issue #36): `scripts/fuzz.sh 300` finds nothing and runs
# >= 1 million executions per harness on the 2-core VM (both cores: two
# workers per harness, executions summed).
# Environment: SEMLIO_FUZZ_BUILD_DIR (default ${TMPDIR:-/tmp}/semlio_build_fuzz),
#              JOBS (build parallelism, default 1), WORKERS (fuzzing
#              processes per harness, default nproc), SKIP_BUILD=1 (use the
#              executable already built there, or FUZZ_BIN when set),
#              SUMMARY (a TSV file to write: harness, seconds, workers,
#              executions, exec/s, new findings; scripts/robustness.sh
#              makes docs/robustness.md from it).
# Exit status: 0 when no harness found anything, 1 otherwise.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
seconds=${1:-60}
shift || true
harnesses=("$@")
build=${SEMLIO_FUZZ_BUILD_DIR:-${TMPDIR:-/tmp}/semlio_build_fuzz}
jobs=${JOBS:-1}
workers=${WORKERS:-$(nproc)}

if [ "${SKIP_BUILD:-0}" != 1 ]; then
  # clang 14 and its sanitizer/libFuzzer runtimes (Debian 12).
  "$root/scripts/install_deps.sh" clang-14 libclang-rt-14-dev
  mkdir -p "$build"
  cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
    -DSEMLIO_FUZZ=ON -DSEMLIO_WITH_BAGS=ON -DSEMLIO_BUILD_BENCHMARKS=OFF \
    -DSEMLIO_AREA_TESTS=OFF -DSEMLIO_WARNINGS_AS_ERRORS=OFF >"$build/configure.log" 2>&1 ||
    { cat "$build/configure.log"; exit 2; }
  # One executable holds every harness; SEMLIO_FUZZ_HARNESS selects one per run.
  # The bag harnesses are compiled in when the bag libraries were found.
  cmake --build "$build" -j "$jobs" --target semlio_fuzz
fi
bin=${FUZZ_BIN:-$build/tests/semlio_fuzz}
# Default: every harness this build holds (the executable lists them).
if [ ${#harnesses[@]} -eq 0 ]; then
  mapfile -t harnesses < <(SEMLIO_FUZZ_HARNESS=list "$bin" 2>/dev/null)
  [ ${#harnesses[@]} -gt 0 ] || { echo "fuzz.sh: $bin lists no harness" >&2; exit 2; }
fi

found=0
summary=()
[ -z "${SUMMARY:-}" ] || printf 'harness\tseconds\tworkers\texecutions\texec_per_s\tfindings\n' > "$SUMMARY"
for h in "${harnesses[@]}"; do
  seeds="$root/tests/fuzz/corpus/$h"
  crashes="$root/tests/fuzz/crashes/$h"
  work="$build/corpus/$h"  # new inputs go here, not into the committed seeds
  mkdir -p "$work" "$crashes"
  before=$(find "$crashes" -type f | wc -l)
  echo "== $h: ${seconds} s, $workers worker(s)"
  # Each worker is a libFuzzer process on the same corpus folder (it picks
  # up the others' new inputs as it goes); their executions add up.
  pids=()
  for ((w = 1; w <= workers; ++w)); do
    SEMLIO_FUZZ_HARNESS=$h ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
      "$bin" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
      -max_len=65536 -print_final_stats=1 -artifact_prefix="$crashes/" "$work" "$seeds" \
      >"$build/fuzz_$h.$w.log" 2>&1 &
    pids+=($!)
  done
  rc=0
  for pid in "${pids[@]}"; do wait "$pid" || rc=$?; done
  execs=0
  rate=0
  for ((w = 1; w <= workers; ++w)); do
    log="$build/fuzz_$h.$w.log"
    e=$(grep -o 'stat::number_of_executed_units: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1)
    r=$(grep -o 'exec/s: *[0-9]*' "$log" | grep -o '[0-9]*$' | tail -1)
    execs=$((execs + ${e:-0}))
    rate=$((rate + ${r:-0}))
  done
  after=$(find "$crashes" -type f | wc -l)
  new=$((after - before))
  if [ "$rc" -ne 0 ] || [ "$new" -gt 0 ]; then
    found=1
    echo "   FINDING (exit $rc, $new new file(s) in tests/fuzz/crashes/$h); logs: $build/fuzz_$h.*.log"
    cat "$build"/fuzz_"$h".*.log | grep -m3 -E 'ERROR: |runtime error|SUMMARY' | sed 's/^/   /' || true
  fi
  summary+=("$(printf '%-18s %10s execs %8s exec/s %4s findings' "$h" "${execs:-?}" "${rate:-?}" "$new")")
  [ -z "${SUMMARY:-}" ] || printf '%s\t%s\t%s\t%s\t%s\t%s\n' "$h" "$seconds" "$workers" "$execs" "$rate" "$new" >> "$SUMMARY"
done
echo
echo "fuzz.sh: ${seconds} s per harness, $workers worker(s) each"
printf '%s\n' "${summary[@]}"
exit "$found"
