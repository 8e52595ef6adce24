#!/usr/bin/env bash
# Builds semlio with warnings as errors (GCC) and runs the whole test suite.
# This is the README's test command and what .ci/run calls.
set -euo pipefail
cd "$(dirname "$0")/.."

# clang++ runs the header checks (tests/CMakeLists.txt): its front end is
# about four times faster than GCC's there, and CI sees both compilers' warnings.
scripts/install_deps.sh clang
BUILD_DIR=${BUILD_DIR:-build}
JOBS=${JOBS:-$(nproc)}
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release -DSEMLIO_WARNINGS_AS_ERRORS=ON
cmake --build "$BUILD_DIR" -j "$JOBS"
ctest --test-dir "$BUILD_DIR" -j "$JOBS" --output-on-failure
