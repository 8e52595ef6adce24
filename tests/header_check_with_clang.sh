#!/bin/sh
# Compiler launcher of semlio_header_check (tests/CMakeLists.txt): runs the
# compile command CMake hands over ($2 = the build compiler, then its
# arguments) through clang ($1) with -fsyntax-only, then creates the object
# file the build rule expects; the OBJECT library is never linked. clang
# writes the dependency file (-MD -MF) as the build compiler would, so a
# changed header re-checks exactly the headers that include it.
set -eu
clang=$1
shift 2
out=""
prev=""
for arg in "$@"; do
  if [ "$prev" = "-o" ]; then out=$arg; fi
  prev=$arg
done
"$clang" -fsyntax-only "$@"
: > "$out"
