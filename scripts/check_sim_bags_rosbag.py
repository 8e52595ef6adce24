#!/usr/bin/python3
"""Checks a ROS 1 bag written by semlio_simulate --bag with Debian's rosbag
(the reference reader) against the KITTI-layout drive of the same run.

usage: /usr/bin/python3 scripts/check_sim_bags_rosbag.py BAG DRIVE_DIR SENSOR FIELDS
  FIELDS: ring,time | ring | time | none (what semlio_simulate was given)

Independent references: the cloud's x y z intensity must equal the drive's
velodyne/*.bin bit for bit, the IMU its oxts/ records; ring and time are
checked against the sensor's beam table (typed in below from the datasheets,
not taken from the C++) and the clockwise spin (sweep starts facing
backwards). Exits 1 on the first class of mismatch, printing what differs.
"""
import math
import os
import sys

import numpy as np
import genpy.dynamic
import rosbag
from sensor_msgs.msg import Imu, PointCloud2

EPOCH_S = 1317643200.0  # KittiWriterConfig::epoch_s (2011-10-03 12:00:00 UTC)
PERIOD_S = 0.1          # every simulated sensor spins at 10 Hz


def elevations_deg(sensor):
    """Beam elevations, ring 0 lowest, from the datasheets / user manuals."""
    if sensor == "vlp16":
        return [-15.0 + 2.0 * r for r in range(16)]
    if sensor == "vlp32c":
        return sorted([-25, -1, -1.667, -15.639, -11.31, 0, -0.667, -8.843, -7.254, 0.333, -0.333, -6.148,
                       -5.333, 1.333, 0.667, -4, -4.667, 1.667, 1, -3.667, -3.333, 3.333, 2.333, -2.667,
                       -3, 7, 4.667, -2.333, -2, 15, 10.333, -1.333])  # VLP-32C manual, by laser id
    if sensor == "hdl32e":
        return [-30.67 + r * 4.0 / 3.0 for r in range(32)]
    if sensor == "os1-64":
        return [-22.5 + 45.0 * r / 63 for r in range(64)]
    if sensor == "os0-128":
        return [-45.0 + 90.0 * r / 127 for r in range(128)]
    if sensor == "hdl64e":  # KITTI's two blocks
        return [-24.9 + (-8.83 + 24.9) * r / 31 for r in range(32)] + [-8.33 + (2.0 + 8.33) * r / 31 for r in range(32)]
    raise SystemExit("unknown sensor " + sensor)


FAILURES = []


def fail(msg):
    FAILURES.append(msg)
    print("MISMATCH: " + msg)


def main():
    bag_path, drive, sensor, fields = sys.argv[1:5]
    want_ring = "ring" in fields.split(",")
    want_time = "time" in fields.split(",")
    ouster = sensor.startswith("os")
    table = np.radians(np.array(elevations_deg(sensor)))
    bag = rosbag.Bag(bag_path)

    # Connections: types, md5sums and definitions that genpy accepts.
    expected = {"/points": PointCloud2, "/imu/data": Imu}
    conns = {c.topic: c for c in bag._connections.values()}
    if set(conns) != set(expected):
        fail("topics %s, expected %s" % (sorted(conns), sorted(expected)))
    for topic, cls in expected.items():
        c = conns.get(topic)
        if c is None:
            continue
        if c.datatype != cls._type or c.md5sum != cls._md5sum:
            fail("%s: type %s md5 %s, expected %s %s" % (topic, c.datatype, c.md5sum, cls._type, cls._md5sum))
        generated = genpy.dynamic.generate_dynamic(c.datatype, c.msg_def)[c.datatype]
        if generated._md5sum != cls._md5sum:
            fail("%s: message_definition hashes to %s, expected %s" % (topic, generated._md5sum, cls._md5sum))

    bins = sorted(f for f in os.listdir(os.path.join(drive, "velodyne")) if f.endswith(".bin"))
    oxts_dir = os.path.join(drive, "oxts", "data")
    oxts = [np.array(open(os.path.join(oxts_dir, f)).read().split(), dtype=float) for f in sorted(os.listdir(oxts_dir))]

    clouds = 0
    imus = 0
    last_log = None
    for topic, msg, t in bag.read_messages():
        if last_log is not None and t < last_log:
            fail("log times go backwards at %s" % t)
        last_log = t
        if topic == "/imu/data":
            k = imus
            imus += 1
            if k >= len(oxts):
                fail("more IMU messages than oxts records (%d)" % len(oxts))
                continue
            stamp = msg.header.stamp.to_sec()
            if abs(stamp - (EPOCH_S + k / 100.0)) > 2e-6 or abs(t.to_sec() - stamp) > 2e-6:
                fail("IMU %d stamp %.9f log %.9f, expected %.9f" % (k, stamp, t.to_sec(), EPOCH_S + k / 100.0))
            acc = np.array([msg.linear_acceleration.x, msg.linear_acceleration.y, msg.linear_acceleration.z])
            gyr = np.array([msg.angular_velocity.x, msg.angular_velocity.y, msg.angular_velocity.z])
            if np.abs(acc - oxts[k][11:14]).max() > 1e-12 or np.abs(gyr - oxts[k][17:20]).max() > 1e-12:
                fail("IMU %d: accel %s gyro %s, oxts %s %s" % (k, acc, gyr, oxts[k][11:14], oxts[k][17:20]))
            if msg.orientation_covariance[0] != -1.0:
                fail("IMU %d: orientation_covariance[0] = %s, expected -1 (no orientation)" % (k, msg.orientation_covariance[0]))
            continue
        i = clouds
        clouds += 1
        if i >= len(bins):
            fail("more clouds than velodyne/*.bin files (%d)" % len(bins))
            continue
        stamp = msg.header.stamp.to_sec()
        if abs(stamp - (EPOCH_S + i * PERIOD_S)) > 2e-6 or abs(t.to_sec() - stamp - PERIOD_S) > 2e-6:
            fail("cloud %d stamp %.9f log %.9f, expected stamp %.9f logged a period later" % (i, stamp, t.to_sec(), EPOCH_S + i * PERIOD_S))
        names = [f.name for f in msg.fields]
        expect = ["x", "y", "z", "intensity"]
        if ouster:
            expect += (["t"] if want_time else []) + ["reflectivity"] + (["ring"] if want_ring else []) + ["ambient", "range"]
        else:
            expect += (["ring"] if want_ring else []) + (["time"] if want_time else [])
        if names != expect:
            fail("cloud %d fields %s, expected %s" % (i, names, expect))
            continue
        types = {1: "i1", 2: "u1", 3: "<i2", 4: "<u2", 5: "<i4", 6: "<u4", 7: "<f4", 8: "<f8"}
        dt = np.dtype({"names": names, "formats": [types[f.datatype] for f in msg.fields],
                       "offsets": [f.offset for f in msg.fields], "itemsize": msg.point_step})
        if msg.height != 1 or msg.row_step != msg.point_step * msg.width or len(msg.data) != msg.row_step:
            fail("cloud %d: height %d width %d row_step %d data %d" % (i, msg.height, msg.width, msg.row_step, len(msg.data)))
            continue
        pts = np.frombuffer(msg.data, dtype=dt, count=msg.width)
        ref = np.fromfile(os.path.join(drive, "velodyne", bins[i]), dtype="<f4").reshape(-1, 4)
        mine = np.stack([pts["x"], pts["y"], pts["z"], pts["intensity"]], axis=1)
        if mine.shape != ref.shape or not np.array_equal(mine.view("<u4"), ref.view("<u4")):
            fail("cloud %d: x y z intensity differ from %s (%s vs %s points)" % (i, bins[i], mine.shape, ref.shape))
            continue
        x = mine[:, 0].astype(float)
        y = mine[:, 1].astype(float)
        z = mine[:, 2].astype(float)
        if want_ring:
            ring = pts["ring"].astype(int)
            if ring.min() < 0 or ring.max() >= len(table):
                fail("cloud %d: ring outside [0, %d)" % (i, len(table)))
            else:
                el = np.arctan2(z, np.hypot(x, y))
                err = np.abs(el - table[ring]).max()
                if err > 1e-4:
                    fail("cloud %d: elevation differs from the beam table at its ring by %.2e rad" % (i, err))
        if want_time:
            t_pt = pts["t"].astype(float) * 1e-9 if ouster else pts["time"].astype(float)
            # Clockwise from azimuth +180 deg: t = period * ((pi - az) mod 2 pi) / 2 pi.
            az = np.arctan2(y, x)
            expect_t = PERIOD_S * np.mod(math.pi - az, 2 * math.pi) / (2 * math.pi)
            d = np.abs(t_pt - expect_t)
            d = np.minimum(d, PERIOD_S - d)  # the seam behind the car
            if t_pt.min() < 0 or t_pt.max() >= PERIOD_S or d.max() > 2e-6:
                fail("cloud %d: per-point time off the clockwise spin by up to %.2e s" % (i, d.max()))
    if clouds != len(bins):
        fail("%d clouds, %d velodyne/*.bin files" % (clouds, len(bins)))
    if imus != len(oxts):
        fail("%d IMU messages, %d oxts records" % (imus, len(oxts)))
    if FAILURES:
        print("rosbag check FAILED: %d mismatches" % len(FAILURES))
        return 1
    print("rosbag check passed: %s, %d clouds (%s layout, fields %s), %d IMU messages match the KITTI-layout drive"
          % (bag_path, clouds, "Ouster" if ouster else "Velodyne", fields, imus))
    return 0


if __name__ == "__main__":
    sys.exit(main())
