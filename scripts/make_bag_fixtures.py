#!/usr/bin/python3
"""Writes the ROS 1 bag fixtures of tests/data/bags/ with the ROS reference
implementation (Debian's python3-rosbag, python3-sensor-msgs, python3-roslz4).

Run with Debian's Python, which has those packages:

    /usr/bin/python3 scripts/make_bag_fixtures.py OXTS_DIR [OUT_DIR]

OXTS_DIR is the real KITTI raw OXTS folder
(/work/shared/data/kitti_raw/2011_09_26_drive_0009_sync/oxts/data); OUT_DIR
defaults to tests/data/bags. The KITTI scans come from
tests/data/kitti_raw/snippet_22/*.pcd (copied bit-exactly into the clouds).

Files written (see tests/data/bags/README.md for the value formulas that the
C++ tests recompute independently):
  kitti3_lz4.bag             3 real KITTI raw scans + 30 real OXTS IMU messages, lz4 chunks
  kitti3_oxts.txt            the 30 OXTS lines (KITTI raw 2011_09_26_drive_0009_sync, frames 0-29)
  quirks_none.bag            synthetic clouds in the Velodyne / Ouster / Hesai / Robosense /
                             Livox layouts, a big-endian float64 cloud and IMU messages,
                             written out of log-time order, small uncompressed chunks
  quirks_bz2.bag             the same messages, bz2 chunks
  quirks_lz4_unindexed.bag   the same messages, lz4 chunks, with the index section cut off
                             and index_pos zeroed (an interrupted recording)
  quirks_expected.txt        "log_time_ns topic" per message in the order a reader must
                             return them (stable sort of the write order by log time)
"""

import math
import os
import random
import struct
import sys

try:
    import genpy
    import rosbag
    from sensor_msgs.msg import Imu, PointCloud2, PointField
except ImportError:
    # The ROS 1 reference implementation comes from Debian; install it once, then run again.
    import subprocess
    subprocess.check_call([os.path.join(os.path.dirname(os.path.abspath(__file__)), 'install_deps.sh'),
                           'python3-rosbag', 'python3-sensor-msgs', 'python3-roslz4', 'python3-genpy'])
    os.execv('/usr/bin/python3', ['/usr/bin/python3'] + sys.argv)

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(HERE)

F32, F64 = PointField.FLOAT32, PointField.FLOAT64
U8, U16, U32 = PointField.UINT8, PointField.UINT16, PointField.UINT32
FMT = {PointField.INT8: 'b', U8: 'B', PointField.INT16: 'h', U16: 'H',
       PointField.INT32: 'i', U32: 'I', F32: 'f', F64: 'd'}


# ---------------------------------------------------------------- KITTI bag
def read_pcd_binary(path):
    """Returns (width, payload bytes) of a PCD v0.7 binary x y z intensity float32 file."""
    with open(path, 'rb') as f:
        blob = f.read()
    pos = 0
    width = height = None
    while True:
        end = blob.index(b'\n', pos)
        line = blob[pos:end].decode('ascii').strip()
        pos = end + 1
        key = line.split()[0] if line else ''
        if key == 'FIELDS' and line.split()[1:] != ['x', 'y', 'z', 'intensity']:
            raise SystemExit(path + ': expected FIELDS x y z intensity')
        if key == 'TYPE' and line.split()[1:] != ['F'] * 4:
            raise SystemExit(path + ': expected float fields')
        if key == 'WIDTH':
            width = int(line.split()[1])
        if key == 'HEIGHT':
            height = int(line.split()[1])
        if key == 'DATA':
            if line.split()[1] != 'binary':
                raise SystemExit(path + ': expected DATA binary')
            break
    n = width * height
    payload = blob[pos:pos + 16 * n]
    if len(payload) != 16 * n:
        raise SystemExit(path + ': payload truncated')
    return n, payload  # trailing padding bytes after the payload are dropped


def imu_from_oxts(path, stamp):
    """sensor_msgs/Imu from one KITTI raw OXTS line (columns per dataformat.txt)."""
    with open(path) as f:
        v = [float(t) for t in f.read().split()]
    roll, pitch, yaw = v[3], v[4], v[5]
    msg = Imu()
    msg.header.stamp = stamp
    msg.header.frame_id = 'imu_link'
    # Orientation from roll/pitch/yaw (R = Rz(yaw) Ry(pitch) Rx(roll)).
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    msg.orientation.w = cr * cp * cy + sr * sp * sy
    msg.orientation.x = sr * cp * cy - cr * sp * sy
    msg.orientation.y = cr * sp * cy + sr * cp * sy
    msg.orientation.z = cr * cp * sy - sr * sp * cy
    msg.linear_acceleration.x, msg.linear_acceleration.y, msg.linear_acceleration.z = v[14], v[15], v[16]  # af al au
    msg.angular_velocity.x, msg.angular_velocity.y, msg.angular_velocity.z = v[20], v[21], v[22]  # wf wl wu
    msg.orientation_covariance = [0.0] * 9
    msg.angular_velocity_covariance = [0.0] * 9
    msg.linear_acceleration_covariance = [0.0] * 9
    return msg


def write_kitti_bag(oxts_dir, out_dir):
    scans = []
    for i in range(3):
        n, payload = read_pcd_binary(os.path.join(REPO, 'tests/data/kitti_raw/snippet_22/%010d.pcd' % i))
        msg = PointCloud2()
        msg.header.seq = i
        msg.header.stamp = genpy.Time(1317357625, i * 100000000)
        msg.header.frame_id = 'velo_link'
        msg.height, msg.width = 1, n
        msg.fields = [PointField(name, 4 * k, F32, 1) for k, name in enumerate(['x', 'y', 'z', 'intensity'])]
        msg.is_bigendian = False
        msg.point_step, msg.row_step = 16, 16 * n
        msg.data = payload
        msg.is_dense = True
        scans.append((msg.header.stamp, '/kitti/velo/pointcloud', msg))
    # 30 IMU messages at 10 Hz from 1.0 s before the first scan, OXTS lines 0..29.
    imus = []
    for k in range(30):
        stamp = genpy.Time(1317357624, 0) + genpy.Duration(0, k * 100000000)
        imus.append((stamp, '/kitti/oxts/imu', imu_from_oxts(os.path.join(oxts_dir, '%010d.txt' % k), stamp)))
    # The 30 OXTS lines themselves, so the test can check the IMU values against their source.
    with open(os.path.join(out_dir, 'kitti3_oxts.txt'), 'w') as f:
        for k in range(30):
            with open(os.path.join(oxts_dir, '%010d.txt' % k)) as src:
                f.write(src.read().strip() + '\n')
    # Scans and IMU messages sharing a stamp: the IMU message first (sorted is stable).
    records = sorted(imus + scans, key=lambda r: r[0])
    with rosbag.Bag(os.path.join(out_dir, 'kitti3_lz4.bag'), 'w', compression='lz4') as bag:
        for stamp, topic, msg in records:
            bag.write(topic, msg, t=stamp)


# ---------------------------------------------------------------- quirk bags
BASE_SEC = 1700000000


def header_stamp(k):
    """Header stamp of cloud k of a topic: BASE_SEC + k * 0.1 s."""
    return genpy.Time(BASE_SEC, k * 100000000)


def point_values(j, k):
    """The formula the C++ test recomputes: x, y, z, intensity, ring-source of point j of cloud k."""
    x = 1.0 + 0.25 * j
    y = -0.5 * j + k
    z = 0.125 * (j % 64) - 2.0
    return x, y, z, float(j % 256)


def dropped_kind(j):
    """Non-dense clouds: j % 17 == 5 -> a NaN coordinate, j % 23 == 7 -> (0,0,0)."""
    if j % 17 == 5:
        return 'nan'
    if j % 23 == 7:
        return 'zero'
    return None


def make_cloud(k, layout):
    """Builds cloud k of one layout (a dict: fields, point_step, height, width, ...)."""
    height, width = layout.get('height', 1), layout['width']
    point_step = layout['point_step']
    row_pad = layout.get('row_pad', 0)
    row_step = width * point_step + row_pad
    big = layout.get('big', False)
    endian = '>' if big else '<'
    data = bytearray(b'\xab' * (height * row_step))  # padding bytes are never zero: a reader must skip them
    stamp = header_stamp(k) + genpy.Duration(0, layout.get('stamp_offset_ns', 0))
    for r in range(height):
        for c in range(width):
            j = r * width + c
            x, y, z, inten = point_values(j, k)
            if layout.get('dense', True) is False:
                kind = dropped_kind(j)
                if kind == 'nan':
                    # NaN in a different coordinate each time
                    x, y, z = [(float('nan') if a == j % 3 else v) for a, v in enumerate((x, y, z))]
                elif kind == 'zero':
                    x, y, z = 0.0, 0.0, 0.0
            ring = r if height > 1 else j % layout.get('rings', 16)
            values = {'x': x, 'y': y, 'z': z, 'intensity': inten, 'ring': ring}
            values.update(layout['time'](j, k))
            base = r * row_step + c * point_step
            for name, off, dt in layout['fields']:
                v = values.get(name, 0)
                if FMT[dt] in 'fd':
                    v = float(v)
                else:
                    v = int(v)
                struct.pack_into(endian + FMT[dt], data, base + off, v)
    msg = PointCloud2()
    msg.header.seq = k
    msg.header.stamp = stamp
    msg.header.frame_id = layout['frame']
    msg.height, msg.width = height, width
    msg.fields = [PointField(name, off, dt, 1) for name, off, dt in layout['fields']]
    msg.is_bigendian = big
    msg.point_step, msg.row_step = point_step, row_step
    msg.data = bytes(data)
    msg.is_dense = layout.get('dense', True)
    return msg


def abs_time_s(j, k, shift_s=0.0):
    """Absolute per-point time [s] as float64: the same double operations the test repeats."""
    return (float(BASE_SEC) + float(k * 100000000) / 1e9) + shift_s + j * 1e-5


# Field layouts of the drivers (names, offsets, datatypes as the drivers publish them):
LAYOUTS = {
    # velodyne_pointcloud PointXYZIRT: x y z (+4 pad) intensity f32, ring u16, time f32 s
    # relative to the header stamp (negative: the stamp is the sweep's end), point_step 32.
    '/velodyne_points': dict(
        frame='velodyne', width=160, point_step=32,
        fields=[('x', 0, F32), ('y', 4, F32), ('z', 8, F32), ('intensity', 16, F32),
                ('ring', 20, U16), ('time', 24, F32)],
        time=lambda j, k: {'time': (j - 160) * 1e-5}),
    # ouster_ros Point (older, ring u8): organised 8 x 40, t u32 ns, row_step padded by 16
    # bytes, not dense: NaN and (0,0,0) points.
    '/ouster/points': dict(
        frame='os_sensor', height=8, width=40, point_step=48, row_pad=16, dense=False,
        fields=[('x', 0, F32), ('y', 4, F32), ('z', 8, F32), ('intensity', 16, F32), ('t', 20, U32),
                ('reflectivity', 24, U16), ('ring', 26, U8), ('ambient', 28, U16), ('range', 32, U32)],
        time=lambda j, k: {'t': j * 10000, 'reflectivity': 7, 'ambient': 9, 'range': 1234}),
    # HesaiLidar_General_ROS PointXYZIT: intensity f32, timestamp f64 absolute s, ring u16;
    # header stamp 0.1 s after the first point (the sweep's end).
    '/hesai/pandar': dict(
        frame='PandarXT-32', width=160, point_step=48, stamp_offset_ns=100000000,
        fields=[('x', 0, F32), ('y', 4, F32), ('z', 8, F32), ('intensity', 16, F32),
                ('timestamp', 24, F64), ('ring', 32, U16)],
        time=lambda j, k: {'timestamp': abs_time_s(j, k)}),
    # rslidar_sdk PointXYZIRT: intensity u8, ring u16, timestamp f64 absolute s.
    '/rslidar_points': dict(
        frame='rslidar', width=160, point_step=32,
        fields=[('x', 0, F32), ('y', 4, F32), ('z', 8, F32), ('intensity', 16, U8),
                ('ring', 18, U16), ('timestamp', 24, F64)],
        time=lambda j, k: {'timestamp': abs_time_s(j, k)}),
    # Livox (CustomMsg points repacked as PointCloud2): packed 22-byte points, no ring,
    # offset_time u32 ns; not dense.
    '/livox/lidar': dict(
        frame='livox_frame', width=150, point_step=22, dense=False,
        fields=[('x', 0, F32), ('y', 4, F32), ('z', 8, F32), ('intensity', 12, F32), ('tag', 16, U8),
                ('line', 17, U8), ('offset_time', 18, U32)],
        time=lambda j, k: {'offset_time': j * 10000, 'tag': 16, 'line': j % 6}),
    # A big-endian cloud with float64 coordinates, ring u16 and time f32 s relative.
    '/bigendian/points': dict(
        frame='be', width=100, point_step=40, big=True,
        fields=[('x', 0, F64), ('y', 8, F64), ('z', 16, F64), ('intensity', 24, F32),
                ('ring', 28, U16), ('time', 32, F32)],
        time=lambda j, k: {'time': j * 1e-5}),
}
TOPIC_ORDER = ['/velodyne_points', '/ouster/points', '/hesai/pandar', '/rslidar_points', '/livox/lidar',
               '/bigendian/points']


def quirk_imu(i):
    """IMU message i of the quirk bags (formula recomputed by the test)."""
    msg = Imu()
    msg.header.seq = i
    msg.header.stamp = genpy.Time(BASE_SEC, i * 50000000)
    msg.header.frame_id = 'imu'
    a = 0.1 * i
    msg.orientation.x, msg.orientation.y, msg.orientation.z, msg.orientation.w = 0.0, 0.0, math.sin(a), math.cos(a)
    msg.angular_velocity.x, msg.angular_velocity.y, msg.angular_velocity.z = 0.01 * i, -0.02 * i, 0.03
    msg.linear_acceleration.x, msg.linear_acceleration.y, msg.linear_acceleration.z = 0.1, 0.2 * i, 9.81
    msg.orientation_covariance = [0.001 * c for c in range(9)]
    msg.angular_velocity_covariance = [0.002 * c for c in range(9)]
    msg.linear_acceleration_covariance = [-1.0] + [0.0] * 8
    return msg


def quirk_records():
    """(log time, topic, msg) in WRITE order: shuffled, so log times go backwards in the file."""
    recs = []
    for t_index, topic in enumerate(TOPIC_ORDER):
        for k in range(3):
            msg = make_cloud(k, LAYOUTS[topic])
            recs.append((header_stamp(k) + genpy.Duration(0, 1000000 * (t_index + 1)), topic, msg))
    for i in range(8):
        msg = quirk_imu(i)
        recs.append((msg.header.stamp, '/imu/data', msg))
    random.Random(7).shuffle(recs)
    # A tie: a cloud logged at exactly the same time as IMU message 2, written after it.
    tie_time = quirk_imu(2).header.stamp
    recs.append((tie_time, '/velodyne_points', make_cloud(3, LAYOUTS['/velodyne_points'])))
    return recs


def write_quirk_bag(path, compression, recs):
    # 8 KiB chunks: the shuffled messages spread over many chunks, so time order crosses chunks.
    with rosbag.Bag(path, 'w', compression=compression, chunk_threshold=8 * 1024) as bag:
        for t, topic, msg in recs:
            bag.write(topic, msg, t=t)


def cut_index(src, dst):
    """Copies a bag without its index section and with index_pos = 0 (an interrupted recording)."""
    with open(src, 'rb') as f:
        blob = bytearray(f.read())
    magic = b'#ROSBAG V2.0\n'
    assert blob.startswith(magic)
    pos = len(magic)
    header_len = struct.unpack_from('<I', blob, pos)[0]
    hdr = blob[pos + 4:pos + 4 + header_len]
    q = 0
    index_pos = None
    while q < len(hdr):
        flen = struct.unpack_from('<I', hdr, q)[0]
        field = hdr[q + 4:q + 4 + flen]
        name, value = bytes(field).split(b'=', 1)
        if name == b'index_pos':
            index_pos = struct.unpack('<Q', value)[0]
            struct.pack_into('<Q', blob, pos + 4 + q + 4 + len(b'index_pos='), 0)
        q += 4 + flen
    assert index_pos
    with open(dst, 'wb') as f:
        f.write(blob[:index_pos])


def main():
    if len(sys.argv) < 2:
        raise SystemExit(__doc__)
    oxts_dir = sys.argv[1]
    out_dir = sys.argv[2] if len(sys.argv) > 2 else os.path.join(REPO, 'tests/data/bags')
    os.makedirs(out_dir, exist_ok=True)
    write_kitti_bag(oxts_dir, out_dir)
    recs = quirk_records()
    write_quirk_bag(os.path.join(out_dir, 'quirks_none.bag'), 'none', recs)
    write_quirk_bag(os.path.join(out_dir, 'quirks_bz2.bag'), 'bz2', recs)
    tmp = os.path.join(out_dir, 'quirks_lz4.tmp.bag')
    write_quirk_bag(tmp, 'lz4', recs)
    cut_index(tmp, os.path.join(out_dir, 'quirks_lz4_unindexed.bag'))
    os.remove(tmp)
    order = sorted(range(len(recs)), key=lambda i: recs[i][0])  # stable: ties in write order
    with open(os.path.join(out_dir, 'quirks_expected.txt'), 'w') as f:
        f.write('# log_time_ns topic, in the order a reader returns them (stable sort by log time)\n')
        for i in order:
            f.write('%d %s\n' % (recs[i][0].to_nsec(), recs[i][1]))
    # Self-check with the reference reader: the index is time-sorted the same way.
    with rosbag.Bag(os.path.join(out_dir, 'quirks_none.bag')) as bag:
        got = [(t.to_nsec(), topic) for topic, _, t in bag.read_messages()]
    want = [(recs[i][0].to_nsec(), recs[i][1]) for i in order]
    if sorted(got) != sorted(want):
        raise SystemExit('reference reader disagrees with the written messages')


if __name__ == '__main__':
    main()
