"""The raw-points input (DESIGN.md 4.3), as the network is trained with it --
and as the runtime computes it (kernels/preprocess/lidar__ref.cc, lidar_points_features;
docs/lidar.md):

1. crop: keep points with x*x + y*y <= r*r (float32), in scan order;
2. farthest-point sampling of N points (the input's H): index 0 first, then
   the point farthest (squared distance (dx*dx + dy*dy) + dz*dz, float32) from
   all chosen, the lowest index on ties; a scan with fewer points than N
   repeats its sampled sequence and is flagged low-confidence; an empty one
   gives all-zero features, flagged;
3. features per sampled point, float32: absolute p / s and relative
   (p - c) / s, with s the coordinate scale and c the sampled points' mean
   (summed in float64, rounded to float32), then (f - mean) / std per channel
   with the model's normalisation.

Non-finite points never reach this (the runtime's point gate drops them; so
does this module)."""

from __future__ import annotations

import numpy as np

POINTS_KEYS = ("crop_radius_m", "coord_scale_m")


def points_meta(points: dict) -> list:
    """The model file's 'points' record (FORMAT.md key 51)."""
    return [float(points[k]) for k in POINTS_KEYS]


def radius_crop(p: np.ndarray, radius: float) -> np.ndarray:
    p = np.asarray(p, np.float32)
    r = np.float32(radius)
    keep = p[:, 0] * p[:, 0] + p[:, 1] * p[:, 1] <= r * r
    return p[keep]


def fps(p: np.ndarray, count: int) -> tuple[np.ndarray, bool]:
    """Indices (count,) and whether the scan had enough points."""
    n = len(p)
    if n == 0:
        return np.zeros(count, np.int64), False
    take = min(n, count)
    x, y, z = (np.ascontiguousarray(p[:, k], np.float32) for k in range(3))
    dist = np.full(n, np.inf, np.float32)
    idx = np.zeros(count, np.int64)
    last = 0
    for s in range(1, take):
        dx, dy, dz = x - x[last], y - y[last], z - z[last]
        dist = np.minimum(dist, (dx * dx + dy * dy) + dz * dz)
        last = int(np.argmax(dist))
        idx[s] = last
    for s in range(take, count):
        idx[s] = idx[s - take]
    return idx, n >= count


def _features(sel: np.ndarray, points: dict, mean=None, std=None) -> np.ndarray:
    """Sampled points [samples, 3] -> [samples, 6]: p / s, (p - mean of the samples) / s."""
    s = np.float32(points["coord_scale_m"])
    c = sel.astype(np.float64).mean(axis=0).astype(np.float32)
    f = np.concatenate([sel / s, (sel - c) / s], axis=1).astype(np.float32)
    if mean is not None:
        f = (f - np.asarray(mean, np.float32)) / np.asarray(std, np.float32)
    return f.astype(np.float32)


def _cropped(scan, points: dict) -> np.ndarray:
    p = np.asarray(scan, np.float32).reshape(-1, np.shape(scan)[-1])[:, :3]
    return radius_crop(p[np.isfinite(p).all(axis=1)], points["crop_radius_m"])


def points_features(scan: np.ndarray, samples: int, points: dict, mean=None,
                    std=None) -> tuple[np.ndarray, bool]:
    """scan [M, >=3] float32 (sensor frame) -> features [samples, 6] float32, ok."""
    p = _cropped(scan, points)
    if len(p) == 0:
        return np.zeros((samples, 6), np.float32), False
    idx, ok = fps(p, samples)
    return _features(p[idx], points, mean, std), ok


def points_features_many(scans, samples: int, points: dict, batch: int = 32):
    """points_features of many scans -> features [len, samples, 6], ok [len]; the
    farthest-point sampling of scans with enough points runs batched through
    the network's own sampler (model/point_ops.fps_indices: the same arithmetic
    and tie rule as fps(), so the same indices), the rest one by one."""
    import torch

    from .model.point_ops import fps_indices

    feats = np.zeros((len(scans), samples, 6), np.float32)
    oks = np.zeros(len(scans), bool)
    cropped = []
    for i, scan in enumerate(scans):
        p = _cropped(scan, points)
        if len(p) < samples:
            feats[i], oks[i] = points_features(scan, samples, points)
        else:
            cropped.append((i, p))
    for b in range(0, len(cropped), batch):
        part = cropped[b:b + batch]
        n = max(len(p) for _, p in part)
        # Padding repeats each scan's first point: distance 0 to the first pick,
        # so never chosen while any real point is farther (len >= samples).
        pad = np.stack([np.concatenate([p, np.repeat(p[:1], n - len(p), 0)]) for _, p in part])
        idx = fps_indices(torch.from_numpy(pad), samples).numpy()
        for j, (i, p) in enumerate(part):
            feats[i], oks[i] = _features(p[idx[j]], points), True
    return feats, oks


def synthetic_scene(rng: np.random.Generator, n: int = 20000, radius: float = 25.0) -> np.ndarray:
    """A street-like scan for tests and golden data: a ground plane below the
    sensor (its height and tilt vary), box-shaped buildings (from none to a
    dense street) and poles at random places, noise. Scenes differ in layout
    and density, so that a network's outputs differ between them."""
    parts = []
    ground = rng.uniform(-2.4, -1.4)
    tilt = rng.uniform(-0.05, 0.05, 2)
    g = rng.uniform(-radius, radius, size=(int(n * rng.uniform(0.2, 0.6)), 2))
    parts.append(np.c_[g, ground + g @ tilt + 0.03 * rng.standard_normal(len(g))])
    for _ in range(int(rng.integers(0, 14))):
        cx, cy = rng.uniform(-radius, radius, 2)
        w, d, h = rng.uniform(2, 14), rng.uniform(2, 14), rng.uniform(2, 20)
        m = int(n * rng.uniform(0.02, 0.1))
        face = rng.integers(0, 4, m)
        u, v = rng.uniform(0, 1, m), rng.uniform(0, 1, m)
        x = np.where(face < 2, cx + (face - 0.5) * w, cx + (u - 0.5) * w)
        y = np.where(face >= 2, cy + (face - 2.5) * d, cy + (u - 0.5) * d)
        parts.append(np.c_[x, y, ground + v * h])
    for _ in range(int(rng.integers(0, 12))):
        cx, cy = rng.uniform(-radius, radius, 2)
        m = int(rng.integers(50, 400))
        parts.append(np.c_[cx + 0.1 * rng.standard_normal(m), cy + 0.1 * rng.standard_normal(m),
                           ground + rng.uniform(0, 6, m)])
    pts = np.concatenate(parts).astype(np.float32)
    return np.c_[pts, rng.uniform(0, 1, len(pts)).astype(np.float32)]
