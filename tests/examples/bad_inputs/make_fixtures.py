#!/usr/bin/env python3
"""Writes the small bad input files of tests/examples/bad_inputs.tsv into this
folder (deterministic; the output is committed). Run: python3 make_fixtures.py"""
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))


def put(name, data):
    if isinstance(data, str):
        data = data.encode()
    with open(os.path.join(HERE, name), "wb") as f:
        f.write(data)


nan = float("nan")
inf = float("inf")
pt = struct.pack("<4f", 1.5, -2.0, 0.25, 0.5)
# KITTI .bin
put("empty.bin", b"")
put("odd.bin", b"0123456789")
put("all_nan.bin", struct.pack("<4f", nan, 1, 2, 0) + struct.pack("<4f", 1, inf, 2, 0))
put("all_zero.bin", struct.pack("<4f", 0, 0, 0, 1) * 3)
put("one_point.bin", pt)
put("three_points.bin", pt * 3)
put("short.label", b"\x01\x00")
put("two.label", struct.pack("<2I", 40, 44))
# PCD
H = ("VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {n}\nHEIGHT 1\n"
     "VIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA {d}\n")
put("count_overflow_ascii.pcd", H.replace("FIELDS x y z", "FIELDS x y z pad").replace("SIZE 4 4 4", "SIZE 4 4 4 4")
    .replace("TYPE F F F", "TYPE F F F F").replace("COUNT 1 1 1", "COUNT 1 1 1 18446744073709551615")
    .format(n=1, d="ascii") + "1 2\n")
put("count_overflow_binary.pcd", H.replace("FIELDS x y z", "FIELDS pad x y z").replace("SIZE 4 4 4", "SIZE 4 4 4 4")
    .replace("TYPE F F F", "TYPE U F F F").replace("COUNT 1 1 1", "COUNT 4611686018427387903 1 1 1")
    .format(n=1, d="binary").encode() + struct.pack("<2f", 1, 2))
put("points_lie.pcd", H.format(n=9, d="binary").encode() + struct.pack("<3f", 1, 2, 3) * 3)
put("compressed.pcd", H.format(n=0, d="binary_compressed"))
put("empty.pcd", b"")
put("not_a_pcd.pcd", "hello world\n")
put("bad_version.pcd", H.format(n=0, d="ascii").replace("VERSION 0.7", "VERSION 9.1"))
put("all_nan.pcd", H.format(n=2, d="ascii") + "nan 1 2\n0 0 0\n")
put("ascii_text_value.pcd", H.format(n=1, d="ascii") + "1 two 3\n")
put("width_overflow.pcd", H.format(n=0, d="ascii").replace("WIDTH 0", "WIDTH 4294967296")
    .replace("HEIGHT 1", "HEIGHT 4294967296"))
# PLY
P = "ply\nformat {f} 1.0\nelement vertex {n}\nproperty float x\nproperty float y\nproperty float z\nend_header\n"
put("vertex_lie.ply", P.format(f="binary_little_endian", n=2).encode() + struct.pack("<3f", 1, 2, 3) * 3)
put("truncated.ply", P.format(f="binary_little_endian", n=2).encode() + struct.pack("<3f", 1, 2, 3))
put("not_a_ply.ply", "plx\n")
put("list_vertex.ply", "ply\nformat ascii 1.0\nelement vertex 1\nproperty list uchar float x\nend_header\n1 1\n")
put("huge_count.ply", P.format(f="binary_little_endian", n=18446744073709551615))
put("ascii_lie.ply", P.format(f="ascii", n=1) + "1 2 3\n4 5 6\n")
put("all_zero.ply", P.format(f="ascii", n=2) + "0 0 0\n0 0 0\n")
# Poses, times, calib
I = "1 0 0 0 0 1 0 0 0 0 1 0\n"
put("poses_ok3.txt", I + "1 0 0 1 0 1 0 0 0 0 1 0\n" + "1 0 0 2 0 1 0 0 0 0 1 0\n")
put("poses_nan.txt", I + "1 0 0 nan 0 1 0 0 0 0 1 0\n")
put("poses_scale.txt", I + "2 0 0 0 0 1 0 0 0 0 1 0\n")
put("poses_11.txt", "1 0 0 0 0 1 0 0 0 0 1\n")
put("poses_text.txt", "one 0 0 0 0 1 0 0 0 0 1 0\n")
put("poses_empty.txt", "")
put("poses_huge.txt", I + "1 0 0 1e308 0 1 0 1e308 0 0 1 1e308\n" + "1 0 0 -1e308 0 1 0 -1e308 0 0 1 -1e308\n")
put("poses_blank_between.txt", I + "\n" + I)
put("tum_badq.tum", "0 0 0 0 0 0 0 2\n")
put("tum_back.tum", "1 0 0 0 0 0 0 1\n0 0 0 0 0 0 0 1\n")
put("tum_ok3.tum", "0 0 0 0 0 0 0 1\n0.1 1 0 0 0 0 0 1\n0.2 2 0 0 0 0 0 1\n")
put("times_ok3.txt", "0\n0.1\n0.2\n")
put("times_back.txt", "0\n0.2\n0.1\n")
put("times_nan.txt", "0\nnan\n")
put("times_two.txt", "0\n0.1\n")
put("calib_no_tr.txt", "P0: 1 0 0 0 0 1 0 0 0 0 1 0\n")
put("calib_bad_tr.txt", "Tr: 1 0 0 0 0 1 0 0 0 0 1\n")
put("subset_bad.txt", "0\nx\n")
put("subset_range.txt", "0\n7\n")
# g2o
V = "VERTEX_SE3:QUAT {i} {x} 0 0 0 0 0 1\n"
E = "EDGE_SE3:QUAT 0 1 1 0 0 0 0 0 1 " + " ".join(["1 0 0 0 0 0", "1 0 0 0 0", "1 0 0 0", "1 0 0", "1 0", "1"]) + "\n"
put("empty.g2o", "")
put("other_format.g2o", H.format(n=0, d="ascii"))
put("only_vertices.g2o", V.format(i=0, x=0) + V.format(i=1, x=1))
put("only_comments.g2o", "# nothing\n\n")
put("bad_quat.g2o", "VERTEX_SE3:QUAT 0 0 0 0 0 0 0 2\n")
put("unknown_vertex.g2o", V.format(i=0, x=0) + E.replace("EDGE_SE3:QUAT 0 1", "EDGE_SE3:QUAT 0 5"))
put("dup_vertex.g2o", V.format(i=0, x=0) + V.format(i=0, x=1))
put("mixed.g2o", V.format(i=0, x=0) + "VERTEX_SE2 1 0 0 0\n")
put("nan_vertex.g2o", V.format(i=0, x="nan"))
put("short_edge.g2o", V.format(i=0, x=0) + V.format(i=1, x=1) + "EDGE_SE3:QUAT 0 1 1 0 0\n")
put("text_id.g2o", "VERTEX_SE2 zero 0 0 0\n")
put("ok_3d.g2o", V.format(i=0, x=0) + V.format(i=1, x=1) + E)
put("ok_with_unknown.g2o", V.format(i=0, x=0) + V.format(i=1, x=1) + E + "SOMETHING_ELSE 1 2 3\n")
