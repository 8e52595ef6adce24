#!/usr/bin/env python3
"""Evaluates an odometry run on the BALM OS0 keyframes (scripts/balm_os0.sh).

Usage: balm_os0_eval.py REFERENCE_POSES ESTIMATED_POSES STATUS_FILE SENSOR_FACTS [JSON_OUT]

Prints the sensor facts, the frame statuses, the median keyframe-to-keyframe
translation / rotation difference to the reference (relative pose errors
between consecutive keyframes), the ATE after an SE(3) alignment (Horn's
closed form, no scale) and one PASS/FAIL line per must-hold. Exit status 0
when every must-hold passes, 1 otherwise. With JSON_OUT the same numbers
are also written there as JSON (read by scripts/data_sources_page.py).
Pure Python (no numpy)."""
import json
import math
import sys

from ate_resolution import aligned_rmse
from kitti_poses import pose_inv, pose_mul


def read_poses(path):
    poses = []
    with open(path) as f:
        for line in f:
            v = [float(x) for x in line.split()]
            if not v:
                continue
            if len(v) != 12:
                sys.exit(f"{path}: expected 12 numbers per line, got {len(v)}")
            poses.append([v[0:4], v[4:8], v[8:12], [0.0, 0.0, 0.0, 1.0]])
    return poses


def angle_deg(a):
    # atan2 of the antisymmetric and symmetric parts: the reference poses are
    # written with 7 digits, and acos((trace - 1) / 2) of a rotation that is
    # orthonormal only to 1e-6 is off by up to ~0.1 deg near the identity.
    c = (a[0][0] + a[1][1] + a[2][2] - 1.0) / 2.0
    s = 0.5 * math.sqrt((a[2][1] - a[1][2]) ** 2 + (a[0][2] - a[2][0]) ** 2 + (a[1][0] - a[0][1]) ** 2)
    return math.degrees(math.atan2(s, c))


def norm3(a):
    return math.sqrt(sum(a[i][3] ** 2 for i in range(3)))


def median(v):
    s = sorted(v)
    n = len(s)
    return s[n // 2] if n % 2 else 0.5 * (s[n // 2 - 1] + s[n // 2])


def main():
    if len(sys.argv) not in (5, 6):
        sys.exit(__doc__)
    ref = read_poses(sys.argv[1])
    est = read_poses(sys.argv[2])
    with open(sys.argv[3]) as f:
        status = [line.strip() for line in f if line.strip()]
    facts = {}
    with open(sys.argv[4]) as f:
        for line in f:
            k, _, v = line.rstrip("\n").partition(" ")
            facts[k] = v
    if len(est) != len(ref) or len(status) != len(ref):
        sys.exit(f"{len(ref)} reference poses, {len(est)} estimated, {len(status)} statuses")
    base = pose_inv(ref[0])
    ref = [pose_mul(base, r) for r in ref]

    print("sensor:", ", ".join(f"{k}={v}" for k, v in facts.items()))
    counts = {}
    for s in status:
        counts[s] = counts.get(s, 0) + 1
    print("statuses:", " ".join(f"{k}={v}" for k, v in sorted(counts.items())))
    dt, dr = [], []
    for i in range(1, len(ref)):
        e = pose_mul(pose_inv(pose_mul(pose_inv(ref[i - 1]), ref[i])), pose_mul(pose_inv(est[i - 1]), est[i]))
        dt.append(norm3(e))
        dr.append(angle_deg(e))
    ate = aligned_rmse([[e[i][3] for i in range(3)] for e in est], [[q[i][3] for i in range(3)] for q in ref])
    print(f"keyframe-to-keyframe difference to the reference: median {median(dt) * 100:.2f} cm / "
          f"{median(dr):.3f} deg, max {max(dt) * 100:.2f} cm / {max(dr):.3f} deg")
    print(f"ATE (SE(3) alignment, {len(ref)} keyframes): RMSE {ate:.4f} m")

    lost = sum(v for k, v in counts.items() if k not in ("initialized", "tracked", "degenerate"))
    checks = [
        ("beam table detected and reported",
         facts.get("detection_separable") == "true" and int(facts.get("beams", "0")) > 0,
         f"{facts.get('beams', '?')} beams, {facts.get('detection', 'no detection')}, "
         f"fit {facts.get('detection_fit_fraction', '?')}"),
        ("no frame lost or rejected", lost == 0, f"{lost} frames neither tracked nor degenerate"),
        ("median keyframe-to-keyframe difference <= 5 cm / 0.5 deg",
         median(dt) <= 0.05 and median(dr) <= 0.5, f"{median(dt) * 100:.2f} cm / {median(dr):.3f} deg"),
        ("ATE <= 0.10 m", ate <= 0.10, f"{ate:.4f} m"),
    ]
    ok = True
    for name, passed, detail in checks:
        print(f"{'PASS' if passed else 'FAIL'}  {name}: {detail}")
        ok = ok and passed
    if len(sys.argv) == 6:
        with open(sys.argv[5], "w") as f:
            json.dump({"keyframes": len(ref), "statuses": counts, "lost": lost, "sensor": facts,
                       "median_step_difference_m": median(dt), "median_step_difference_deg": median(dr),
                       "max_step_difference_m": max(dt), "max_step_difference_deg": max(dr), "ate_m": ate,
                       "checks": [{"name": n, "pass": p, "detail": d} for n, p, d in checks], "pass": ok},
                      f, indent=1)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
