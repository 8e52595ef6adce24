#!/usr/bin/env python3
"""Writes the seed corpus of the fuzz harnesses (tests/fuzz/corpus/<reader>/)
from small cuts of tests/data, plus a few hand-written edge cases. Run from
anywhere: python3 tests/fuzz/make_corpus.py. Deterministic; the output is
committed (a few KB per reader)."""
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))
DATA = os.path.join(HERE, "..", "data")
OUT = os.path.join(HERE, "corpus")


def put(reader, name, data):
    d = os.path.join(OUT, reader)
    os.makedirs(d, exist_ok=True)
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(d, name), "wb") as f:
        f.write(data)


def read(rel):
    with open(os.path.join(DATA, rel), "rb") as f:
        return f.read()


def lines(rel, n):
    return b"".join(read(rel).splitlines(keepends=True)[:n])


# KITTI .bin: 24 real points of 00/000000, the 50 SemanticKITTI points, and
# edge cases (a NaN point, a (0,0,0) point, a partial record).
velo = read("kitti/sequences/00/velodyne/000000.bin")
put("kitti_bin", "real_00_000000_24pts.bin", velo[: 24 * 16])
put("kitti_bin", "semantickitti_50pts.bin", read("kitti/semantickitti_subset/00/velodyne/000000.bin"))
put("kitti_bin", "nan_and_zero.bin", struct.pack("<4f", float("nan"), 1, 2, 3) + struct.pack("<4f", 0, 0, 0, 1)
    + velo[:16])
put("kitti_bin", "partial_record.bin", velo[:21])

# .label: the 50 real labels, and a short one.
labels = read("kitti/semantickitti_subset/00/labels/000000.label")
put("kitti_label", "semantickitti_50.label", labels)
put("kitti_label", "three.label", labels[:12])

# calib.txt: the real files.
put("kitti_calib", "calib_00.txt", read("kitti/sequences/00/calib.txt"))
put("kitti_calib", "calib_04-10.txt", read("kitti/calib/calib_04-10_Tr_RECONSTRUCTED.txt"))
put("kitti_calib", "tr_only.txt", "Tr: 1 0 0 0 0 1 0 0 0 0 1 0\n")

# times.txt and poses.
put("kitti_times", "times_00.txt", read("kitti/sequences/00/times.txt"))
put("kitti_times", "times_00_first20.txt", lines("kitti/times_00_first200.txt", 20))
put("kitti_times", "equal_and_blank.txt", "0\n0\n1e-300\n\n")
put("kitti_poses", "poses_00.txt", read("kitti/sequences/00/poses.txt"))
put("kitti_poses", "poses_04_first5.txt", lines("kitti/poses/04.txt", 5))

# TUM: the first KITTI 04 poses rewritten as TUM lines (stamp tx ty tz qx qy qz qw).
def quat(m):
    r = [[m[0], m[1], m[2]], [m[4], m[5], m[6]], [m[8], m[9], m[10]]]
    w = max(1e-12, (1 + r[0][0] + r[1][1] + r[2][2])) ** 0.5 / 2
    return ((r[2][1] - r[1][2]) / (4 * w), (r[0][2] - r[2][0]) / (4 * w), (r[1][0] - r[0][1]) / (4 * w), w)


tum = "# timestamp tx ty tz qx qy qz qw\n"
for i, line in enumerate(lines("kitti/poses/04.txt", 5).decode().splitlines()):
    m = [float(v) for v in line.split()]
    q = quat(m)
    tum += "%.6f %s %s %s %.9f %.9f %.9f %.9f\n" % (0.1 * i, m[3], m[7], m[11], *q)
put("tum", "poses_04_first5.tum", tum)
put("tum", "identity.tum", "0 0 0 0 0 0 0 1\n")

# PCD: the header of a real KITTI raw scan with its first 16 points, binary
# and ascii, and the real file's tail padding.
pcd = read("kitti_raw/snippet_22/0000000000.pcd")
end = pcd.index(b"DATA binary\n") + len(b"DATA binary\n")
header = pcd[:end].decode()
rec = 16  # x y z intensity float32
fields = {}
for l in header.splitlines():
    if l and not l.startswith("#"):
        fields[l.split()[0]] = l.split()[1:]
rec = sum(int(s) * int(c) for s, c in zip(fields["SIZE"], fields.get("COUNT", ["1"] * len(fields["SIZE"]))))


def with_points(h, n, data_kw):
    out = []
    for l in h.splitlines():
        k = l.split()[0] if l.split() else ""
        if k in ("WIDTH", "POINTS"):
            l = "%s %d" % (k, n)
        elif k == "DATA":
            l = "DATA " + data_kw
        out.append(l)
    return "\n".join(out) + "\n"


n = 16
payload = pcd[end : end + n * rec]
put("pcd", "kitti_raw_16pts_binary.pcd", with_points(header, n, "binary").encode() + payload)
asc = ""
for i in range(n):
    vals = []
    off = 0
    for s, t, c in zip(fields["SIZE"], fields["TYPE"], fields.get("COUNT", ["1"] * len(fields["SIZE"]))):
        for _ in range(int(c)):
            fmt = {("F", "4"): "<f", ("F", "8"): "<d", ("U", "1"): "<B", ("U", "2"): "<H", ("U", "4"): "<I",
                   ("I", "1"): "<b", ("I", "2"): "<h", ("I", "4"): "<i"}[(t, s)]
            vals.append(repr(struct.unpack_from(fmt, payload, i * rec + off)[0]))
            off += int(s)
    asc += " ".join(vals) + "\n"
put("pcd", "kitti_raw_16pts_ascii.pcd", with_points(header, n, "ascii") + asc)
put("pcd", "kitti_raw_4pts_padding.pcd", with_points(header, 4, "binary").encode() + payload[: 4 * rec]
    + b"\0" * 64)
put("pcd", "ring_time_label.pcd",
    "VERSION 0.7\nFIELDS x y z intensity ring time label\nSIZE 4 4 4 4 2 4 4\nTYPE F F F F U F U\n"
    "COUNT 1 1 1 1 1 1 1\nWIDTH 2\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA ascii\n"
    "1 2 3 0.5 7 0.01 40\n-4 5 6 1 63 0.09 655370\n")

# PLY: the real scan pair's header with its first 16 vertices, and an ascii
# file with a face element after the vertices.
ply = read("scan_pair/source.ply")
end = ply.index(b"end_header\n") + len(b"end_header\n")
h = ply[:end].decode().replace("element vertex 69792", "element vertex 16")
put("ply", "scan_pair_16pts_binary.ply", h.encode() + ply[end : end + 16 * 16])
verts = [struct.unpack_from("<4f", ply, end + 16 * i) for i in range(6)]
asc = "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\n" \
      "property float scalar_intensity\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n"
asc += "".join("%r %r %r %r\n" % v for v in verts) + "3 0 1 2\n"
put("ply", "scan_pair_6pts_ascii_face.ply", asc)
be = "ply\nformat binary_big_endian 1.0\nelement vertex 2\nproperty double x\nproperty double y\n" \
     "property double z\nproperty uint label\nproperty ushort ring\nproperty float time\nend_header\n"
put("ply", "big_endian_label_ring_time.ply", be.encode() + struct.pack(">dddIHf", 1, 2, 3, 40, 5, 0.01)
    + struct.pack(">dddIHf", -1, 0.5, 2, 65546, 6, 0.02))

# OXTS: timestamps.txt, then '|' before each data file (harness layout).
line = ("49.015003823272 8.4342971002335 116.43032836914 0.035752 0.00903 -1.0130890800029 "
        "-0.017141324727 0.008932893 -0.0038 -0.015 -0.0011 0.21 0.13 9.82 0.23 0.12 9.81 "
        "-0.017 0.0021 0.0031 -0.017 0.0022 0.003 0.49 0.02 4 10 4 4 0\n")
put("oxts", "two_records.txt", "2011-09-26 13:02:25.594360375\n2011-09-26 13:02:25.604340375\n|" + line + "|" + line)
put("oxts", "one_record.txt", "1970-01-01 00:00:00.0\n|" + line)

# g2o: the first vertices and the edges between them of a 3D and a 2D benchmark.
def g2o_cut(rel, nv):
    out = []
    for l in read(rel).decode().splitlines():
        t = l.split()
        if not t:
            continue
        if t[0].startswith("VERTEX") and int(t[1]) < nv:
            out.append(l)
        elif t[0].startswith("EDGE") and int(t[1]) < nv and int(t[2]) < nv:
            out.append(l)
    return "\n".join(out) + "\n"


put("g2o", "tinyGrid3D_first6.g2o", g2o_cut("posegraphs/tinyGrid3D.g2o", 6))
put("g2o", "M3500_first8.g2o", g2o_cut("posegraphs/M3500.g2o", 8))
put("g2o", "fix_and_comment.g2o", "# comment\nVERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 0\nFIX 0\n"
    "EDGE_SE2 0 1 1 0 0 1 0 0 1 0 1\nUNKNOWN_TAG 1 2 3\n")

# settings YAML: the keys of every section and the deskew section.
put("settings_yaml", "odometry.yaml", "odometry:\n  max_correction_m: 2.0\n  min_frame_interval_s: 0.1\n"
    "  min_features: 50\nsolver:\n  max_iterations: 30\n  levenberg_marquardt: true\n")
put("settings_yaml", "back_end.yaml", "slam:\n  loop_closure: true\n  loop_detector: scancontext\n"
    "scan_context:\n  rings: 20\n  max_distance: 0.2\ngraph:\n  huber_delta: 4\nsemantic_map:\n  leaf_size_m: 0.4\n")
put("settings_yaml", "deskew.yaml", "deskew:\n  mode: constant_velocity\n  sweep_period_s: 0.1\n"
    "  start_azimuth_deg: 180\n  direction: clockwise\n  target: middle\n")
put("settings_yaml", "flow.yaml", "{nearest: {k: 5, max_distance_m: 1.0}, normal: {keep: 5, candidates: 15}}\n")
put("settings_yaml", "null_key.yaml", "? :")

# KITTI raw calibration files and velodyne timestamps (drive 0009: lines
# 175-183 hold the recorder's blank lines for dropped sweeps).
RAW = "kitti_raw/2011_09_26/"
put("kitti_raw_calib", "calib_velo_to_cam.txt", read(RAW + "calib_velo_to_cam.txt"))
put("kitti_raw_calib", "calib_imu_to_velo.txt", read(RAW + "calib_imu_to_velo.txt"))
stamps = read(RAW + "2011_09_26_drive_0009_sync/velodyne_points/timestamps.txt").splitlines(keepends=True)
put("kitti_raw_stamps", "first8.txt", b"".join(stamps[:8]))
put("kitti_raw_stamps", "dropped_174-183.txt", b"".join(stamps[174:183]))

# Folder logic (harnesses_folders.hpp): parts separated by '|', name lists one
# name per line; an empty part is a file or folder that does not exist.
# scan_folder: names | times.txt | poses.txt
seq = "kitti/sequences/00/"
put("scan_folder", "kitti_bin_times_poses.txt",
    b"000002.bin\n000000.bin\n000001.bin\ntimes.txt\nposes.txt\ncalib.txt\n|" + lines(seq + "times.txt", 3) + b"|"
    + lines(seq + "poses.txt", 3))
put("scan_folder", "snippet_pcd_frame_numbers.txt", "\n".join(sorted(os.listdir(os.path.join(DATA, "kitti_raw/snippet_22")))) + "\n.hidden.pcd\nREADME\n")
put("scan_folder", "ply_natural_order_gap.txt", "scan_10.ply\nscan_9.ply\nscan_100.PLY\nmap.txt\n")
put("scan_folder", "seconds_names_tum.txt", "1317357625.123456.bin\n1317357625.2235.bin\n1317357625.0.bin\n||"
    "1317357625.0 0 0 0 0 0 0 1\n1317357625.123456 1 0 0 0 0 0 1\n1317357625.2235 2 0 0 0 0 0 1\n")
put("scan_folder", "nanosecond_names.txt", "1599131415123456789.pcd\n1599131415223456789.pcd\n1599131415023456789.pcd\n")
put("scan_folder", "mixed_formats.txt", "0.pcd\n1.ply\n")
put("scan_folder", "same_number.txt", "1.pcd\n01.pcd\n")
# kitti_raw_drive: timestamps.txt | timestamps_start.txt | velodyne_points/data names | oxts/timestamps.txt | oxts/data names
DRIVE = RAW + "2011_09_26_drive_0009_sync/"
mid = read(DRIVE + "velodyne_points/timestamps.txt").splitlines(keepends=True)
start = read(DRIVE + "velodyne_points/timestamps_start.txt").splitlines(keepends=True)
oxts = read(DRIVE + "oxts/timestamps.txt").splitlines(keepends=True)
bins = lambda ks: "".join("%010d.bin\n" % k for k in ks).encode()
txts = lambda ks: "".join("%010d.txt\n" % k for k in ks).encode()
put("kitti_raw_drive", "fewer_scans_than_oxts.txt",
    b"".join(mid[:6]) + b"|" + b"".join(start[:6]) + b"|" + bins(range(3)) + b"|" + b"".join(oxts[:6]) + b"|" + txts(range(6)))
put("kitti_raw_drive", "blank_lines_gap_no_start.txt",
    b"".join(mid[174:184]) + b"||" + bins([0, 1, 3, 9]))
put("kitti_raw_drive", "blank_lines_with_start.txt",
    b"".join(mid[176:184]) + b"|" + b"".join(start[176:184]) + b"|" + bins(range(8)) + b"|" + b"".join(oxts[176:184])
    + b"|" + txts([0, 2, 5]))
put("kitti_raw_drive", "scan_beyond_lines.txt", b"".join(mid[:2]) + b"||" + bins([0, 5]))
