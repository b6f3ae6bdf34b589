"""Trajectory and error plots from `aprt eval --csv` files (matplotlib, no display).

One CSV gives the paper-style figure: ground-truth track (x/y in metres, map
frame; the start and the direction marked) with the predicted positions over
it, coloured by their error on one colour scale for every panel, the poses the
validity gate withheld marked with a cross, and the per-frame position /
orientation error below; the headline gives the medians, the share of frames
more than 10 m off, and how many went out valid. With --dataset (a synthetic
drive's dataset.json) the town's streets are drawn beneath. Several CSVs (fp32
and int8, two models, two drives) are drawn side by side with their labels.
With --published the pose that went out is drawn instead of the model's
estimate: the pose filter's where `aprt eval` ran it (sanity.filter; the
CSV's published_* columns).

  python3 -m aprt_tools plot-eval run.csv [int8.csv ...] --out plot.png [--labels fp32,int8]
                                  [--dataset DRIVE/dataset.json]
"""

from __future__ import annotations

import csv

import numpy as np


class EvalCsvError(ValueError):
    pass


REQUIRED = ("x", "y", "gt_x", "gt_y", "position_error_m", "orientation_error_deg")
# --published: the pose that went out, under the names the plot uses.
PUBLISHED = {"x": "published_x", "y": "published_y",
             "position_error_m": "published_position_error_m",
             "orientation_error_deg": "published_orientation_error_deg"}


def read_eval_csv(path: str, published: bool = False) -> dict:
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        raise EvalCsvError(f"{path}: no frames (is it an `aprt eval --csv` file?)")
    missing = [k for k in REQUIRED if k not in rows[0]]
    if missing:
        raise EvalCsvError(f"{path}: missing column(s) {', '.join(missing)} "
                           "(expected the header written by `aprt eval --csv`)")
    if published and PUBLISHED["x"] not in rows[0]:
        raise EvalCsvError(f"{path}: no published_* columns (written by `aprt eval --csv` of "
                           "this version)")
    out = {}
    for k in REQUIRED + (("flags",) if "flags" in rows[0] else ()):
        column = PUBLISHED.get(k, k) if published else k
        try:
            out[k] = np.array([float(r[column]) for r in rows])
        except ValueError as e:
            raise EvalCsvError(f"{path}: column {k}: {e}") from None
    return out


def summary(d: dict) -> str:
    pe, oe = d["position_error_m"], d["orientation_error_deg"]
    text = (f"median {np.median(pe):.2f} m / {np.median(oe):.2f}°, "
            f"{100 * np.mean(pe > 10):.1f} % > 10 m")
    if "flags" in d:
        valid = d["flags"] == 0
        wrong = int(np.sum(valid & (pe > 10)))
        text += f"\n{100 * np.mean(valid):.1f} % valid, {wrong} valid > 10 m"
    return text


def town_streets(dataset: str):
    """The synthetic town's street centre lines and road width from a drive's
    dataset.json (aprt_synth), or None for another kind of drive."""
    import json

    with open(dataset) as f:
        meta = json.load(f)
    if meta.get("generator") != "aprt_synth":
        return None
    extent = float(meta.get("town_extent_m", 200.0))
    spacing = float(meta.get("street_spacing_m", 50.0))
    width = float(meta.get("road_width_m", 10.0))
    lines = [c for c in np.arange(0.0, extent + 1e-6, spacing)]
    return lines, extent, width


def plot_eval(paths: list, out: str, labels: list | None = None, title: str | None = None,
              dataset: str | None = None, published: bool = False) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels = labels or [p.rsplit("/", 1)[-1].rsplit(".", 1)[0] for p in paths]
    if len(labels) != len(paths):
        raise EvalCsvError(f"{len(labels)} labels for {len(paths)} CSV files")
    runs = [read_eval_csv(p, published) for p in paths]
    streets = town_streets(dataset) if dataset else None
    # One colour scale for every panel: they compare. It saturates at the
    # largest p90 so a few outliers do not wash it out.
    vmax = max(1e-3, max(float(np.percentile(d["position_error_m"], 90)) for d in runs))
    n = len(runs)
    fig = plt.figure(figsize=(6.0 * n, 8.5))
    grid = fig.add_gridspec(2, n, height_ratios=(3, 1.2))
    for i, (d, label) in enumerate(zip(runs, labels)):
        ax = fig.add_subplot(grid[0, i])
        if streets:
            lines, extent, width = streets
            for c in lines:
                ax.plot([c, c], [0, extent], color="0.88", lw=width * 0.6, solid_capstyle="butt",
                        zorder=0)
                ax.plot([0, extent], [c, c], color="0.88", lw=width * 0.6, solid_capstyle="butt",
                        zorder=0)
        ax.plot(d["gt_x"], d["gt_y"], color="0.2", lw=1.2, label="ground truth", zorder=1)
        valid = d["flags"] == 0 if "flags" in d else np.ones(len(d["x"]), bool)
        what = "published" if published else "predicted"
        sc = ax.scatter(d["x"][valid], d["y"][valid], c=d["position_error_m"][valid], s=7,
                        cmap="plasma", vmin=0, vmax=vmax, label=f"{what} (valid)", zorder=2)
        if not valid.all():
            ax.scatter(d["x"][~valid], d["y"][~valid], c=d["position_error_m"][~valid], s=14,
                       cmap="plasma", vmin=0, vmax=vmax, marker="x", lw=0.8,
                       label=f"{what} (withheld)", zorder=2)
        ax.plot(d["gt_x"][0], d["gt_y"][0], marker="o", color="tab:green", ms=8, zorder=3,
                label="start")
        k = min(len(d["gt_x"]) - 1, 8)
        if k > 0:
            ax.annotate("", xy=(d["gt_x"][k], d["gt_y"][k]), xytext=(d["gt_x"][0], d["gt_y"][0]),
                        arrowprops=dict(arrowstyle="->", color="tab:green", lw=2), zorder=3)
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


