#!/usr/bin/env bash
# Builds semlio's tests (and, in address mode, the examples the CTest suite
# runs) with GCC's sanitizers and runs CTest on them: memory errors and
# undefined behaviour (default), or data races in the code that runs
# threads.
#
#   scripts/sanitize.sh [address|thread]
#
# address (default): AddressSanitizer + UndefinedBehaviorSanitizer, every
#   test (unit tests, the example binaries' CTest runs and the short script
#   runs); any report fails the test that raised it.
# thread: ThreadSanitizer on the tests that start threads (concurrent const
#   queries of the k-d trees and of the lazy FeatureMap caches, the
#   simulator's workers, the KITTI writer).
#
# Environment: BUILD_DIR (default build-sanitize-<mode>), JOBS (default
# nproc), CTEST_ARGS (extra ctest arguments, e.g. "-R kdtree"). Not part of
# CI (a sanitized build and run take about three times the plain test
# command); run it before a release or after touching buffers, atomics or
# SIMD code.
set -euo pipefail
cd "$(dirname "$0")/.."

MODE=${1:-address}
case "$MODE" in
  address) SANITIZE="address,undefined" ;;
  thread) SANITIZE="thread" ;;
  *) echo "usage: scripts/sanitize.sh [address|thread]" >&2; exit 2 ;;
esac
BUILD_DIR=${BUILD_DIR:-build-sanitize-$MODE}
JOBS=${JOBS:-$(nproc)}

scripts/install_deps.sh
# Benchmarks are left out: they time code, a sanitized build says nothing
# about speed, and the tests cover the same kernels. Warnings stay warnings:
# GCC 12's instrumentation makes -Wmaybe-uninitialized fire inside
# libstdc++'s <regex> (which Catch2 includes); scripts/test.sh is the
# warnings-as-errors build.
# Debug keeps the asserts (ours and Eigen's index checks); -O1 keeps the
# pipelines' tests fast enough.
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Debug -DCMAKE_CXX_FLAGS_DEBUG="-O1 -g" -DSEMLIO_SANITIZE="$SANITIZE" \
  -DSEMLIO_BUILD_BENCHMARKS=OFF -DSEMLIO_WARNINGS_AS_ERRORS=OFF
# Which compiler the build dir holds (the configure step names it only the first time).
echo "sanitize.sh: compiler $(sed -n 's/^CMAKE_CXX_COMPILER:[A-Z]*=//p' "$BUILD_DIR/CMakeCache.txt")" \
  "($("$(sed -n 's/^CMAKE_CXX_COMPILER:[A-Z]*=//p' "$BUILD_DIR/CMakeCache.txt")" --version | head -n 1))"
if [ "$MODE" = address ]; then
  cmake --build "$BUILD_DIR" -j "$JOBS"
  # detect_leaks: a leak is a failure too. halt_on_error: the first report
  # ends the test, so it cannot scroll past unnoticed.
  export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:halt_on_error=1:abort_on_error=1}
  export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
  # shellcheck disable=SC2086
  ctest --test-dir "$BUILD_DIR" -j "$JOBS" --output-on-failure ${CTEST_ARGS:-}
else
  cmake --build "$BUILD_DIR" -j "$JOBS" --target semlio_tests semlio_tests_scalar_kdtree
  export TSAN_OPTIONS=${TSAN_OPTIONS:-halt_on_error=1:second_deadlock_stack=1}
  # The tests that start threads (their names say so: concurrent queries,
  # output independent of the thread count).
  # shellcheck disable=SC2086
  ctest --test-dir "$BUILD_DIR" -j "$JOBS" --output-on-failure \
    -R "${TSAN_TESTS:-concurrent|thread}" ${CTEST_ARGS:-}
fi
