// An independent reading of an MCAP file aprt wrote: eProsima-free, aprt-free
// code from the MCAP and Foxglove projects (npm @mcap/core, @foxglove/rosmsg,
// @foxglove/rosmsg2-serialization, @foxglove/crc), the libraries Foxglove
// Studio opens bags with.
//
//   node mcap_check.js FILE.mcap [--expect sample]
//
// Streams every record (CRCs validated), recomputes the data section's CRC,
// opens the summary with the indexed reader (summary CRC validated), decodes
// every message with the schema the file carries, and prints one JSON line
// per message. --expect sample: the values tests/unit/mcap_writer_test.cc
// wrote, checked field by field. Exit 0 when all holds.
"use strict";
const fs = require("fs");
const { McapStreamReader, McapIndexedReader } = require("@mcap/core");
const { parse } = require("@foxglove/rosmsg");
const { MessageReader } = require("@foxglove/rosmsg2-serialization");
const { crc32 } = require("@foxglove/crc");

function fail(msg) {
  console.error(`mcap_check: ${msg}`);
  process.exit(1);
}

async function main() {
  const [file, flag, expect] = process.argv.slice(2);
  if (!file) fail("usage: node mcap_check.js FILE.mcap [--expect sample]");
  const bytes = new Uint8Array(fs.readFileSync(file));

  const stream = new McapStreamReader({ validateCrcs: true });
  stream.append(bytes);
  const schemas = new Map(), channels = new Map(), readers = new Map();
  const messages = [];
  let header, dataEnd, statistics, footer, offset = 8;
  for (let r; (r = stream.nextRecord()); ) {
    switch (r.type) {
      case "Header": header = r; break;
      case "Schema": schemas.set(r.id, r); break;
      case "Channel": channels.set(r.id, r); break;
      case "Message": messages.push(r); break;
      case "DataEnd": dataEnd = r; break;
      case "Statistics": statistics = r; break;
      case "Footer": footer = r; break;
    }
  }
  if (!stream.done()) fail("the stream reader did not reach the closing magic");
  if (!header || header.profile !== "ros2") fail(`profile ${header && header.profile}, not ros2`);
  if (!dataEnd || !footer || !statistics) fail("no DataEnd, Statistics or Footer record");
  // The data section's CRC: every byte before the DataEnd record.
  const dataEndOffset = Number(footer.summaryStart) - (1 + 8 + 4);
  const crc = crc32(bytes.subarray(0, dataEndOffset));
  if (dataEnd.dataSectionCrc !== 0 && dataEnd.dataSectionCrc !== crc) {
    fail(`data section CRC ${dataEnd.dataSectionCrc}, recomputed ${crc}`);
  }
  // The indexed reader checks the footer, the summary and its CRC.
  const indexed = await McapIndexedReader.Initialize({
    readable: {
      size: async () => BigInt(bytes.length),
      read: async (o, n) => bytes.subarray(Number(o), Number(o + n)),
    },
  });
  if (indexed.schemasById.size !== schemas.size || indexed.channelsById.size !== channels.size) {
    fail("the summary's schemas or channels differ from the data section's");
  }
  if (Number(statistics.messageCount) !== messages.length) {
    fail(`statistics say ${statistics.messageCount} messages, the file has ${messages.length}`);
  }
  const decoded = [];
  for (const m of messages) {
    const ch = channels.get(m.channelId);
    if (!ch) fail(`message on unknown channel ${m.channelId}`);
    if (ch.messageEncoding !== "cdr") fail(`channel ${ch.topic}: encoding ${ch.messageEncoding}`);
    let reader = readers.get(ch.id);
    if (!reader) {
      const s = schemas.get(ch.schemaId);
      if (!s || s.encoding !== "ros2msg") fail(`channel ${ch.topic}: no ros2msg schema`);
      reader = new MessageReader(parse(new TextDecoder().decode(s.data), { ros2: true }));
      readers.set(ch.id, reader);
    }
    const msg = reader.readMessage(m.data);
    decoded.push({ topic: ch.topic, schema: schemas.get(ch.schemaId).name, logTime: m.logTime, msg });
  }
  for (const d of decoded) {
    const m = d.msg, short = { topic: d.topic, stamp: m.header && m.header.stamp };
    if (m.pose && m.pose.pose) Object.assign(short, { position: m.pose.pose.position, orientation: m.pose.pose.orientation });
    if (m.status) short.status = m.status.map((s) => ({ level: s.level, message: s.message, values: s.values }));
    if (m.encoding) Object.assign(short, { width: m.width, height: m.height, encoding: m.encoding, bytes: m.data.length });
    if (m.fields) Object.assign(short, { points: m.width, fields: m.fields.map((f) => f.name).join(",") });
    console.log(JSON.stringify(short));
  }
  if (flag === "--expect" && expect === "sample") checkSample(decoded);
  console.log(`mcap_check: ${file}: ${messages.length} messages on ${channels.size} channels, ` +
              `CRCs ok, every message decoded`);
}

function near(a, b) { return Math.abs(a - b) < 1e-12; }

function checkSample(decoded) {
  const by = (t) => decoded.filter((d) => d.topic === t).map((d) => d.msg);
  const images = by("/aprt/image"), poses = by("/aprt/pose_with_covariance");
  const diags = by("/diagnostics"), clouds = by("/points_raw");
  if (images.length !== 4 || poses.length !== 3 || diags.length !== 2 || clouds.length !== 2) {
    fail(`sample: ${images.length} images, ${poses.length} poses, ${diags.length} diagnostics, ${clouds.length} clouds`);
  }
  images.slice(0, 3).forEach((im, i) => {
    if (im.width !== 5 || im.height !== 3 || im.encoding !== "rgb8" || im.step !== 15) fail(`image ${i} geometry`);
    for (let k = 0; k < 45; ++k) if (im.data[k] !== ((k * 7 + i) & 255)) fail(`image ${i} byte ${k}`);
    if (im.header.frame_id !== "camera" || im.header.stamp.sec !== 1796000000) fail(`image ${i} header`);
  });
  if (images[3].width !== 640 || images[3].data.length !== 640 * 480 * 3 || images[3].data[921599] !== 0x5a) {
    fail("the large image");
  }
  poses.forEach((p, i) => {
    const pp = p.pose.pose;
    if (!near(pp.position.x, 100.5 + i) || !near(pp.position.y, -20.25) || !near(pp.position.z, 1.5)) fail(`pose ${i} position`);
    const q = pp.orientation;  // written as w x y z = 0.5 0.5 -0.5 0.5
    if (!near(q.w, 0.5) || !near(q.x, 0.5) || !near(q.y, -0.5) || !near(q.z, 0.5)) fail(`pose ${i} orientation`);
    if (!near(p.pose.covariance[0], 0.25) || !near(p.pose.covariance[35], 9) || p.pose.covariance[1] !== 0) fail(`pose ${i} covariance`);
    if (p.header.frame_id !== "map" || p.header.stamp.nanosec !== 5 + i * 40000000) fail(`pose ${i} stamp`);
  });
  const s = diags[1].status[0];
  if (s.level !== 0 || s.name !== "aprt: pose" || s.message !== "RUNNING: ok" ||
      s.values[0].key !== "state" || s.values[0].value !== "RUNNING") fail("diagnostics");
  const c = clouds[0];
  if (c.width !== 2 || c.point_step !== 16 || c.fields.map((f) => f.name).join() !== "x,y,z,intensity") fail("cloud layout");
  const f = new Float32Array(c.data.slice().buffer);
  if (f[0] !== 1 || f[6] !== 0.25 || f[7] !== 9) fail("cloud points");
  console.log("mcap_check: the sample's values all read back");
}

main().catch((e) => fail(e.stack || String(e)));
