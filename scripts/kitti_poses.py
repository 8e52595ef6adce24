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


def pose_mul(a, b):
    """Product of two 4x4 matrices (lists of rows)."""
    return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


def pose_inv(a):
    """Inverse of a rigid 4x4 transform (lists of rows)."""
    r = [[a[j][i] for j in range(3)] for i in range(3)]
    t = [-sum(r[i][k] * a[k][3] for k in range(3)) for i in range(3)]
    return [r[0] + [t[0]], r[1] + [t[1]], r[2] + [t[2]], [0.0, 0.0, 0.0, 1.0]]
