"""Latency histogram and time series from `aprt run --timing FILE.json` (matplotlib).

Reads the JSON report and the per-pose CSV beside it; draws the end-to-end and
inference latency histograms (log-count, with median / p99 / p99.9 marked) and
the per-frame time series, and puts the report's figures in the title.

  python3 -m aprt_tools plot-timing report.json --out timing.png
"""

from __future__ import annotations

import csv
import json
import os

import numpy as np


class TimingReportError(ValueError):
    pass


def read_report(json_path: str):
    try:
        with open(json_path) as f:
            report = json.load(f)
    except json.JSONDecodeError as e:
        raise TimingReportError(f"{json_path}: not JSON ({e})") from None
    if "stages_ms" not in report:
        raise TimingReportError(f"{json_path}: no stages_ms (is it an `aprt run --timing` report?)")
    csv_path = os.path.splitext(json_path)[0] + ".csv"
    if not os.path.exists(csv_path):
        raise TimingReportError(f"{csv_path}: missing (written beside the JSON by aprt run --timing)")
    with open(csv_path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        raise TimingReportError(f"{csv_path}: no timed poses")
    col = {k: np.array([int(r[k]) for r in rows], dtype=np.int64)
           for k in ("capture_ns", "inference_start_ns", "inference_end_ns", "publish_ns")}
    series = dict(end_to_end=(col["publish_ns"] - col["capture_ns"]) * 1e-6,
                  inference=(col["inference_end_ns"] - col["inference_start_ns"]) * 1e-6,
                  capture_s=(col["capture_ns"] - col["capture_ns"][0]) * 1e-9)
    return report, series


def plot_timing(json_path: str, out: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    report, s = read_report(json_path)
    fig, (hist, ts) = plt.subplots(2, 1, figsize=(10, 8))
    top = max(float(np.percentile(s["end_to_end"], 99.9)) * 1.3, 1e-3)
    bins = np.linspace(0, top, 80)
    for key, colour in (("end_to_end", "tab:blue"), ("inference", "tab:orange")):
        hist.hist(np.minimum(s[key], top), bins=bins, alpha=0.6, color=colour,
                  label=key.replace("_", " "))
        st = report["stages_ms"][key]
        for q, style in (("median", "-"), ("p99", "--"), ("p99.9", ":")):
            hist.axvline(st[q], color=colour, ls=style, lw=1)
    hist.set_yscale("log")
    hist.set_xlabel("latency [ms] (median —, p99 --, p99.9 ··; the last bin holds everything above)")
    hist.set_ylabel("poses")
    hist.legend()
    hist.grid(alpha=0.3)
    ts.plot(s["capture_s"], s["end_to_end"], lw=0.6, color="tab:blue", label="end to end")
    ts.plot(s["capture_s"], s["inference"], lw=0.6, color="tab:orange", label="inference")
    deadline = report.get("jitter", {}).get("inference_deadline_ms", 0)
    top_ts = float(s["end_to_end"].max()) * 1.15
    if deadline and deadline <= 2 * top_ts:  # far above the data it would flatten the series
        ts.axhline(deadline, color="tab:red", lw=1, label=f"inference deadline {deadline:g} ms")
        top_ts = max(top_ts, deadline * 1.05)
    ts.set_ylim(0, top_ts)
    ts.set_xlabel("capture time [s]")
    ts.set_ylabel("latency [ms]")
    ts.legend(loc="upper right")
    ts.grid(alpha=0.3)
    e2e = report["stages_ms"]["end_to_end"]
    fr = report["frames"]
    mem = report.get("memory", {})
    fig.suptitle(
        f"{os.path.basename(report['model'])} on {report['isa']} ({report['threads']} thread(s)): "
        f"end to end median {e2e['median']:.2f} ms, p99.9 {e2e['p99.9']:.2f} ms, "
        f"max {e2e['max']:.2f} ms\n{fr['poses']} poses, {fr['deadline_misses']} deadline misses, "
        f"{fr['dropped_stale']} dropped; allocations after the first pose: "
        f"{mem.get('allocations_after_first_pose')}", fontsize=10)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)
