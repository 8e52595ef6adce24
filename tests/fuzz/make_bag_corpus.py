#!/usr/bin/python3
"""Writes the seed corpus of the message and bag container harnesses
(tests/fuzz/corpus/<harness>/): ros1_pointcloud2, ros1_imu, cdr_pointcloud2,
cdr_imu, rosbag1, mcap, sqlite_bag. Deterministic; the output is committed
(~60 KB in all). Run with Debian's Python (it has the ROS 1 reference
implementation, python3-rosbag):

    /usr/bin/python3 tests/fuzz/make_bag_corpus.py

- ROS 1 messages and bags: the quirk layouts of scripts/make_bag_fixtures.py
  (Velodyne, Ouster, Hesai, Robosense, Livox, big-endian float64), shrunk to
  a few points so that the fuzzer mutates small inputs, serialised and
  written by the reference implementation (rosbag: uncompressed, bz2 (block
  size 1) and lz4 chunks, and an lz4 bag with its index cut off).
- CDR messages: cut from tests/data/bags/ros2_sqlite/ros2_sqlite_0.db3
  (written by @foxglove/cdr, see tests/data/bags/README.md).
- MCAP: the three smallest MCAP fixtures of tests/data/bags as they are.
- sqlite3: ros2_sqlite_1.db3 without its largest message, rewritten with
  512-byte pages (VACUUM) so the database is a few KB.
"""

import bz2
import copy
import functools
import io
import os
import shutil
import sqlite3
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(REPO, 'scripts'))

import make_bag_fixtures as fx  # noqa: E402  (its imports need /usr/bin/python3)
import rosbag  # noqa: E402

BAGS = os.path.join(REPO, 'tests', 'data', 'bags')
OUT = os.path.join(HERE, 'corpus')


def put(harness, name, data):
    d = os.path.join(OUT, harness)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), 'wb') as f:
        f.write(data)


def small_layout(topic):
    """The quirk layout of `topic` with a few points (organised: 2 rows of 3)."""
    lay = copy.deepcopy(fx.LAYOUTS[topic])
    lay['time'] = fx.LAYOUTS[topic]['time']
    if lay.get('height', 1) > 1:
        lay['height'], lay['width'] = 2, 3
    else:
        lay['width'] = 8 if lay.get('dense', True) else 24  # not dense: reaches j % 17 == 5 and j % 23 == 7
    return lay


def serialise(msg):
    buf = io.BytesIO()
    msg.serialize(buf)
    return buf.getvalue()


def main():
    clouds = {topic: fx.make_cloud(1, small_layout(topic)) for topic in fx.TOPIC_ORDER}
    for topic, msg in clouds.items():
        put('ros1_pointcloud2', topic.strip('/').replace('/', '_') + '.bin', serialise(msg))
    put('ros1_imu', 'imu_3.bin', serialise(fx.quirk_imu(3)))

    db = sqlite3.connect(os.path.join(BAGS, 'ros2_sqlite', 'ros2_sqlite_0.db3'))
    for name, topic in (('points.cdr', '/points'), ('padded_points.cdr', '/padded/points')):
        row = db.execute('SELECT data FROM messages JOIN topics ON topics.id = topic_id WHERE name = ? '
                         'ORDER BY timestamp LIMIT 1', (topic,)).fetchone()
        put('cdr_pointcloud2', name, bytes(row[0]))
    row = db.execute("SELECT data FROM messages JOIN topics ON topics.id = topic_id WHERE name = '/imu' "
                     'ORDER BY timestamp LIMIT 1').fetchone()
    put('cdr_imu', 'imu.cdr', bytes(row[0]))
    db.close()

    tmp = tempfile.mkdtemp()
    try:
        recs = []
        for t_index, topic in enumerate(['/velodyne_points', '/livox/lidar']):
            recs.append((fx.header_stamp(1) + fx.genpy.Duration(0, 1000000 * (t_index + 1)), topic, clouds[topic]))
        for i in (2, 0, 1):  # out of log-time order in the file
            m = fx.quirk_imu(i)
            recs.append((m.header.stamp, '/imu/data', m))
        # bz2 chunks at block size 1 (100 kB; rosbag's default is 9): the
        # decompressor allocates 4 bytes per block byte for every chunk, 3.6 MB
        # at level 9, which would dominate an execution's time.
        rosbag.bag.bz2.BZ2Compressor = functools.partial(bz2.BZ2Compressor, 1)
        for compression in ('none', 'bz2', 'lz4'):
            path = os.path.join(tmp, compression + '.bag')
            # 1.5 KB chunks: a few chunks (each repeats its connection records), so the
            # index and the time order cross chunks.
            with rosbag.Bag(path, 'w', compression=compression, chunk_threshold=1536) as bag:
                for t, topic, msg in recs:
                    bag.write(topic, msg, t=t)
            with open(path, 'rb') as f:
                put('rosbag1', 'small_%s.bag' % compression, f.read())
        fx.cut_index(os.path.join(tmp, 'lz4.bag'), os.path.join(tmp, 'unindexed.bag'))
        with open(os.path.join(tmp, 'unindexed.bag'), 'rb') as f:
            put('rosbag1', 'small_lz4_unindexed.bag', f.read())

        for name in ('small_streamed.mcap', 'small_ros1.mcap', 'small_lz4.mcap'):
            with open(os.path.join(BAGS, name), 'rb') as f:
                put('mcap', name, f.read())

        db3 = os.path.join(tmp, 'small.db3')
        shutil.copy(os.path.join(BAGS, 'ros2_sqlite', 'ros2_sqlite_1.db3'), db3)
        db = sqlite3.connect(db3)
        db.execute("DELETE FROM messages WHERE topic_id = (SELECT id FROM topics WHERE name = '/points')")
        db.commit()
        db.execute('PRAGMA journal_mode = DELETE')
        db.execute('PRAGMA page_size = 512')
        db.execute('VACUUM')
        db.close()
        with open(db3, 'rb') as f:
            put('sqlite_bag', 'small.db3', f.read())
    finally:
        shutil.rmtree(tmp)


if __name__ == '__main__':
    main()
