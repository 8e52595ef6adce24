#!/usr/bin/env python3
"""How much ATE can loop closure remove from a given odometry at all?

Builds a pose graph from a semlio_kitti run: one node per keyframe at its
odometry pose (poses_odom.txt), one odometry edge per consecutive keyframe
pair (the odometry's own relative motion), and one loop edge per loop the run
accepted (report.json), but measured from the GROUND TRUTH (an oracle: a
perfect loop measurement). semlio_pgo solves it and semlio_eval scores the
keyframes before and after. Whatever a back end does with real, noisy loop
measurements, it cannot beat this by much: the oracle tells apart "the back
end weighs its loops badly" from "these loops cannot observe this odometry's
error".

    scripts/loop_oracle.py --run OUT --gt DRIVE/poses.txt [--build build]

OUT is a semlio_kitti --loop on output directory (poses_odom.txt, poses.txt,
keyframes.txt, report.json); the ground truth has one pose per input frame in
the same frame as the run's poses (semlio_kitti writes camera-0 poses when the
sequence has a calib, as the simulator's has).

Edge information (g2o order x y z qx qy qz, diagonal): odometry
1/sigma^2 with --odometry-sigma-m (default 1.3 mm) and --odometry-sigma-rad
(default 14 urad): the per-keyframe error of an odometry with 0.1 % and
0.06 deg/100 m KITTI errors at ~1.3 m keyframe spacing, semlio's on the
simulated drives; oracle loops 100 times stronger. Too weak a rotation
information bends the trajectory to meet the loops (1 cm / 1 mrad: the 92
oracle loops of the 5000-frame drive worsen its ATE by 9 %).
Prints the keyframe ATE of the odometry, of the run's own back end and of the
oracle graph, and the two ratios.
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile

from kitti_poses import read_kitti_poses


def inverse(a):
    r = [[a[j][i] for j in range(3)] for i in range(3)]
    t = [-sum(r[i][k] * a[k][3] for k in range(3)) for i in range(3)]
    return [r[0] + [t[0]], r[1] + [t[1]], r[2] + [t[2]], [0.0, 0.0, 0.0, 1.0]]


def compose(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


def quaternion(m):
    """Unit quaternion (x, y, z, w) of a rotation matrix (Shepperd's method)."""
    tr = m[0][0] + m[1][1] + m[2][2]
    if tr > 0.0:
        s = math.sqrt(tr + 1.0) * 2.0
        q = ((m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s, 0.25 * s)
    elif m[0][0] > m[1][1] and m[0][0] > m[2][2]:
        s = math.sqrt(1.0 + m[0][0] - m[1][1] - m[2][2]) * 2.0
        q = (0.25 * s, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s, (m[2][1] - m[1][2]) / s)
    elif m[1][1] > m[2][2]:
        s = math.sqrt(1.0 + m[1][1] - m[0][0] - m[2][2]) * 2.0
        q = ((m[0][1] + m[1][0]) / s, 0.25 * s, (m[1][2] + m[2][1]) / s, (m[0][2] - m[2][0]) / s)
    else:
        s = math.sqrt(1.0 + m[2][2] - m[0][0] - m[1][1]) * 2.0
        q = ((m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, 0.25 * s, (m[1][0] - m[0][1]) / s)
    n = math.sqrt(sum(c * c for c in q))
    return tuple(c / n for c in q)


def rotation(qx, qy, qz, qw):
    return [[1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
            [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
            [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)]]


def g2o_pose(m):
    x, y, z, w = quaternion(m)
    return f"{m[0][3]:.9f} {m[1][3]:.9f} {m[2][3]:.9f} {x:.12f} {y:.12f} {z:.12f} {w:.12f}"


def g2o_information(sigma_t2_inv, sigma_r2_inv):
    diag = [sigma_t2_inv] * 3 + [sigma_r2_inv] * 3
    return " ".join(f"{diag[i] if i == j else 0.0:g}" for i in range(6) for j in range(i, 6))


def write_kitti(path, poses):
    with open(path, "w") as f:
        for m in poses:
            f.write(" ".join(f"{m[i][j]:.9f}" for i in range(3) for j in range(4)) + "\n")


def read_g2o_vertices(path):
    out = {}
    with open(path) as f:
        for line in f:
            t = line.split()
            if t and t[0] == "VERTEX_SE3:QUAT":
                x, y, z, qx, qy, qz, qw = (float(v) for v in t[2:9])
                r = rotation(qx, qy, qz, qw)
                out[int(t[1])] = [r[0] + [x], r[1] + [y], r[2] + [z], [0.0, 0.0, 0.0, 1.0]]
    return out


def ate(build, gt_path, est_path, work):
    js = os.path.join(work, "eval.json")
    subprocess.run([os.path.join(build, "examples", "semlio_eval"), "--gt", gt_path, "--est", est_path, "--json", js],
                   check=True, stdout=subprocess.DEVNULL)
    with open(js) as f:
        return json.load(f)["ate"]["rmse_m"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--run", required=True, help="semlio_kitti --loop on output directory")
    ap.add_argument("--gt", required=True, help="ground-truth poses, one per input frame")
    ap.add_argument("--build", default="build", help="build directory with semlio_pgo and semlio_eval")
    ap.add_argument("--odometry-sigma-m", type=float, default=1.3e-3, help="odometry edge sigma, translation [m]")
    ap.add_argument("--odometry-sigma-rad", type=float, default=1.4e-5, help="odometry edge sigma, rotation [rad]")
    args = ap.parse_args()

    for name in ("poses_odom.txt", "poses.txt", "keyframes.txt", "report.json"):
        if not os.path.isfile(os.path.join(args.run, name)):
            sys.exit(f"{os.path.join(args.run, name)}: missing (expected a semlio_kitti --loop on output directory)")
    if not os.path.isfile(args.gt):
        sys.exit(f"{args.gt}: missing ground-truth pose file")
    gt = read_kitti_poses(args.gt)
    odom = read_kitti_poses(os.path.join(args.run, "poses_odom.txt"))
    optimised = read_kitti_poses(os.path.join(args.run, "poses.txt"))
    with open(os.path.join(args.run, "keyframes.txt")) as f:
        keyframes = [int(line.split()[0]) for line in f if line.strip() and not line.startswith("#")]
    with open(os.path.join(args.run, "report.json")) as f:
        report = json.load(f)
    if "loop" not in report or "loops" not in report["loop"]:
        sys.exit(f"{args.run}/report.json has no loop section: run semlio_kitti with --loop on")
    loops = [(l["from_frame"], l["to_frame"]) for l in report["loop"]["loops"]]
    if len(odom) != len(gt) or len(optimised) != len(gt):
        sys.exit(f"poses_odom.txt / poses.txt have {len(odom)} / {len(optimised)} poses, the ground truth "
                 f"{len(gt)}: pass the matching --gt")
    if not loops:
        sys.exit("the run accepted no loops: nothing to compare")
    node = {frame: k for k, frame in enumerate(keyframes)}
    if any(f < 0 or f >= len(gt) for f in keyframes) or any(a not in node or b not in node for a, b in loops):
        sys.exit(f"{args.run}: keyframes.txt and report.json's loops do not match (a loop frame is not a keyframe)")

    with tempfile.TemporaryDirectory() as work:
        graph = os.path.join(work, "oracle.g2o")
        with open(graph, "w") as f:
            for k, frame in enumerate(keyframes):
                f.write(f"VERTEX_SE3:QUAT {k} {g2o_pose(odom[frame])}\n")
            f.write("FIX 0\n")
            wt = 1.0 / args.odometry_sigma_m ** 2
            wr = 1.0 / args.odometry_sigma_rad ** 2
            odometry_information = g2o_information(wt, wr)
            for k in range(1, len(keyframes)):
                z = compose(inverse(odom[keyframes[k - 1]]), odom[keyframes[k]])
                f.write(f"EDGE_SE3:QUAT {k - 1} {k} {g2o_pose(z)} {odometry_information}\n")
            loop_information = g2o_information(100.0 * wt, 100.0 * wr)
            for a, b in loops:
                z = compose(inverse(gt[a]), gt[b])
                f.write(f"EDGE_SE3:QUAT {node[a]} {node[b]} {g2o_pose(z)} {loop_information}\n")
        solved = os.path.join(work, "solved.g2o")
        subprocess.run([os.path.join(args.build, "examples", "semlio_pgo"), graph, "--out", solved,
                        "--max-iterations", "50"], check=True, stdout=subprocess.DEVNULL)
        vertices = read_g2o_vertices(solved)

        write_kitti(os.path.join(work, "gt.txt"), [gt[f] for f in keyframes])
        write_kitti(os.path.join(work, "odom.txt"), [odom[f] for f in keyframes])
        write_kitti(os.path.join(work, "run.txt"), [optimised[f] for f in keyframes])
        write_kitti(os.path.join(work, "oracle.txt"), [vertices[k] for k in range(len(keyframes))])
        gt_kf = os.path.join(work, "gt.txt")
        a_odom = ate(args.build, gt_kf, os.path.join(work, "odom.txt"), work)
        a_run = ate(args.build, gt_kf, os.path.join(work, "run.txt"), work)
        a_oracle = ate(args.build, gt_kf, os.path.join(work, "oracle.txt"), work)

    print(f"keyframes {len(keyframes)}, loops {len(loops)} (oracle: measured from the ground truth)")
    print(f"keyframe ATE  odometry {a_odom:.4f} m | run's back end {a_run:.4f} m (ratio {a_run / a_odom:.3f})"
          f" | oracle loops {a_oracle:.4f} m (ratio {a_oracle / a_odom:.3f})")


if __name__ == "__main__":
    main()
