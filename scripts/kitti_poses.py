"""KITTI-format poses (12 numbers per line: a 3x4 row-major matrix), shared
by the scripts that read trajectories (no third-party imports)."""
import sys


def read_kitti_poses(path):
    """4x4 matrices (lists of rows) of the poses in path; exits with file:line on a malformed line."""
    poses = []
    with open(path) as f:
        for n, line in enumerate(f, 1):
            v = line.split()
            if not v:
                continue
            if len(v) != 12:
                sys.exit(f"{path}:{n}: expected 12 numbers, got {len(v)}")
            m = [float(x) for x in v]
            poses.append([m[0:4], m[4:8], m[8:12], [0.0, 0.0, 0.0, 1.0]])
    return poses
