#!/usr/bin/env bash
# Self-consistency of the odometry on a real KITTI raw snippet (no ground
# truth): runs semlio_kitti forward and backward over a folder of PCD scans
# (e.g. the 22-frame KITTI raw snippet) and checks smooth forward motion, no
# jumps, and agreement of the forward and backward relative motions.
#   scripts/kitti_raw_consistency.sh PCD_DIR [PRESET]
# The scans are used as recorded: KITTI raw sweeps are not motion-compensated
# and semlio_kitti does not deskew yet, so forward and backward runs see the
# in-sweep distortion with opposite signs; the fwd/bwd gap measures that.
set -euo pipefail
cd "$(dirname "$0")/.."
IN=${1:?usage: scripts/kitti_raw_consistency.sh PCD_DIR [baseline|full]}
PRESET=${2:-full}
BUILD_DIR=${BUILD_DIR:-build}
OUT=results/kitti_raw_consistency
scripts/install_deps.sh python3-numpy
cmake -S . -B "$BUILD_DIR" -DCMAKE_BUILD_TYPE=Release > /dev/null
cmake --build "$BUILD_DIR" -j "$(nproc)" --target semlio_convert semlio_kitti
rm -rf "$OUT" && mkdir -p "$OUT/fwd/velodyne" "$OUT/bwd/velodyne"
mapfile -t files < <(ls "$IN"/*.pcd | sort)
n=${#files[@]}
for i in "${!files[@]}"; do
  "$BUILD_DIR/examples/semlio_convert" "${files[$i]}" "$OUT/fwd/velodyne/$(printf %06d "$i").bin" > /dev/null
  cp "$OUT/fwd/velodyne/$(printf %06d "$i").bin" "$OUT/bwd/velodyne/$(printf %06d $((n - 1 - i))).bin"
done
for d in fwd bwd; do
  /usr/bin/python3 -c "import sys; [print(f'{0.1*i:.6f}') for i in range($n)]" > "$OUT/$d/times.txt"
  "$BUILD_DIR/examples/semlio_kitti" --sequence "$OUT/$d" --labels none --preset "$PRESET" \
    --kitti-correction on --out "$OUT/run_$d" --quiet
done
/usr/bin/python3 - "$OUT/run_fwd/poses_tum.txt" "$OUT/run_bwd/poses_tum.txt" <<'PY'
import sys
import numpy as np
def load(p):
    rows = [list(map(float, l.split())) for l in open(p) if l.strip()]
    T = []
    for r in rows:
        x, y, z, qx, qy, qz, qw = r[1:]
        R = np.array([[1-2*(qy*qy+qz*qz), 2*(qx*qy-qz*qw), 2*(qx*qz+qy*qw)],
                      [2*(qx*qy+qz*qw), 1-2*(qx*qx+qz*qz), 2*(qy*qz-qx*qw)],
                      [2*(qx*qz-qy*qw), 2*(qy*qz+qx*qw), 1-2*(qx*qx+qy*qy)]])
        M = np.eye(4); M[:3, :3] = R; M[:3, 3] = [x, y, z]; T.append(M)
    return T
fwd, bwd = load(sys.argv[1]), load(sys.argv[2])
n = len(fwd)
step_f = [np.linalg.inv(fwd[i]) @ fwd[i + 1] for i in range(n - 1)]
# backward frame j is forward frame n-1-j: the backward step j -> j+1 is the
# inverse of the forward step n-2-j -> n-1-j.
step_b = [np.linalg.inv(np.linalg.inv(bwd[n - 2 - i]) @ bwd[n - 1 - i]) for i in range(n - 1)]
d = np.array([np.linalg.norm(s[:3, 3]) for s in step_f])
fx = np.array([s[0, 3] for s in step_f])
diff = np.array([np.linalg.norm(a[:3, 3] - b[:3, 3]) for a, b in zip(step_f, step_b)])
ang = np.array([np.degrees(np.arccos(np.clip((np.trace(a[:3, :3].T @ b[:3, :3]) - 1) / 2, -1, 1))) for a, b in zip(step_f, step_b)])
total = np.linalg.norm(fwd[-1][:3, 3])
print(f"frames {n}, forward distance {total:.2f} m")
print(f"step length [m]: min {d.min():.3f} median {np.median(d):.3f} max {d.max():.3f} (forward x component min {fx.min():.3f})")
print(f"largest step change between consecutive frames: {np.abs(np.diff(d)).max():.3f} m")
print(f"forward vs backward step: translation max {diff.max()*100:.2f} cm (mean {diff.mean()*100:.2f} cm), rotation max {ang.max():.3f} deg")
ok = fx.min() > 0.5 and np.abs(np.diff(d)).max() < 0.1 and diff.max() < 0.05
print("consistent" if ok else "NOT consistent (thresholds: forward step > 0.5 m, step change < 0.1 m, fwd/bwd < 5 cm)")
sys.exit(0 if ok else 1)
PY
