"""The LiDAR bird's-eye histogram (DESIGN.md 4.2), as the network is trained
with it -- and as the runtime's kernels compute it (kernels/preprocess/lidar__ref.cc,
runtime/base/lidar_point.h; docs/lidar.md): grid x grid cells of cell_m from
(x_min, y_min), row along x, column along y, channel 0 counts points with
z < height_threshold_m, channel 1 the rest; counts clipped to clip_count and
divided by it; NHWC [grid][grid][2]; points off the grid ignored.

Binning as the kernel does it: floor((double(x) - x_min) / cell_m) in double
with the parameters as float32; non-finite points are dropped (the runtime's
point gate does that before the kernel)."""

from __future__ import annotations

import numpy as np

BEV_KEYS = ("cell_m", "x_min", "y_min", "height_threshold_m", "clip_count")


def bev_meta(bev: dict) -> list:
    """The model file's 'bev' record (FORMAT.md key 50)."""
    return [float(bev[k]) for k in BEV_KEYS]


def bev_histogram(points: np.ndarray, grid: int, bev: dict) -> np.ndarray:
    """points [N, >=3] (x, y, z, ...) float32 -> [grid, grid, 2] float32 in [0, 1]."""
    p = np.asarray(points, np.float32).reshape(-1, points.shape[-1])
    x, y, z = p[:, 0], p[:, 1], p[:, 2]
    ok = np.isfinite(x) & np.isfinite(y) & np.isfinite(z)
    x, y, z = x[ok], y[ok], z[ok]
    f = lambda k: float(np.float32(bev[k]))
    cell = f("cell_m")
    r = np.floor((x.astype(np.float64) - f("x_min")) / cell)
    c = np.floor((y.astype(np.float64) - f("y_min")) / cell)
    inside = (r >= 0) & (r < grid) & (c >= 0) & (c < grid)
    ch = (z >= np.float32(bev["height_threshold_m"])).astype(np.int64)
    idx = (r[inside].astype(np.int64) * grid + c[inside].astype(np.int64)) * 2 + ch[inside]
    counts = np.bincount(idx, minlength=grid * grid * 2).astype(np.float32)
    clip = np.float32(bev["clip_count"])
    return (np.minimum(counts, clip) / clip).reshape(grid, grid, 2)


def read_kitti(path: str) -> np.ndarray:
    """A KITTI-style scan: x y z intensity float32, no header."""
    data = np.fromfile(path, "<f4")
    if data.size % 4:
        raise ValueError(f"{path}: {data.size * 4} bytes is not a whole number of points")
    return data.reshape(-1, 4)
