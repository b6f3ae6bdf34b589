// ONNX Runtime timing of one model, the peer aprt is measured against.
// usage: node ort_bench.js MODEL.onnx THREADS RUNS WARMUP
// Prints one JSON line: per-run milliseconds, and the session settings.
'use strict';
const ort = require('onnxruntime-node');

async function main() {
  const [model, threads = '1', runs = '30', warmup = '5'] = process.argv.slice(2);
  if (!model) {
    console.error('usage: node ort_bench.js MODEL.onnx THREADS RUNS WARMUP');
    process.exit(2);
  }
  const t0 = process.hrtime.bigint();
  const session = await ort.InferenceSession.create(model, {
    intraOpNumThreads: Number(threads),
    interOpNumThreads: 1,
    graphOptimizationLevel: 'all',
    executionMode: 'sequential',
  });
  const createMs = Number(process.hrtime.bigint() - t0) / 1e6;
  const input = session.inputNames[0];
  const meta = session.inputMetadata ? session.inputMetadata[0] : null;
  const dims = meta && meta.shape ? meta.shape.map(Number) : null;
  if (!dims || dims.some((d) => !(d > 0))) {
    console.error(`ort_bench: input ${input} has no static shape`);
    process.exit(2);
  }
  const n = dims.reduce((a, b) => a * b, 1);
  const data = new Float32Array(n);
  let s = 1;
  for (let i = 0; i < n; ++i) {  // deterministic pseudo-random input
    s = (s * 1103515245 + 12345) >>> 0;
    data[i] = (s / 4294967296) * 2 - 1;
  }
  const feeds = {[input]: new ort.Tensor('float32', data, dims)};
  for (let i = 0; i < Number(warmup); ++i) await session.run(feeds);
  const ms = [];
  for (let i = 0; i < Number(runs); ++i) {
    const a = process.hrtime.bigint();
    await session.run(feeds);
    ms.push(Number(process.hrtime.bigint() - a) / 1e6);
  }
  console.log(JSON.stringify({peer: 'onnxruntime-node', version: ort.env.versions ? ort.env.versions.common : '1.30.0',
                              model, threads: Number(threads), create_ms: createMs, ms}));
}

main().catch((e) => {
  console.error(`ort_bench: ${e.message}`);
  process.exit(1);
});
