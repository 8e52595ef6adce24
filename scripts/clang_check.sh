#!/usr/bin/env bash
# Builds everything with clang (Release, warnings as errors) and runs the
# whole CTest suite on it, then checks that the simulator writes the same
# drives under clang as under GCC.
#
#   scripts/clang_check.sh
#
# Why: robot stacks build with either compiler, and GCC alone forgives
# things the standard leaves open. Clang 14 found three: aggregate CTAD
# (`LoamResiduals{corner, surface}` needs a deduction guide before clang
# 17), lambdas capturing structured bindings (clang 16+), and two real bugs
# -- the pose graph read a prior factor's unwritten Jacobian, and the
# simulator's worlds depended on the order in which a call's arguments are
# evaluated (unspecified: GCC goes right to left, clang left to right).
#
# Environment: CXX_CLANG (default clang++), BUILD_DIR (default build-clang),
# GCC_BUILD_DIR (default build: the GCC build whose semlio_simulate the drives
# are compared with; configured with g++ when missing, and semlio_simulate
# brought up to date either way), JOBS (default nproc). Not part of
# CI: Debian 12 does not install clang by default, and a second full build
# would double CI's time. Installs clang when it is missing.
set -euo pipefail
cd "$(dirname "$0")/.."

CXX_CLANG=${CXX_CLANG:-clang++}
BUILD_DIR=${BUILD_DIR:-build-clang}
GCC_BUILD_DIR=${GCC_BUILD_DIR:-build}
JOBS=${JOBS:-$(nproc)}

scripts/install_deps.sh
if ! command -v "$CXX_CLANG" > /dev/null; then scripts/install_deps.sh clang; fi

cmake -S . -B "$BUILD_DIR" -DCMAKE_CXX_COMPILER="$CXX_CLANG" -DCMAKE_BUILD_TYPE=Release \
  -DSEMLIO_WARNINGS_AS_ERRORS=ON
cmake --build "$BUILD_DIR" -j "$JOBS"
ctest --test-dir "$BUILD_DIR" -j "$JOBS" --output-on-failure

# The same drives from both compilers (every world, traffic, distortion, a
# revisit): byte for byte.
if [ ! -f "$GCC_BUILD_DIR/CMakeCache.txt" ]; then
  cmake -S . -B "$GCC_BUILD_DIR" -DCMAKE_CXX_COMPILER=g++ -DCMAKE_BUILD_TYPE=Release
fi
cmake --build "$GCC_BUILD_DIR" -j "$JOBS" --target semlio_simulate
GCC_SIM="$GCC_BUILD_DIR/examples/semlio_simulate"
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
status=0
for args in "--world urban --frames 3 --distortion on" "--world urban --traffic heavy --frames 3" \
            "--world rural --frames 3" "--world highway --traffic heavy --frames 3" \
            "--world aliased --frames 3" "--world urban --traffic none --frames 120 --revisit"; do
  # shellcheck disable=SC2086
  "$GCC_SIM" $args --out "$TMP/gcc" > /dev/null
  # shellcheck disable=SC2086
  "$BUILD_DIR/examples/semlio_simulate" $args --out "$TMP/clang" > /dev/null
  if diff -rq "$TMP/gcc" "$TMP/clang" > /dev/null; then
    echo "same drive from GCC and clang: $args"
  else
    echo "DIFFERENT drives from GCC and clang: $args"
    status=1
  fi
  rm -rf "$TMP/gcc" "$TMP/clang"
done
exit $status
