#!/usr/bin/python3
"""aprt against ONNX Runtime on the same exported model, same thread count.

One command: installs onnxruntime-node from npm if needed (--ignore-scripts:
its postinstall wants CUDA downloads), makes the full APR-Transformer at each
input size (random input-sensitive weights; speed does not depend on them),
then runs ORT and aprt in interleaved rounds -- ORT, aprt, ORT, aprt, ... --
so that both see the same machine state, and prints medians, p99 and the
ratio ORT/aprt, then the fastest run of each and their ratio (a shared host's
noise only adds time, so the minima show how much of the medians' ratio is it).
--markdown FILE also writes the tables. Unless --no-int8, the model is also
quantised (python3 -m aprt_tools quantize, calibrated on frames of
data/demo_drive; default policy) and aprt int8 runs in the same rounds.

  tools/bench/run_bench.py [--sizes 224,128] [--threads 1,2] [--rounds 5] [--runs 20] [--no-int8]
                           [--bev] [--points] [--compare-aprt OTHER_BUILD/bin/aprt]

--compare-aprt runs a second aprt binary in the same rounds (a build of an
earlier commit): the before/after table a change that must not cost speed
is judged by.

--points adds the LiDAR raw-points model (4096 points, PointNet++ and the same
transformers): aprt runs its model_bin, ONNX Runtime the same network exported
in standard ONNX ops (model_portable.onnx: ORT has no PointNet++ operators, so
farthest-point sampling is an unrolled loop there), with the same weights.
"""

import argparse
import datetime
import json
import os
import platform
import statistics
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BENCH = os.path.join(ROOT, "tools", "bench")
PYTHON = "/usr/bin/python3"


def sh(cmd, **kw):
    return subprocess.run(cmd, check=True, text=True, capture_output=True, **kw)


def ensure_ort():
    if os.path.isdir(os.path.join(BENCH, "node_modules", "onnxruntime-node")):
        return
    print("run_bench: installing onnxruntime-node from npm (--ignore-scripts)", flush=True)
    subprocess.run(["npm", "install", "--ignore-scripts", "--no-audit", "--no-fund"], cwd=BENCH,
                   check=True, env=dict(os.environ, ONNXRUNTIME_NODE_INSTALL="skip"))


def ensure_model(size, out_root, config="full"):
    d = os.path.join(out_root, f"{config}_{size}")
    points = config == "points"
    want = "model_portable.onnx" if points else "model.aprt"
    if not os.path.exists(os.path.join(d, want)) or not os.path.exists(os.path.join(d, "model.aprt")):
        print(f"run_bench: making the {config} {size} model in {d}"
              + (" (and its portable ONNX: minutes)" if points else ""), flush=True)
        env = dict(os.environ, PYTHONPATH=os.path.join(ROOT, "tools"), PYTHONWARNINGS="ignore")
        sh([PYTHON, "-m", "aprt_tools", "golden", "--config", config, "--size", str(size),
            "--count", "2", "--convert", "--out", d] + (["--portable", "--seed", "10"] if points
                                                       else []), env=env)
    return d


def ort_model(s, d):
    return os.path.join(d, "model_portable.onnx" if s == "points" else "model.onnx")


def ensure_int8(d, attention=None):
    """Calibrated on demo-drive frames (camera) or on the golden inputs (BEV: any
    input of the right shape serves a speed measurement). attention: "int8"
    (scores int8 too, quantize --int8-attention), "bf16" (--bf16-attention) or
    None (fp32 attention)."""
    out = os.path.join(d, f"model_int8_{attention}_attention.aprt" if attention else
                       "model_int8.aprt")
    if not os.path.exists(out):
        print(f"run_bench: quantising {d}/model.aprt", flush=True)
        env = dict(os.environ, PYTHONPATH=os.path.join(ROOT, "tools"), PYTHONWARNINGS="ignore")
        calib = os.path.join(ROOT, "data", "demo_drive")
        if os.path.basename(d).startswith("bev"):
            import numpy as np
            cfg = json.load(open(os.path.join(d, "model.json")))
            g, c = cfg["image_size"], cfg["in_channels"]
            x = np.fromfile(os.path.join(d, "in_1.f32"), "<f4").reshape(1, c, g, g)
            calib = os.path.join(d, "calibration.npy")
            np.save(calib, np.abs(x.transpose(0, 2, 3, 1)))
        sh([PYTHON, "-m", "aprt_tools", "quantize", os.path.join(d, "model.aprt"),
            "--calibration", calib, "--frames", "4", "-o", out] +
           ([f"--{attention}-attention"] if attention else []), env=env)
    return out


def input_label(s):
    return {"bev": "BEV 256x256x2", "points": "points 4096x6"}.get(s, f"{s}x{s}")


def p99(xs):
    xs = sorted(xs)
    pos = 0.99 * (len(xs) - 1)
    lo = int(pos)
    hi = min(lo + 1, len(xs) - 1)
    return xs[lo] + (xs[hi] - xs[lo]) * (pos - lo)


def run_ort(model, threads, runs):
    out = sh(["node", os.path.join(BENCH, "ort_bench.js"), model, str(threads), str(runs), "3"])
    return json.loads(out.stdout.strip().splitlines()[-1])["ms"]


def run_aprt(aprt, model, threads, runs):
    out = sh([aprt, "bench", model, "--json", "--runs", str(runs), "--warmup", "3",
              "--threads", str(threads)])
    d = json.loads(out.stdout)
    return d["ms"], d


def cpu_name():
    try:
        for line in open("/proc/cpuinfo"):
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", default="224,128")
    ap.add_argument("--threads", default="1,2")
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--runs", type=int, default=20, help="timed runs per round and peer")
    ap.add_argument("--aprt", default=os.path.join(ROOT, "build", "release", "bin", "aprt"))
    ap.add_argument("--compare-aprt", metavar="PATH",
                    help="a second aprt binary (e.g. a build of an earlier commit) measured in "
                         "the same rounds: before/after medians and minima")
    ap.add_argument("--models", default=os.path.join(ROOT, "build", "bench"))
    ap.add_argument("--markdown", help="also write the table to this file")
    ap.add_argument("--no-int8", action="store_true", help="fp32 only")
    att = ap.add_mutually_exclusive_group()
    att.add_argument("--int8-attention", action="store_const", const="int8", dest="attention",
                     help="the int8 model with int8 attention scores too (docs/int8.md)")
    att.add_argument("--bf16-attention", action="store_const", const="bf16", dest="attention",
                     help="the int8 model with bf16 attention (docs/int8.md)")
    ap.add_argument("--bev", action="store_true",
                    help="also the LiDAR BEV model (256 x 256 x 2 histogram, same network)")
    ap.add_argument("--points", action="store_true",
                    help="also the LiDAR raw-points model (4096 points, PointNet++)")
    a = ap.parse_args()
    if not os.path.exists(a.aprt):
        sys.exit(f"run_bench: {a.aprt} not found: build first (tools/setup.sh)")
    ensure_ort()
    sizes = [int(s) for s in a.sizes.split(",") if s] + (["bev"] if a.bev else []) + \
        (["points"] if a.points else [])
    threads = [int(t) for t in a.threads.split(",")]
    models = {s: ensure_model(256, a.models, "bev") if s == "bev" else
              ensure_model(4096, a.models, "points") if s == "points" else
              ensure_model(s, a.models) for s in sizes}
    ort = {(s, t): [] for s in sizes for t in threads}
    ours = {(s, t): [] for s in sizes for t in threads}
    int8 = {(s, t): [] for s in sizes for t in threads}
    before = {(s, t): [] for s in sizes for t in threads}  # --compare-aprt, fp32
    before8 = {(s, t): [] for s in sizes for t in threads}  # --compare-aprt, int8
    if a.compare_aprt and not os.path.exists(a.compare_aprt):
        sys.exit(f"run_bench: {a.compare_aprt} not found")
    # (int8 of the points model: not measured; its policy is the image model's)
    int8_models = {} if a.no_int8 else {s: ensure_int8(models[s], a.attention) for s in sizes
                                         if s != "points"}
    info = {}
    for r in range(a.rounds):
        for s in sizes:
            for t in threads:
                ort[(s, t)] += run_ort(ort_model(s, models[s]), t, a.runs)
                ms, d = run_aprt(a.aprt, os.path.join(models[s], "model.aprt"), t, a.runs)
                ours[(s, t)] += ms
                info[(s, t)] = d
                if a.compare_aprt:
                    ms, _ = run_aprt(a.compare_aprt, os.path.join(models[s], "model.aprt"), t,
                                     a.runs)
                    before[(s, t)] += ms
                if s in int8_models:
                    ms, _ = run_aprt(a.aprt, int8_models[s], t, a.runs)
                    int8[(s, t)] += ms
                    if a.compare_aprt:
                        ms, _ = run_aprt(a.compare_aprt, int8_models[s], t, a.runs)
                        before8[(s, t)] += ms
        print(f"run_bench: round {r + 1}/{a.rounds} done", flush=True)
    now = datetime.datetime.now().strftime("%Y-%m-%d %H:%M")
    head = (f"ONNX Runtime (onnxruntime-node 1.30.0, graph optimisation 'all', sequential) vs aprt, "
            f"{a.rounds} interleaved rounds x {a.runs} runs each; {cpu_name()}, "
            f"{os.cpu_count()} cores; {now}." +
            ({"int8": " int8: attention scores int8 too.", "bf16": " int8: attention in bf16."}
             .get(a.attention, "") if not a.no_int8 else ""))
    q = "" if a.no_int8 else " aprt int8 median ms | int8 p99 | ORT / int8 |"
    lines = ["| input | threads | ORT median ms | ORT p99 | aprt median ms | aprt p99 | ORT / aprt |" +
             q + " aprt kernels | allocations/frame |",
             "|---|---:|---:|---:|---:|---:|---:|" + ("" if a.no_int8 else "---:|---:|---:|") +
             "---|---:|"]
    for s in sizes:
        for t in threads:
            om, am = statistics.median(ort[(s, t)]), statistics.median(ours[(s, t)])
            d = info[(s, t)]
            label = input_label(s)
            row = (f"| {label} | {t} | {om:.1f} | {p99(ort[(s, t)]):.1f} | {am:.1f} | "
                   f"{p99(ours[(s, t)]):.1f} | **{om / am:.2f}x** |")
            if not a.no_int8 and int8[(s, t)]:
                qm = statistics.median(int8[(s, t)])
                row += f" {qm:.1f} | {p99(int8[(s, t)]):.1f} | **{om / qm:.2f}x** |"
            elif not a.no_int8:
                row += " — | — | — |"
            lines.append(row + f" {d['isa']} | {d['allocations_during_runs']} |")
    # The fastest run of each: a shared host's interruptions only ever add time,
    # so the minimum is the estimate least moved by them (the medians above are
    # the target's measure; this table says how much of a ratio is the host's).
    q = "" if a.no_int8 else " aprt int8 min ms | ORT / int8 at min |"
    fast = ["| input | threads | ORT min ms | aprt min ms | ORT / aprt at min |" + q,
            "|---|---:|---:|---:|---:|" + ("" if a.no_int8 else "---:|---:|")]
    for s in sizes:
        for t in threads:
            om, am = min(ort[(s, t)]), min(ours[(s, t)])
            label = input_label(s)
            row = f"| {label} | {t} | {om:.1f} | {am:.1f} | {om / am:.2f}x |"
            if not a.no_int8:
                qm = min(int8[(s, t)], default=None)
                row += f" {qm:.1f} | {om / qm:.2f}x |" if qm else " — | — |"
            fast.append(row)
    table = (head + "\n\n" + "\n".join(lines) + "\n\nFastest run of each (the host's noise only adds):\n\n" +
             "\n".join(fast) + "\n")
    if a.compare_aprt:
        cmp = [f"Before ({a.compare_aprt}) and after ({a.aprt}), the same rounds:", "",
               "| input | threads | model | before median ms | after median ms | after / before |"
               " before min ms | after min ms | after / before at min |",
               "|---|---:|---|---:|---:|---:|---:|---:|---:|"]
        for s in sizes:
            for t in threads:
                for kind, b, n in (("fp32", before, ours), ("int8", before8, int8)):
                    if not b[(s, t)] or not n[(s, t)]:
                        continue
                    bm, nm = statistics.median(b[(s, t)]), statistics.median(n[(s, t)])
                    bn, nn = min(b[(s, t)]), min(n[(s, t)])
                    cmp.append(f"| {input_label(s)} | {t} | {kind} | {bm:.1f} | {nm:.1f} | "
                               f"{nm / bm:.3f} | {bn:.1f} | {nn:.1f} | {nn / bn:.3f} |")
        table += "\n" + "\n".join(cmp) + "\n"
    print()
    print(table)
    if a.markdown:
        with open(a.markdown, "w") as f:
            f.write(table)


if __name__ == "__main__":
    main()
