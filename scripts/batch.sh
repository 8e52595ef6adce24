#!/usr/bin/env bash
# The odometry over many inputs, one process per input with GNU parallel, and
# one table of every report.json (CSV and Markdown).
#
#   scripts/batch.sh LIST_OR_GLOB [-- TOOL_OPTIONS...]
#
# LIST_OR_GLOB: a file with one input path per line (blank lines and lines
# starting with # ignored), or a quoted glob such as 'data/drives/*'.
# TOOL_OPTIONS go to every run unchanged (e.g. -- --preset baseline --labels none).
# The tool is BUILD_DIR/examples/semlio_run (--input PATH) when it is built,
# else semlio_kitti (--sequence PATH: KITTI-layout inputs only); TOOL=PATH
# picks another binary of either kind.
#
# Writes OUT/runs/NNN_NAME/ (the tool's outputs; log.txt its terminal
# output), OUT/joblog.tsv (GNU parallel's: exit code and run time per input),
# OUT/summary.csv and OUT/summary.md (scripts/batch_table.py). Exits 1 when
# any run failed (its row says so), after writing the table.
# Environment: BUILD_DIR (build), OUT (results/batch), JOBS (nproc), TOOL,
# SKIP_BUILD=1 (use BUILD_DIR as built, install nothing).
# The same as a Slurm job array: docs/batch.md.
set -euo pipefail
cd "$(dirname "$0")/.."

usage() { sed -n '2,21p' "$0"; }
[[ $# -ge 1 ]] || { usage >&2; exit 2; }
[[ "$1" == -h || "$1" == --help ]] && { usage; exit 0; }
SPEC=$1
shift
if [[ $# -gt 0 ]]; then
  [[ "$1" == -- ]] || { echo "batch.sh: tool options go after --, got '$1'" >&2; exit 2; }
  shift
fi
TOOL_OPTS=("$@")
BUILD_DIR=${BUILD_DIR:-build}
OUT=${OUT:-results/batch}
JOBS=${JOBS:-$(nproc)}

if [[ -z "${SKIP_BUILD:-}" ]]; then
  scripts/install_deps.sh
  cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release > /dev/null
  # semlio_run where the tree has it, semlio_kitti always.
  cmake --build "$BUILD_DIR" -j "$(nproc)" --target semlio_run 2> /dev/null ||
    cmake --build "$BUILD_DIR" -j "$(nproc)" --target semlio_kitti
fi
# GNU parallel also with SKIP_BUILD (CTest's run): a fresh machine lacks it.
command -v parallel > /dev/null || scripts/install_deps.sh parallel > /dev/null
command -v parallel > /dev/null || { echo "batch.sh: GNU parallel is missing (apt-get install parallel)" >&2; exit 1; }

TOOL=${TOOL:-}
if [[ -z "$TOOL" ]]; then
  if [[ -x "$BUILD_DIR/examples/semlio_run" ]]; then TOOL=$BUILD_DIR/examples/semlio_run
  else TOOL=$BUILD_DIR/examples/semlio_kitti; fi
fi
[[ -x "$TOOL" ]] || { echo "batch.sh: $TOOL is not built" >&2; exit 1; }
case "$(basename "$TOOL")" in
  semlio_kitti*) INPUT_FLAG=--sequence ;;
  *) INPUT_FLAG=--input ;;
esac

# The inputs, in a stable order.
inputs=()
if [[ -f "$SPEC" ]]; then
  while IFS= read -r line || [[ -n "$line" ]]; do
    line=${line%%$'\r'}
    [[ -z "${line// }" || "$line" == \#* ]] && continue
    inputs+=("$line")
  done < "$SPEC"
else
  shopt -s nullglob
  # shellcheck disable=SC2206  # the glob is meant to expand here
  inputs=($SPEC)
  shopt -u nullglob
fi
[[ ${#inputs[@]} -gt 0 ]] || { echo "batch.sh: '$SPEC' is neither a list file nor a glob that matches anything" >&2; exit 2; }
for p in "${inputs[@]}"; do
  [[ -e "$p" ]] || { echo "batch.sh: input '$p' does not exist" >&2; exit 2; }
done

mkdir -p "$OUT/runs"
jobs_file="$OUT/jobs.tsv"  # run name <TAB> input path
: > "$jobs_file"
i=0
for p in "${inputs[@]}"; do
  name=$(printf '%03d_%s' "$i" "$(basename "${p%/}" | tr -c 'A-Za-z0-9._\n-' '_')")
  printf '%s\t%s\n' "$name" "$p" >> "$jobs_file"
  i=$((i + 1))
done
echo "== $(basename "$TOOL") over ${#inputs[@]} inputs, $JOBS at a time -> $OUT"

# One job per input; each run's outputs in its own folder, its terminal output in log.txt.
# --overwrite where the tool has it (semlio_run, today's semlio_kitti): a rerun replaces old runs.
overwrite=()
# The help text is read whole first: `--help | grep -q` under pipefail fails
# whenever grep quits before the tool has written everything (SIGPIPE), and a
# rerun without --overwrite is then refused (exit 1, the old report left in place).
help=$("$TOOL" --help 2>&1 || true)
[[ "$help" == *--overwrite* ]] && overwrite=(--overwrite)
export TOOL INPUT_FLAG OUT
run_one() {  # name input options...
  local name=$1 input=$2
  shift 2
  mkdir -p "$OUT/runs/$name"
  "$TOOL" "$INPUT_FLAG" "$input" --out "$OUT/runs/$name" --quiet "$@" > "$OUT/runs/$name/log.txt" 2>&1
}
export -f run_one
status=0
# -q quotes every argument (paths and options with spaces survive); the
# exported function needs bash as parallel's shell.
PARALLEL_SHELL=bash parallel --will-cite -q --jobs "$JOBS" --colsep '\t' --joblog "$OUT/joblog.tsv" \
  run_one '{1}' '{2}' "${overwrite[@]}" "${TOOL_OPTS[@]}" :::: "$jobs_file" || status=1

/usr/bin/python3 scripts/batch_table.py "$OUT"
if [[ $status -ne 0 ]]; then
  echo "== some runs failed: see their log.txt (the table's exit column)" >&2
fi
exit "$status"
