#!/usr/bin/env bash
# The bad-input must-holds (issue #36) in one command: libFuzzer on every
# reader harness (scripts/fuzz.sh), then the whole test suite under
# AddressSanitizer + UndefinedBehaviorSanitizer (scripts/sanitize.sh address:
# unit tests, fuzz corpus replay, the bad-input catalogue, the tools' and
# scripts' CTest runs), and docs/robustness.md plus README's robustness
# block from what they printed.
#
#   scripts/robustness.sh [SECONDS_PER_HARNESS]   (default 300: the must-hold)
#
# With INTERRUPT_SCANS=DIR (real scans, e.g. the 22-scan KITTI raw snippet of
# the shared data) it also runs scripts/interrupt_check.sh DIR 10 with the
# tools of TOOLS_BUILD_DIR (build): SIGINT after 10 frames leaves complete
# outputs for those frames, and OUT is guarded.
#
# Takes hours on a 2-core machine (the fuzzing: 23 harnesses x SECONDS; the
# sanitized build and suite); not part of CI. Either half can be reused:
#   FUZZ_SUMMARY=FILE   a SUMMARY TSV of an earlier scripts/fuzz.sh run (no fuzzing)
#   INTERRUPT_LOG=FILE  the output of an earlier scripts/interrupt_check.sh run
#   SANITIZE_LOG=FILE   the output of an earlier scripts/sanitize.sh address run
#                       (BUILD_DIR: its build folder, which names the compiler)
# Environment: OUT (results/robustness), PAGE (docs/robustness.md), README
# (README.md; - leaves it alone), and what fuzz.sh and sanitize.sh read
# (WORKERS, JOBS, BUILD_DIR, CC/CXX, ...).
set -euo pipefail
cd "$(dirname "$0")/.."
SECONDS_PER_HARNESS=${1:-300}
OUT=${OUT:-results/robustness}
PAGE=${PAGE:-docs/robustness.md}
README=${README:-README.md}
mkdir -p "$OUT"

fuzz_summary=${FUZZ_SUMMARY:-}
if [[ -z "$fuzz_summary" ]]; then
  fuzz_summary="$OUT/fuzz.tsv"
  # fuzz.sh exits 1 on a finding: the page reports it, so keep going.
  SUMMARY="$fuzz_summary" scripts/fuzz.sh "$SECONDS_PER_HARNESS" | tee "$OUT/fuzz.log" || true
fi
sanitize_log=${SANITIZE_LOG:-}
sanitize_build=${BUILD_DIR:-build-sanitize-address}
if [[ -z "$sanitize_log" ]]; then
  sanitize_log="$OUT/sanitize.log"
  # clang by default: its front end builds the sanitized suite several times
  # faster than GCC's (the pipelines' headers), and fuzz.sh installed it.
  CC=${CC:-clang} CXX=${CXX:-clang++} BUILD_DIR=$sanitize_build scripts/sanitize.sh address > "$sanitize_log" 2>&1 || true
  tail -n 5 "$sanitize_log"
fi
interrupt_log=${INTERRUPT_LOG:-}
if [[ -z "$interrupt_log" && -n "${INTERRUPT_SCANS:-}" ]]; then
  interrupt_log="$OUT/interrupt.log"
  BUILD_DIR=${TOOLS_BUILD_DIR:-build} OUT="$OUT/interrupt" scripts/interrupt_check.sh "$INTERRUPT_SCANS" 10 \
    | tee "$interrupt_log" || true
fi
/usr/bin/python3 scripts/robustness_page.py ${interrupt_log:+--interrupt "$interrupt_log"} --fuzz "$fuzz_summary" --sanitize "$sanitize_log" \
  --sanitize-build "$sanitize_build" --page "$PAGE" --readme "$README"
echo "robustness.sh: wrote $PAGE"
