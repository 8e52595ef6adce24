#!/usr/bin/python3
"""Can a drive's reference tell two estimates apart? The paired difference of
their aligned ATE and its standard error by a moving-block bootstrap over the
frames. Pure Python (the results page must not need numpy); the self-test
checks the alignment against numpy's SVD when numpy is there.

usage: ate_resolution.py --self-test

Why a bootstrap over frames: on a real drive the reference's own error
(OXTS jitters by centimetres per frame) is common to both estimates, so a
sub-millimetre ATE difference between two estimates a centimetre apart can
come from where that error happens to point. Resampling the frames (in
blocks, since odometry and reference errors are correlated in time) and
re-aligning both estimates on each resample shows how much the difference
moves with the choice of frames: a difference within two standard errors is
one the drive cannot resolve. The same two-standard-error rule judges the
label-quality sweep across seeds (scripts/label_quality_sweep.sh).
"""
import math
import random
import sys


def _jacobi_top_eigenvector(a):
    """Eigenvector of the largest eigenvalue of a symmetric 4x4 matrix
    (cyclic Jacobi rotations, accumulated)."""
    a = [row[:] for row in a]
    n = 4
    v = [[1.0 if i == j else 0.0 for j in range(n)] for i in range(n)]
    for _ in range(100):
        off = sum(a[i][j] * a[i][j] for i in range(n) for j in range(n) if i != j)
        if off < 1e-30 * max(1e-300, sum(a[i][i] * a[i][i] for i in range(n))):
            break
        for p in range(n - 1):
            for q in range(p + 1, n):
                if a[p][q] == 0.0:
                    continue
                theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q])
                t = math.copysign(1.0, theta) / (abs(theta) + math.sqrt(theta * theta + 1.0))
                c = 1.0 / math.sqrt(t * t + 1.0)
                s = t * c
                for k in range(n):  # columns p, q of a and of v
                    akp, akq = a[k][p], a[k][q]
                    a[k][p], a[k][q] = c * akp - s * akq, s * akp + c * akq
                    vkp, vkq = v[k][p], v[k][q]
                    v[k][p], v[k][q] = c * vkp - s * vkq, s * vkp + c * vkq
                for k in range(n):  # rows p, q of a
                    apk, aqk = a[p][k], a[q][k]
                    a[p][k], a[q][k] = c * apk - s * aqk, s * apk + c * aqk
    top = max(range(n), key=lambda i: a[i][i])
    return [v[k][top] for k in range(n)]


def aligned_rmse(est, ref, idx=None):
    """RMSE of est's positions against ref's after the best rigid (SE(3))
    alignment, over the frame indices idx (all when None; repeats allowed).

    Horn's closed form: the rotation is the unit quaternion of the largest
    eigenvalue of his 4x4 matrix of the cross-covariance; the residuals are
    then formed explicitly (not from the eigenvalue, whose subtraction from
    the spread would lose the micrometres)."""
    if idx is None:
        idx = range(len(est))
    idx = list(idx)
    n = len(idx)
    mx = [sum(est[i][k] for i in idx) / n for k in range(3)]
    my = [sum(ref[i][k] for i in idx) / n for k in range(3)]
    s = [[0.0] * 3 for _ in range(3)]
    for i in idx:
        x = [est[i][k] - mx[k] for k in range(3)]
        y = [ref[i][k] - my[k] for k in range(3)]
        for r in range(3):
            for c in range(3):
                s[r][c] += x[r] * y[c]
    (xx, xy, xz), (yx, yy, yz), (zx, zy, zz) = s
    N = [[xx + yy + zz, yz - zy, zx - xz, xy - yx],
         [yz - zy, xx - yy - zz, xy + yx, zx + xz],
         [zx - xz, xy + yx, -xx + yy - zz, yz + zy],
         [xy - yx, zx + xz, yz + zy, -xx - yy + zz]]
    w, qx, qy, qz = _jacobi_top_eigenvector(N)
    R = [[w * w + qx * qx - qy * qy - qz * qz, 2 * (qx * qy - w * qz), 2 * (qx * qz + w * qy)],
         [2 * (qx * qy + w * qz), w * w - qx * qx + qy * qy - qz * qz, 2 * (qy * qz - w * qx)],
         [2 * (qx * qz - w * qy), 2 * (qy * qz + w * qx), w * w - qx * qx - qy * qy + qz * qz]]
    sse = 0.0
    for i in idx:
        x = [est[i][k] - mx[k] for k in range(3)]
        for r in range(3):
            e = R[r][0] * x[0] + R[r][1] * x[1] + R[r][2] * x[2] + my[r] - ref[i][r]
            sse += e * e
    return math.sqrt(sse / n)


def block_length(n):
    """Moving-block length: n^(1/3) frames (the usual order for the moving-block bootstrap)."""
    return max(1, round(n ** (1.0 / 3.0)))


MIN_BLOCKS = 4  # fewer blocks than this cannot give a standard error worth quoting


def paired_difference(ref, est_a, est_b, resamples=2000, seed=1):
    """(ATE_b - ATE_a, its bootstrap standard error, block length) in metres;
    the error is None when the drive has fewer than MIN_BLOCKS blocks.
    Deterministic for a given seed."""
    n = len(ref)
    if not (len(est_a) == len(est_b) == n):
        raise ValueError(f"{len(est_a)} and {len(est_b)} estimated positions for {n} reference positions")
    diff = aligned_rmse(est_b, ref) - aligned_rmse(est_a, ref)
    length = block_length(n)
    if n // length < MIN_BLOCKS:
        return diff, None, length
    rng = random.Random(seed)
    starts = n - length + 1
    blocks = math.ceil(n / length)
    diffs = []
    for _ in range(resamples):
        idx = []
        for _ in range(blocks):
            s = rng.randrange(starts)
            idx.extend(range(s, s + length))
        idx = idx[:n]
        diffs.append(aligned_rmse(est_b, ref, idx) - aligned_rmse(est_a, ref, idx))
    mean = sum(diffs) / len(diffs)
    se = math.sqrt(sum((d - mean) ** 2 for d in diffs) / (len(diffs) - 1))
    return diff, se, length


def verdict(diff, se):
    """'worse' / 'better' when |diff| >= 2 se, else 'not resolved'."""
    if se is None:
        return "too few frames to resolve"
    if diff >= 2.0 * se:
        return "worse"
    if diff <= -2.0 * se:
        return "better"
    return "not resolved"


def _self_test():
    rng = random.Random(7)
    failures = []

    def check(ok, what):
        if not ok:
            failures.append(what)

    # A drive-like path: 80 positions along a curve.
    ref = [[0.8 * i, 3.0 * math.sin(0.05 * i), 0.02 * i] for i in range(80)]
    # A rigid motion of it: aligned RMSE is 0.
    ang = 0.7
    R = [[math.cos(ang), -math.sin(ang), 0.0], [math.sin(ang), math.cos(ang), 0.0], [0.0, 0.0, 1.0]]
    moved = [[sum(R[r][c] * p[c] for c in range(3)) + [5.0, -2.0, 1.0][r] for r in range(3)] for p in ref]
    check(aligned_rmse(moved, ref) < 1e-9, f"rigid copy: aligned RMSE {aligned_rmse(moved, ref)} not 0")
    # With noise: equal to numpy's SVD (Umeyama) alignment.
    noisy = [[v + rng.gauss(0.0, 0.05) for v in p] for p in moved]
    mine = aligned_rmse(noisy, ref)
    try:
        import numpy as np
        X, Y = np.array(noisy), np.array(ref)
        mx, my = X.mean(0), Y.mean(0)
        U, _, Vt = np.linalg.svd((Y - my).T @ (X - mx))
        D = np.eye(3)
        D[2, 2] = np.sign(np.linalg.det(U @ Vt))
        Rn = U @ D @ Vt
        theirs = float(np.sqrt(np.mean(np.sum(((X - mx) @ Rn.T + my - Y) ** 2, axis=1))))
        check(abs(mine - theirs) < 1e-9, f"noisy copy: {mine} against numpy's {theirs}")
    except ImportError:
        print("numpy missing: the SVD comparison was not run", file=sys.stderr)
    check(0.06 < mine < 0.1, f"noisy copy: aligned RMSE {mine} far from the noise's 0.087 m (0.05 m per axis)")
    # Identical estimates: difference 0, standard error 0.
    d, se, _ = paired_difference(ref, noisy, noisy, resamples=200)
    check(d == 0.0 and se == 0.0, f"identical estimates: {d} +- {se}")
    # The same estimate rigidly moved: alignment removes it.
    d, se, _ = paired_difference(ref, noisy, [[v + 1.0 for v in p] for p in noisy], resamples=200)
    check(abs(d) < 1e-9 and se < 1e-9, f"shifted estimate: {d} +- {se}")
    # A clearly worse estimate (10x the noise) is resolved as worse, and the
    # other way round as better; a tiny perturbation is not resolved.
    bad = [[v + rng.gauss(0.0, 0.5) for v in p] for p in moved]
    d, se, _ = paired_difference(ref, noisy, bad, resamples=400)
    check(verdict(d, se) == "worse", f"much worse estimate judged {verdict(d, se)} ({d} +- {se})")
    d, se, _ = paired_difference(ref, bad, noisy, resamples=400)
    check(verdict(d, se) == "better", f"much better estimate judged {verdict(d, se)} ({d} +- {se})")
    tiny = [[v + rng.gauss(0.0, 0.005) for v in p] for p in noisy]
    d, se, _ = paired_difference(ref, noisy, tiny, resamples=400)
    check(verdict(d, se) == "not resolved", f"tiny perturbation judged {verdict(d, se)} ({d} +- {se})")
    # Deterministic for a seed.
    check(paired_difference(ref, noisy, tiny, resamples=100, seed=3) ==
          paired_difference(ref, noisy, tiny, resamples=100, seed=3), "not deterministic")
    # Too few frames: no standard error.
    d, se, _ = paired_difference(ref[:2], noisy[:2], tiny[:2])
    check(se is None and verdict(d, se) == "too few frames to resolve", "two frames gave a standard error")
    try:
        paired_difference(ref, noisy[:10], tiny)
        check(False, "mismatched lengths accepted")
    except ValueError:
        pass
    for f in failures:
        print("FAIL:", f)
    print(f"ate_resolution self-test: {10 - len(failures)} of 10 checks passed")
    return 1 if failures else 0


if __name__ == "__main__":
    if sys.argv[1:] == ["--self-test"]:
        sys.exit(_self_test())
    sys.exit(__doc__)
