// Record -> replay -> record: the second recording must hold the same drive.
//
//   node mcap_roundtrip.js A.mcap B.mcap [--estimates-only]
//
// A: `aprt run --record A.mcap` of a replayed sequence; B: `aprt run --replay
// A.mcap --record B.mcap`. Read with the independent libraries (@mcap/core,
// @foxglove/rosmsg2-serialization). Checks: the same frames (bytes, size,
// encoding, header stamps), the same model estimate for every frame bit for
// bit (aprt_msgs/PoseTiming), and the same published poses (values and stamps).
"use strict";
const fs = require("fs");
const { McapStreamReader } = require("@mcap/core");
const { parse } = require("@foxglove/rosmsg");
const { MessageReader } = require("@foxglove/rosmsg2-serialization");

function fail(msg) {
  console.error(`mcap_roundtrip: ${msg}`);
  process.exit(1);
}

function read(file) {
  const r = new McapStreamReader({ validateCrcs: true });
  r.append(new Uint8Array(fs.readFileSync(file)));
  const schemas = new Map(), channels = new Map(), readers = new Map(), out = {};
  for (let rec; (rec = r.nextRecord()); ) {
    if (rec.type === "Schema") schemas.set(rec.id, rec);
    if (rec.type === "Channel") channels.set(rec.id, rec);
    if (rec.type !== "Message") continue;
    const ch = channels.get(rec.channelId);
    const name = schemas.get(ch.schemaId).name;
    if (!readers.has(ch.id)) {
      readers.set(ch.id, new MessageReader(parse(new TextDecoder().decode(schemas.get(ch.schemaId).data), { ros2: true })));
    }
    (out[name] = out[name] || []).push(readers.get(ch.id).readMessage(rec.data));
  }
  if (!r.done()) fail(`${file}: not read to its closing magic`);
  return out;
}

const stamp = (h) => `${h.stamp.sec}.${String(h.stamp.nanosec).padStart(9, "0")}`;
const [fa, fb] = process.argv.slice(2, 4);
const estimatesOnly = process.argv.includes("--estimates-only");
if (!fa || !fb) fail("usage: node mcap_roundtrip.js A.mcap B.mcap");
const a = read(fa), b = read(fb);
const frames = (x) => x["sensor_msgs/msg/Image"] || x["sensor_msgs/msg/PointCloud2"] || [];
const fa_ = frames(a), fb_ = frames(b);
if (fa_.length === 0 || fa_.length !== fb_.length) fail(`frames: ${fa_.length} vs ${fb_.length}`);
// Each frame of a drive has its own stamp, later than the one before (a
// frame buffer reused by the camera must not hand on its old stamp).
const ns = (h) => BigInt(h.stamp.sec) * 1000000000n + BigInt(h.stamp.nanosec);
fa_.forEach((x, i) => {
  if (i > 0 && ns(x.header) <= ns(fa_[i - 1].header)) fail(`frame ${i}: stamp ${stamp(x.header)} not after frame ${i - 1}'s ${stamp(fa_[i - 1].header)}`);
});
fa_.forEach((x, i) => {
  const y = fb_[i];
  if (stamp(x.header) !== stamp(y.header)) fail(`frame ${i}: stamp ${stamp(x.header)} vs ${stamp(y.header)}`);
  if (x.width !== y.width || x.height !== y.height || x.encoding !== y.encoding || x.step !== y.step) fail(`frame ${i}: geometry`);
  if (Buffer.compare(Buffer.from(x.data), Buffer.from(y.data)) !== 0) fail(`frame ${i}: bytes differ`);
});
const ta = a["aprt_msgs/msg/PoseTiming"] || [], tb = b["aprt_msgs/msg/PoseTiming"] || [];
if (ta.length !== fa_.length || tb.length !== ta.length) fail(`timing records: ${ta.length} vs ${tb.length} for ${fa_.length} frames`);
ta.forEach((x, i) => {
  const y = tb[i];
  for (let k = 0; k < 3; ++k) if (!Object.is(x.position[k], y.position[k])) fail(`pose ${i}: position ${x.position} vs ${y.position}`);
  for (let k = 0; k < 4; ++k) if (!Object.is(x.orientation[k], y.orientation[k])) fail(`pose ${i}: orientation ${x.orientation} vs ${y.orientation}`);
  if (stamp(x.header) !== stamp(y.header)) fail(`pose ${i}: stamp`);
});
// A valid pose goes out only once the supervisor is RUNNING, and when it gets
// there is the wall clock's (its ticks), not the drive's: at the start the two
// runs may differ by the poses of a tick or two. From the later of the two
// first published stamps on, every published pose must be the same.
const pa_ = a["geometry_msgs/msg/PoseWithCovarianceStamped"] || [];
const pb_ = b["geometry_msgs/msg/PoseWithCovarianceStamped"] || [];
const from = pa_.length && pb_.length ? (ns(pa_[0].header) > ns(pb_[0].header) ? ns(pa_[0].header) : ns(pb_[0].header)) : 0n;
const pa = pa_.filter((x) => ns(x.header) >= from), pb = pb_.filter((x) => ns(x.header) >= from);
if (!estimatesOnly && pa.length !== pb.length) fail(`published poses: ${pa.length} vs ${pb.length}`);
if (!estimatesOnly) pa.forEach((x, i) => {
  const y = pb[i];
  if (stamp(x.header) !== stamp(y.header) || JSON.stringify(x.pose) !== JSON.stringify(y.pose)) fail(`published pose ${i} differs`);
});
console.log(`mcap_roundtrip: ${fa_.length} frames identical, ${ta.length} estimates identical bit for bit, ` +
            (estimatesOnly ? `published poses not compared (${pa_.length} vs ${pb_.length})`
                           : `${pa.length} published poses identical (${pa_.length - pa.length} vs ${pb_.length - pb.length} before the later start)`) + ` (${fa} -> ${fb})`);
