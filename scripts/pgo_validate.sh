#!/usr/bin/env bash
# Runs semlio_pgo on every benchmark graph in tests/data/posegraphs and prints
# the final chi2 next to the reference value from tests/data/posegraphs/README.md
# (copied from the shared data README), with the relative difference and time.
# When the optional Ceres peer (bench_pgo_ceres) was built, runs it too: it
# solves the same problems with Ceres and prints the semlio/Ceres time ratio.
#
#   scripts/pgo_validate.sh [BUILD_DIR]     (default: ./build)
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
build=${1:-$root/build}
pgo=$build/examples/semlio_pgo
data=$root/tests/data/posegraphs
if [[ ! -x $pgo ]]; then
  echo "pgo_validate: $pgo not found; build the semlio_pgo target first" >&2
  exit 2
fi
printf '%-16s %18s %18s %10s %6s %10s %10s %s\n' graph final_chi2 reference rel_diff iters wall_s cpu_s status
fail=0
for file in "$data"/*.g2o; do
  name=$(basename "$file" .g2o)
  ref=$(awk -v n="$name" '$1 == n { print $2; exit }' "$data/README.md")
  out=$("$pgo" "$file") || true
  chi2=$(awk -F': ' '/^final chi2/ { print $2 }' <<<"$out")
  iters=$(awk -F': ' '/^iterations/ { print $2 }' <<<"$out")
  secs=$(awk -F': ' '/^time/ { sub(/ s$/, "", $2); print $2 }' <<<"$out")
  cpu=$(awk -F': ' '/^cpu time/ { sub(/ s$/, "", $2); print $2 }' <<<"$out")
  status=$(awk -F': ' '/^status/ { print $2 }' <<<"$out")
  if [[ -n $ref && -n $chi2 ]]; then
    rel=$(awk -v a="$chi2" -v b="$ref" 'BEGIN { d = (a - b) / b; if (d < 0) d = -d; printf "%.2e", d }')
    ok=$(awk -v r="$rel" 'BEGIN { print (r <= 1e-6) ? "ok" : "DIFFERS" }')
    [[ $ok == ok ]] || fail=1
  else
    ref=${ref:--}
    rel=-
    ok=no-reference
  fi
  printf '%-16s %18s %18s %10s %6s %10s %10s %s (%s)\n' "$name" "${chi2:--}" "$ref" "$rel" "${iters:--}" "${secs:--}" "${cpu:--}" "$ok" "${status:-failed}"
done
ceres=$build/bench/bench_pgo_ceres
if [[ -x $ceres ]]; then
  echo
  echo "Ceres peer (same objective, same run; ratio = semlio CPU time / Ceres CPU time):"
  "$ceres" "$data"/*.g2o
else
  echo
  echo "(bench_pgo_ceres not built: install libceres-dev and reconfigure for the Ceres time ratio)"
fi
exit $fail
