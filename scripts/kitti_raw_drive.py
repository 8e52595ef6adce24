#!/usr/bin/python3
"""Lays a KITTI raw drive, as published, out as a KITTI odometry sequence
semlio_kitti reads, with the drive's GNSS/INS (OXTS) trajectory as poses.txt.

usage: kitti_raw_drive.py DRIVE_DIR CALIB_DIR OUT_DIR [--frames N]

DRIVE_DIR is e.g. 2011_09_26_drive_0009_sync (velodyne_points/data/*.bin,
velodyne_points/timestamps.txt, oxts/data/*.txt); CALIB_DIR holds the day's
calib_imu_to_velo.txt. OUT_DIR gets velodyne/NNNNNN.bin (symbolic links to
the scans), times.txt (sweep middle, seconds from the first sweep) and
poses.txt: T_velo0_velo_i in the lidar frame (no calib.txt is written, so
semlio_kitti evaluates in the lidar frame too). OXTS poses follow the KITTI
raw devkit (convertOxtsToPose: Mercator with the first latitude's scale,
R = Rz(yaw) Ry(pitch) Rx(roll)), T_world_velo = T_world_imu * inv(T_velo_imu).
The OXTS positions are GNSS-grade (about 0.5 m without RTK): a reference for
drift over tens of metres, not a centimetre ground truth. Sweeps whose
timestamp line is blank (the recorder dropped them) end the sequence there.
Plain Python, no third-party imports.
"""
import argparse
import datetime
import math
import os
import sys


def matmul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


def inverse(t):
    r = [[t[j][i] for j in range(3)] for i in range(3)]  # R^T
    p = [-sum(r[i][k] * t[k][3] for k in range(3)) for i in range(3)]
    return [r[0] + [p[0]], r[1] + [p[1]], r[2] + [p[2]], [0.0, 0.0, 0.0, 1.0]]


def oxts_pose(fields, scale):
    lat, lon, alt, roll, pitch, yaw = (float(v) for v in fields[:6])
    er = 6378137.0
    tx = scale * lon * math.pi * er / 180.0
    ty = scale * er * math.log(math.tan((90.0 + lat) * math.pi / 360.0))
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    rx = [[1, 0, 0], [0, cr, -sr], [0, sr, cr]]
    ry = [[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]]
    rz = [[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]]
    m3 = lambda a, b: [[sum(a[i][k] * b[k][j] for k in range(3)) for j in range(3)] for i in range(3)]  # noqa: E731
    r = m3(rz, m3(ry, rx))
    return [r[0] + [tx], r[1] + [ty], r[2] + [alt], [0.0, 0.0, 0.0, 1.0]]


def read_calib(path):
    vals = {}
    with open(path) as f:
        for line in f:
            if ":" in line:
                k, v = line.split(":", 1)
                vals[k.strip()] = v.split()
    try:
        r = [float(x) for x in vals["R"]]
        t = [float(x) for x in vals["T"]]
    except (KeyError, ValueError):
        sys.exit(f"{path}: expected 'R:' (9 numbers) and 'T:' (3 numbers)")
    if len(r) != 9 or len(t) != 3:
        sys.exit(f"{path}: expected 'R:' (9 numbers) and 'T:' (3 numbers)")
    return [r[0:3] + [t[0]], r[3:6] + [t[1]], r[6:9] + [t[2]], [0.0, 0.0, 0.0, 1.0]]


def parse_stamp(text, path, n):
    try:
        day, clock = text.split()
        hms, frac = clock.split(".")
        base = datetime.datetime.strptime(day + " " + hms, "%Y-%m-%d %H:%M:%S")
    except ValueError:
        sys.exit(f"{path}:{n}: not a KITTI raw timestamp: '{text}'")
    return base.timestamp() + float("0." + frac)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("drive")
    ap.add_argument("calib")
    ap.add_argument("out")
    ap.add_argument("--frames", type=int, default=0, help="at most this many sweeps (0 = all present)")
    a = ap.parse_args()

    T_velo_imu = read_calib(os.path.join(a.calib, "calib_imu_to_velo.txt"))
    T_imu_velo = inverse(T_velo_imu)
    scans = os.path.join(a.drive, "velodyne_points", "data")
    stamps_path = os.path.join(a.drive, "velodyne_points", "timestamps.txt")
    with open(stamps_path) as f:
        stamp_lines = f.read().splitlines()
    stamps = []
    for n, line in enumerate(stamp_lines, 1):
        bin_path = os.path.join(scans, f"{n - 1:010d}.bin")
        oxts_path = os.path.join(a.drive, "oxts", "data", f"{n - 1:010d}.txt")
        if not line.strip() or not os.path.exists(bin_path) or not os.path.exists(oxts_path):
            break
        stamps.append(parse_stamp(line.strip(), stamps_path, n))
        if a.frames and len(stamps) == a.frames:
            break
    if len(stamps) < 2:
        sys.exit(f"{a.drive}: fewer than 2 sweeps with scan, OXTS packet and timestamp")

    os.makedirs(os.path.join(a.out, "velodyne"), exist_ok=True)
    poses = []
    scale = None
    for i in range(len(stamps)):
        with open(os.path.join(a.drive, "oxts", "data", f"{i:010d}.txt")) as f:
            fields = f.read().split()
        if len(fields) < 6:
            sys.exit(f"{a.drive}/oxts/data/{i:010d}.txt: expected 30 numbers")
        if scale is None:
            scale = math.cos(float(fields[0]) * math.pi / 180.0)
        poses.append(matmul(oxts_pose(fields, scale), T_imu_velo))  # T_world_velo
        link = os.path.join(a.out, "velodyne", f"{i:06d}.bin")
        if os.path.lexists(link):
            os.remove(link)
        os.symlink(os.path.abspath(os.path.join(scans, f"{i:010d}.bin")), link)
    first = inverse(poses[0])
    with open(os.path.join(a.out, "poses.txt"), "w") as f:
        for p in poses:
            rel = matmul(first, p)
            f.write(" ".join(f"{rel[r][c]:.9e}" for r in range(3) for c in range(4)) + "\n")
    with open(os.path.join(a.out, "times.txt"), "w") as f:
        for s in stamps:
            f.write(f"{s - stamps[0]:.6e}\n")
    print(f"{a.out}: {len(stamps)} sweeps, OXTS reference in the lidar frame")


if __name__ == "__main__":
    main()
