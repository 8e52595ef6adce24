#!/usr/bin/env bash
# Self-consistency of the odometry on a real KITTI raw snippet (no ground
# truth): runs semlio_kitti forward and backward over a folder of PCD scans
# (e.g. the 22-frame KITTI raw snippet), with and without deskew, for each
# preset, and checks smooth forward motion, no jumps, and agreement of the
# forward and backward relative motions (< 5 cm per step).
#   scripts/kitti_raw_consistency.sh PCD_DIR [PRESETS] [DESKEW]
#     PRESETS: "baseline full" (default), "baseline" or "full"
#     DESKEW:  "off on" (default), "off" or "on"
# Environment: BUILD_DIR (default build); SEMLIO_KITTI (default
# $BUILD_DIR/examples/semlio_kitti) to run another semlio_kitti binary; OUT
# (results/kitti_raw_consistency); SKIP_BUILD=1 (use BUILD_DIR as built; CI
# runs it on the 3 frames in tests/data/kitti_raw/snippet_22 this way);
# REPORT_ONLY=1 (exit 0 when every run and the analysis complete, whatever the
# verdict: 3 frames are too few for the bounds, the first step has no
# velocity to deskew with); EXTRA_CONFIG=FILE.yaml (appended to every run's
# config, for settings other than deskew, e.g. features: or solver:).
#
# KITTI raw sweeps are not motion-compensated. Deskew (imu/deskew.hpp,
# SweepDeskew) is switched on through a --config YAML file:
#   forward:  deskew: {mode: constant_velocity, point_times: azimuth}
#   backward: the same plus reverse_time: true. The backward run plays the
#   scans in reverse order, but each sweep was still recorded forward in time:
#   seen in reversed time it spins the other way, so the per-point times are
#   reversed (t -> period - t). With the backward (negated) predicted motion
#   the correction is then the same as forward; without it the backward run
#   would double the distortion.
# The time convention (clockwise, sweep seam facing forward) is KITTI raw's
# as measured in features/rings.hpp.
set -euo pipefail
cd "$(dirname "$0")/.."
IN=${1:?usage: scripts/kitti_raw_consistency.sh PCD_DIR [PRESETS] [DESKEW]}
PRESETS=${2:-baseline full}
DESKEWS=${3:-off on}
BUILD_DIR=${BUILD_DIR:-build}
KITTI_BIN=${SEMLIO_KITTI:-$BUILD_DIR/examples/semlio_kitti}
OUT=${OUT:-results/kitti_raw_consistency}
if [ -z "${SKIP_BUILD:-}" ]; then
  scripts/install_deps.sh
  cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release > /dev/null
  cmake --build "$BUILD_DIR" -j "$(nproc)" --target semlio_convert semlio_kitti
fi
rm -rf "$OUT" && mkdir -p "$OUT/fwd/velodyne" "$OUT/bwd/velodyne"
mapfile -t files < <(ls "$IN"/*.pcd | sort)
n=${#files[@]}
for i in "${!files[@]}"; do
  "$BUILD_DIR/examples/semlio_convert" "${files[$i]}" "$OUT/fwd/velodyne/$(printf %06d "$i").bin" > /dev/null
  cp "$OUT/fwd/velodyne/$(printf %06d "$i").bin" "$OUT/bwd/velodyne/$(printf %06d $((n - 1 - i))).bin"
done
for d in fwd bwd; do
  /usr/bin/python3 -c "import sys; [print(f'{0.1*i:.6f}') for i in range($n)]" > "$OUT/$d/times.txt"
done
printf 'deskew:\n  mode: none\n' > "$OUT/off_fwd.yaml"
cp "$OUT/off_fwd.yaml" "$OUT/off_bwd.yaml"
printf 'deskew:\n  mode: constant_velocity\n  point_times: azimuth\n' > "$OUT/on_fwd.yaml"
printf 'deskew:\n  mode: constant_velocity\n  point_times: azimuth\n  reverse_time: true\n' > "$OUT/on_bwd.yaml"
if [ -n "${EXTRA_CONFIG:-}" ]; then
  if [ ! -r "$EXTRA_CONFIG" ]; then echo "EXTRA_CONFIG=$EXTRA_CONFIG: no such readable file"; exit 2; fi
  if grep -q '^deskew' "$EXTRA_CONFIG"; then echo "EXTRA_CONFIG must not set deskew: (this script does)"; exit 2; fi
  # A bare `{}` (the defaults) after the deskew: mapping would not be YAML.
  for f in off_fwd off_bwd on_fwd on_bwd; do
    grep -v '^[[:space:]]*{}[[:space:]]*$' "$EXTRA_CONFIG" >> "$OUT/$f.yaml" || true
  done
fi

status=0
for preset in $PRESETS; do
  for deskew in $DESKEWS; do
    tag="${preset}_deskew_${deskew}"
    ok=1
    for d in fwd bwd; do
      if ! "$KITTI_BIN" --sequence "$OUT/$d" --labels none --preset "$preset" --kitti-correction on \
          --config "$OUT/${deskew}_${d}.yaml" --out "$OUT/run_${tag}_$d" --quiet --overwrite > "$OUT/run_${tag}_$d.log" 2>&1; then
        echo "$tag: semlio_kitti failed ($d), see $OUT/run_${tag}_$d.log:"
        tail -n 3 "$OUT/run_${tag}_$d.log"
        if grep -q "deskew" "$OUT/run_${tag}_$d.log"; then
          echo "  (semlio_kitti must read the config's deskew: section: semlio_examples::load_deskew_yaml in examples/common/deskew_yaml.hpp)"
        fi
        ok=0
        break
      fi
    done
    if [ "$ok" -eq 0 ]; then status=1; continue; fi
    verdict=0
    /usr/bin/python3 - "$tag" "$OUT/run_${tag}_fwd/poses_tum.txt" "$OUT/run_${tag}_bwd/poses_tum.txt" <<'PY' || verdict=$?
import math
import statistics
import sys
# Plain Python (no numpy): poses as (R, t) with R a row-major 3x3 list.
def quat_to_R(qx, qy, qz, qw):
    return [[1-2*(qy*qy+qz*qz), 2*(qx*qy-qz*qw), 2*(qx*qz+qy*qw)],
            [2*(qx*qy+qz*qw), 1-2*(qx*qx+qz*qz), 2*(qy*qz-qx*qw)],
            [2*(qx*qz-qy*qw), 2*(qy*qz+qx*qw), 1-2*(qx*qx+qy*qy)]]
def matmul(A, B):
    return [[sum(A[i][k] * B[k][j] for k in range(3)) for j in range(3)] for i in range(3)]
def transpose(A):
    return [[A[j][i] for j in range(3)] for i in range(3)]
def apply(R, v):
    return [sum(R[i][k] * v[k] for k in range(3)) for i in range(3)]
def inverse(T):
    R, t = T
    Rt = transpose(R)
    return (Rt, [-x for x in apply(Rt, t)])
def compose(A, B):
    return (matmul(A[0], B[0]), [a + b for a, b in zip(apply(A[0], B[1]), A[1])])
def norm(v):
    return math.sqrt(sum(x * x for x in v))
def load(p):
    T = []
    for line in open(p):
        if line.strip():
            x, y, z, qx, qy, qz, qw = map(float, line.split()[1:8])
            T.append((quat_to_R(qx, qy, qz, qw), [x, y, z]))
    return T
tag = sys.argv[1]
fwd, bwd = load(sys.argv[2]), load(sys.argv[3])
n = len(fwd)
step_f = [compose(inverse(fwd[i]), fwd[i + 1]) for i in range(n - 1)]
# backward frame j is forward frame n-1-j: the backward step j -> j+1 is the
# inverse of the forward step n-2-j -> n-1-j.
step_b = [inverse(compose(inverse(bwd[n - 2 - i]), bwd[n - 1 - i])) for i in range(n - 1)]
d = [norm(s[1]) for s in step_f]
fx = [s[1][0] for s in step_f]
diff = [norm([p - q for p, q in zip(a[1], b[1])]) for a, b in zip(step_f, step_b)]
def angle_deg(A, B):
    M = matmul(transpose(A), B)
    c = (M[0][0] + M[1][1] + M[2][2] - 1) / 2
    return math.degrees(math.acos(max(-1.0, min(1.0, c))))
ang = [angle_deg(a[0], b[0]) for a, b in zip(step_f, step_b)]
jump = max(abs(d[i + 1] - d[i]) for i in range(len(d) - 1))
ok = min(fx) > 0.5 and jump < 0.1 and max(diff) < 0.05
print(f"{tag}: {n} frames, {norm(fwd[-1][1]):.2f} m; step [m] min {min(d):.3f} median {statistics.median(d):.3f} "
      f"max {max(d):.3f} (forward x min {min(fx):.3f}); largest step change {jump:.3f} m; "
      f"fwd/bwd step difference mean {statistics.fmean(diff)*100:.2f} cm max {max(diff)*100:.2f} cm, rotation max {max(ang):.3f} deg"
      f" -> {'consistent' if ok else 'NOT consistent'}")
print("  fwd/bwd per step [cm]: " + " ".join(f"{x*100:.1f}" for x in diff))
sys.exit(0 if ok else 1)
PY
    # 1 = measured and not consistent; anything else = the analysis broke.
    if [ "$verdict" -ne 0 ] && { [ "$verdict" -ne 1 ] || [ -z "${REPORT_ONLY:-}" ]; }; then status=1; fi
  done
done
echo "thresholds: forward step > 0.5 m, step change < 0.1 m, fwd/bwd < 5 cm on every step"
exit $status
