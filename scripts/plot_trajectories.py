#!/usr/bin/python3
"""Top-view plot of KITTI-format trajectories (3x4 row-major per line).

usage: plot_trajectories.py OUT.png --gt GT.txt NAME=EST.txt [NAME=EST.txt ...]
       [--frame camera|lidar] [--title TEXT]

Camera-frame poses (KITTI convention) are drawn as x (right) vs z (forward);
lidar-frame poses as x (forward) vs y (left). Needs python3-matplotlib.
"""
import argparse

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from kitti_poses import read_kitti_poses  # noqa: E402


def positions(path):
    poses = read_kitti_poses(path)
    return [T[0][3] for T in poses], [T[1][3] for T in poses], [T[2][3] for T in poses]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("estimates", nargs="+", help="NAME=PATH")
    ap.add_argument("--gt")
    ap.add_argument("--frame", choices=["camera", "lidar"], default="camera")
    ap.add_argument("--title", default="")
    a = ap.parse_args()

    fig, ax = plt.subplots(figsize=(8, 8))
    def draw(path, label, **kw):
        x, y, z = positions(path)
        if a.frame == "camera":
            ax.plot(x, z, label=label, **kw)
        else:
            ax.plot(x, y, label=label, **kw)
    if a.gt:
        draw(a.gt, "ground truth", color="black", linewidth=2.0)
    for item in a.estimates:
        name, _, path = item.partition("=")
        draw(path, name, linewidth=1.2)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("z [m]" if a.frame == "camera" else "y [m]")
    ax.set_title(a.title or "trajectories (top view)")
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(a.out, dpi=110)


if __name__ == "__main__":
    main()
