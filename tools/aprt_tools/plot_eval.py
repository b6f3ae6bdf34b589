"""Trajectory and error plots from `aprt eval --csv` files (matplotlib, no display).

One CSV gives the paper-style figure: ground-truth track (x/y in metres, map
frame) with the predicted positions over it, coloured by their error, and the
per-frame position / orientation error below. Several CSVs (fp32 and int8,
two models) are drawn side by side with their labels.

  python3 -m aprt_tools plot-eval run.csv [int8.csv ...] --out plot.png [--labels fp32,int8]
"""

from __future__ import annotations

import csv

import numpy as np


class EvalCsvError(ValueError):
    pass


REQUIRED = ("x", "y", "gt_x", "gt_y", "position_error_m", "orientation_error_deg")


def read_eval_csv(path: str) -> dict:
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        raise EvalCsvError(f"{path}: no frames (is it an `aprt eval --csv` file?)")
    missing = [k for k in REQUIRED if k not in rows[0]]
    if missing:
        raise EvalCsvError(f"{path}: missing column(s) {', '.join(missing)} "
                           "(expected the header written by `aprt eval --csv`)")
    out = {}
    for k in REQUIRED:
        try:
            out[k] = np.array([float(r[k]) for r in rows])
        except ValueError as e:
            raise EvalCsvError(f"{path}: column {k}: {e}") from None
    return out


def summary(d: dict) -> str:
    pe, oe = d["position_error_m"], d["orientation_error_deg"]
    return (f"median {np.median(pe):.2f} m / {np.median(oe):.2f}°, "
            f"p90 {np.percentile(pe, 90):.2f} m / {np.percentile(oe, 90):.2f}°")


def plot_eval(paths: list, out: str, labels: list | None = None, title: str | None = None) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels = labels or [p.rsplit("/", 1)[-1].rsplit(".", 1)[0] for p in paths]
    if len(labels) != len(paths):
        raise EvalCsvError(f"{len(labels)} labels for {len(paths)} CSV files")
    runs = [read_eval_csv(p) for p in paths]
    n = len(runs)
    fig = plt.figure(figsize=(6.0 * n, 8.5))
    grid = fig.add_gridspec(2, n, height_ratios=(3, 1.2))
    for i, (d, label) in enumerate(zip(runs, labels)):
        ax = fig.add_subplot(grid[0, i])
        ax.plot(d["gt_x"], d["gt_y"], color="0.2", lw=1.2, label="ground truth", zorder=1)
        # Colour scale saturates at the p90 error so a few outliers do not wash it out.
        vmax = max(1e-3, float(np.percentile(d["position_error_m"], 90)))
        sc = ax.scatter(d["x"], d["y"], c=d["position_error_m"], s=7, cmap="plasma", vmin=0,
                        vmax=vmax, label="predicted", zorder=2)
        fig.colorbar(sc, ax=ax, fraction=0.046, pad=0.03, label="position error [m]")
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel("x east [m]")
        ax.set_ylabel("y north [m]")
        ax.set_title(f"{label}\n{summary(d)}", fontsize=10)
        ax.legend(loc="best", fontsize=8)
        ax.grid(alpha=0.3)
        ex = fig.add_subplot(grid[1, i])
        frames = np.arange(len(d["x"]))
        ex.plot(frames, d["position_error_m"], color="tab:blue", lw=0.8)
        ex.set_xlabel("frame")
        ex.set_ylabel("position error [m]", color="tab:blue")
        ex.grid(alpha=0.3)
        ex2 = ex.twinx()
        ex2.plot(frames, d["orientation_error_deg"], color="tab:red", lw=0.8)
        ex2.set_ylabel("orientation error [°]", color="tab:red")
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


