// Checks an MCAP file written by semlio_simulate --mcap with the reference
// readers (@mcap/core's McapIndexedReader and McapStreamReader, CRCs
// validated; @foxglove/cdr's CdrReader for the messages) against the
// KITTI-layout drive of the same run.
//
// usage: node scripts/check_sim_bags_mcap.cjs FILE.mcap DRIVE_DIR SENSOR FIELDS NODE_MODULES_PARENT
//   FIELDS: ring,time | ring | time | none; NODE_MODULES_PARENT: a folder whose
//   node_modules holds @mcap/core, @foxglove/cdr and @foxglove/wasm-zstd.
//
// Independent references, as in check_sim_bags_rosbag.py: x y z intensity
// equal velodyne/*.bin bit for bit, the IMU equals oxts/, ring matches the
// datasheet beam table by elevation, time matches the clockwise spin.
"use strict";
const fs = require("fs");
const path = require("path");
const { createRequire } = require("module");

const [file, drive, sensor, fields, modulesParent] = process.argv.slice(2);
const req = createRequire(path.join(path.resolve(modulesParent), "package.json"));
const { McapIndexedReader, McapStreamReader } = req("@mcap/core");
const { CdrReader } = req("@foxglove/cdr");
const zstd = req("@foxglove/wasm-zstd");

const EPOCH_S = 1317643200.0;
const PERIOD_S = 0.1;
const wantRing = fields.split(",").includes("ring");
const wantTime = fields.split(",").includes("time");
const ouster = sensor.startsWith("os");

function elevationsDeg(s) {
  const range = (n, f) => Array.from({ length: n }, (_, r) => f(r));
  if (s === "vlp16") return range(16, (r) => -15 + 2 * r);
  if (s === "vlp32c")
    return [-25, -1, -1.667, -15.639, -11.31, 0, -0.667, -8.843, -7.254, 0.333, -0.333, -6.148, -5.333, 1.333,
      0.667, -4, -4.667, 1.667, 1, -3.667, -3.333, 3.333, 2.333, -2.667, -3, 7, 4.667, -2.333, -2, 15, 10.333,
      -1.333].sort((a, b) => a - b);
  if (s === "hdl32e") return range(32, (r) => -30.67 + (r * 4) / 3);
  if (s === "os1-64") return range(64, (r) => -22.5 + (45 * r) / 63);
  if (s === "os0-128") return range(128, (r) => -45 + (90 * r) / 127);
  if (s === "hdl64e")
    return range(32, (r) => -24.9 + ((-8.83 + 24.9) * r) / 31).concat(range(32, (r) => -8.33 + ((2 + 8.33) * r) / 31));
  throw new Error("unknown sensor " + s);
}
const table = elevationsDeg(sensor).map((d) => (d * Math.PI) / 180);

const failures = [];
function fail(msg) {
  failures.push(msg);
  console.log("MISMATCH: " + msg);
}

function stampOf(r) {
  const sec = r.int32();
  const nsec = r.uint32();
  return { sec, nsec, s: sec + nsec * 1e-9 };
}

function decodeCloud(data) {
  const r = new CdrReader(data);
  const stamp = stampOf(r);
  const frameId = r.string();
  const height = r.uint32();
  const width = r.uint32();
  const nf = r.sequenceLength();
  const fl = [];
  for (let k = 0; k < nf; ++k) fl.push({ name: r.string(), offset: r.uint32(), datatype: r.uint8(), count: r.uint32() });
  const isBigendian = r.uint8();
  const pointStep = r.uint32();
  const rowStep = r.uint32();
  const bytes = r.uint8Array();
  const isDense = r.uint8();
  return { stamp, frameId, height, width, fields: fl, isBigendian, pointStep, rowStep, bytes, isDense };
}

function decodeImu(data) {
  const r = new CdrReader(data);
  const stamp = stampOf(r);
  const frameId = r.string();
  const q = r.float64Array(4);
  const qc = r.float64Array(9);
  const w = r.float64Array(3);
  r.float64Array(9);
  const a = r.float64Array(3);
  r.float64Array(9);
  return { stamp, frameId, q, qc, w, a };
}

async function main() {
  await zstd.isLoaded;
  const decompressHandlers = { zstd: (buf, size) => zstd.decompress(buf, Number(size)) };
  const buffer = fs.readFileSync(file);
  const readable = {
    size: async () => BigInt(buffer.length),
    read: async (offset, length) => buffer.subarray(Number(offset), Number(offset + length)),
  };
  const reader = await McapIndexedReader.Initialize({ readable, decompressHandlers });
  if (reader.header.profile !== "ros2") fail(`profile '${reader.header.profile}', expected 'ros2'`);
  const channels = new Map();
  for (const ch of reader.channelsById.values()) {
    const schema = reader.schemasById.get(ch.schemaId);
    channels.set(ch.id, { topic: ch.topic, encoding: ch.messageEncoding, schema: schema && schema.name, schemaEncoding: schema && schema.encoding });
  }
  const expected = { "/points": "sensor_msgs/msg/PointCloud2", "/imu/data": "sensor_msgs/msg/Imu" };
  const topics = [...channels.values()].map((c) => c.topic).sort();
  if (JSON.stringify(topics) !== JSON.stringify(Object.keys(expected).sort())) fail(`topics ${topics}`);
  for (const c of channels.values()) {
    if (c.schema !== expected[c.topic] || c.encoding !== "cdr" || c.schemaEncoding !== "ros2msg") {
      fail(`${c.topic}: schema ${c.schema} (${c.schemaEncoding}), encoding ${c.encoding}`);
    }
  }
  if (reader.chunkIndexes.length === 0) fail("no chunk indexes in the summary");
  const stats = reader.statistics;
  if (!stats) fail("no Statistics record");

  const bins = fs.readdirSync(path.join(drive, "velodyne")).filter((f) => f.endsWith(".bin")).sort();
  const oxtsDir = path.join(drive, "oxts", "data");
  const oxts = fs.readdirSync(oxtsDir).sort().map((f) => fs.readFileSync(path.join(oxtsDir, f), "utf8").trim().split(/\s+/).map(Number));

  let clouds = 0;
  let imus = 0;
  let last = -1n;
  for await (const m of reader.readMessages({ validateCrcs: true })) {
    if (m.logTime < last) fail(`log times go backwards at ${m.logTime}`);
    last = m.logTime;
    const topic = channels.get(m.channelId).topic;
    if (topic === "/imu/data") {
      const k = imus++;
      const msg = decodeImu(m.data);
      const want = EPOCH_S + k / 100;
      if (Math.abs(msg.stamp.s - want) > 2e-6) fail(`IMU ${k} stamp ${msg.stamp.s}, expected ${want}`);
      const o = oxts[k];
      if (!o) {
        fail(`more IMU messages than oxts records (${oxts.length})`);
        continue;
      }
      for (let j = 0; j < 3; ++j) {
        if (Math.abs(msg.a[j] - o[11 + j]) > 1e-12 || Math.abs(msg.w[j] - o[17 + j]) > 1e-12) {
          fail(`IMU ${k}: accel ${msg.a} gyro ${msg.w}, oxts ${o.slice(11, 14)} ${o.slice(17, 20)}`);
          break;
        }
      }
      if (msg.qc[0] !== -1) fail(`IMU ${k}: orientation_covariance[0] = ${msg.qc[0]}`);
      continue;
    }
    const i = clouds++;
    const c = decodeCloud(m.data);
    const want = EPOCH_S + i * PERIOD_S;
    const logS = Number(m.logTime) * 1e-9;
    if (Math.abs(c.stamp.s - want) > 2e-6 || Math.abs(logS - want - PERIOD_S) > 2e-6) {
      fail(`cloud ${i}: stamp ${c.stamp.s} log ${logS}, expected ${want} logged a period later`);
    }
    const names = c.fields.map((f) => f.name);
    let expect = ["x", "y", "z", "intensity"];
    if (ouster) {
      expect = expect.concat(wantTime ? ["t"] : [], ["reflectivity"], wantRing ? ["ring"] : [], ["ambient", "range"]);
    } else {
      expect = expect.concat(wantRing ? ["ring"] : [], wantTime ? ["time"] : []);
    }
    if (JSON.stringify(names) !== JSON.stringify(expect)) {
      fail(`cloud ${i}: fields ${names}, expected ${expect}`);
      continue;
    }
    if (c.height !== 1 || c.rowStep !== c.pointStep * c.width || c.bytes.length !== c.rowStep || c.isBigendian !== 0) {
      fail(`cloud ${i}: height ${c.height} width ${c.width} row_step ${c.rowStep} data ${c.bytes.length}`);
      continue;
    }
    const ref = fs.readFileSync(path.join(drive, "velodyne", bins[i]));
    if (ref.length !== 16 * c.width) {
      fail(`cloud ${i}: ${c.width} points, ${bins[i]} has ${ref.length / 16}`);
      continue;
    }
    const dv = new DataView(c.bytes.buffer, c.bytes.byteOffset, c.bytes.byteLength);
    const off = Object.fromEntries(c.fields.map((f) => [f.name, f.offset]));
    let bad = 0;
    let ringErr = 0;
    let timeErr = 0;
    for (let p = 0; p < c.width; ++p) {
      const b = p * c.pointStep;
      for (const [j, name] of ["x", "y", "z", "intensity"].entries()) {
        if (dv.getUint32(b + off[name], true) !== ref.readUInt32LE(16 * p + 4 * j)) bad++;
      }
      const x = dv.getFloat32(b + off.x, true);
      const y = dv.getFloat32(b + off.y, true);
      const z = dv.getFloat32(b + off.z, true);
      if (wantRing) {
        const ring = dv.getUint16(b + off.ring, true);
        const e = ring < table.length ? Math.abs(Math.atan2(z, Math.hypot(x, y)) - table[ring]) : Infinity;
        ringErr = Math.max(ringErr, e);
      }
      if (wantTime) {
        const t = ouster ? dv.getUint32(b + off.t, true) * 1e-9 : dv.getFloat32(b + off.time, true);
        let az = Math.PI - Math.atan2(y, x);
        az -= 2 * Math.PI * Math.floor(az / (2 * Math.PI));
        let d = Math.abs(t - (PERIOD_S * az) / (2 * Math.PI));
        d = Math.min(d, PERIOD_S - d);
        timeErr = Math.max(timeErr, t < 0 || t >= PERIOD_S ? Infinity : d);
      }
    }
    if (bad > 0) fail(`cloud ${i}: ${bad} x/y/z/intensity values differ from ${bins[i]}`);
    if (ringErr > 1e-4) fail(`cloud ${i}: elevation off the beam table at its ring by ${ringErr} rad`);
    if (timeErr > 2e-6) fail(`cloud ${i}: per-point time off the clockwise spin by ${timeErr} s`);
  }
  if (clouds !== bins.length) fail(`${clouds} clouds, ${bins.length} velodyne/*.bin files`);
  if (imus !== oxts.length) fail(`${imus} IMU messages, ${oxts.length} oxts records`);
  if (stats && Number(stats.messageCount) !== clouds + imus) fail(`Statistics.message_count ${stats.messageCount}, read ${clouds + imus}`);

  // The stream reader, fed 1 MiB at a time, CRCs validated, to the footer.
  const stream = new McapStreamReader({ decompressHandlers, validateCrcs: true });
  let streamed = 0;
  let sawFooter = false;
  for (let at = 0; at < buffer.length; at += 1 << 20) {
    stream.append(buffer.subarray(at, Math.min(buffer.length, at + (1 << 20))));
    let rec;
    while ((rec = stream.nextRecord()) !== undefined) {
      if (rec.type === "Message") streamed++;
      if (rec.type === "Footer") sawFooter = true;
    }
  }
  if (!stream.done() || !sawFooter) fail("McapStreamReader did not reach the footer");
  if (streamed !== clouds + imus) fail(`McapStreamReader read ${streamed} messages, the indexed reader ${clouds + imus}`);

  if (failures.length > 0) {
    console.log(`mcap check FAILED: ${failures.length} mismatches`);
    process.exit(1);
  }
  const compression = reader.chunkIndexes.map((ci) => ci.compression || "none")[0];
  console.log(`mcap check passed: ${file}, ${reader.chunkIndexes.length} chunks (${compression}), ${clouds} clouds (${ouster ? "Ouster" : "Velodyne"} layout, fields ${fields}), ${imus} IMU messages match the KITTI-layout drive (indexed and stream readers)`);
}

main().catch((e) => {
  console.log("mcap check FAILED: " + (e && e.stack ? e.stack : e));
  process.exit(1);
});
