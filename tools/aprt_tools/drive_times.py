"""Recorded times for a labelled sequence that has none: a speed profile a
vehicle could drive along its poses (times.txt: "name seconds" per frame).

The synthetic drives are sampled every metre, and replayed at a fixed rate
they pass a corner of 4-9 m radius as fast as a straight (25 m/s at 25 Hz:
no vehicle does). The profile here caps the speed on straights, slows for
curves by a lateral-acceleration limit, and bounds the acceleration and the
braking between them (a forward and a backward pass); the times follow from
the distances. `aprt eval --rate recorded` and the replay's `rate_hz:
recorded` then give the validity gate the clock of such a drive. The poses
and frames are unchanged."""

from __future__ import annotations

import math
import os

import numpy as np

from .dataset import read_poses


def speed_profile(xy: np.ndarray, max_speed: float, lateral_accel: float,
                  accel: float) -> np.ndarray:
    """Speed (m/s) at each of the positions xy [N, 2] along the path."""
    n = len(xy)
    v = np.full(n, max_speed)
    if n < 3:
        return v
    # Heading over +-2 frames (a frame's own jitter is not a curve), and its
    # change per metre between the neighbours: the curvature.
    k = 2
    idx = np.arange(n)
    ahead, behind = np.minimum(idx + k, n - 1), np.maximum(idx - k, 0)
    d = xy[ahead] - xy[behind]
    heading = np.arctan2(d[:, 1], d[:, 0])
    dh = np.abs((heading[np.minimum(idx + 1, n - 1)] - heading[np.maximum(idx - 1, 0)] + math.pi)
                % (2 * math.pi) - math.pi)
    ds = np.linalg.norm(xy[np.minimum(idx + 1, n - 1)] - xy[np.maximum(idx - 1, 0)], axis=1)
    curvature = dh / np.maximum(ds, 1e-6)
    v = np.minimum(v, np.sqrt(lateral_accel / np.maximum(curvature, 1e-9)))
    step = np.linalg.norm(np.diff(xy, axis=0), axis=1)
    for i in range(1, n):  # accelerate no faster than `accel`
        v[i] = min(v[i], math.sqrt(v[i - 1] ** 2 + 2 * accel * step[i - 1]))
    for i in range(n - 2, -1, -1):  # and brake no harder
        v[i] = min(v[i], math.sqrt(v[i + 1] ** 2 + 2 * accel * step[i]))
    return v


def drive_times(folder: str, max_speed: float = 13.9, lateral_accel: float = 3.0,
                accel: float = 2.0, filename: str = "poses.txt") -> tuple[list, np.ndarray]:
    """The names of `filename` and their times (s, from 0)."""
    if not (max_speed > 0 and lateral_accel > 0 and accel > 0):
        raise ValueError("speed, lateral acceleration and acceleration must be positive")
    poses = read_poses(folder, filename)
    xy = np.array([p[:2] for _, p, _ in poses], np.float64)
    v = speed_profile(xy, max_speed, lateral_accel, accel)
    step = np.linalg.norm(np.diff(xy, axis=0), axis=1)
    dt = step / np.maximum(0.5 * (v[1:] + v[:-1]), 1e-6)
    dt = np.maximum(dt, 1e-3)  # strictly increasing even where two poses coincide
    t = np.concatenate([[0.0], np.cumsum(dt)])
    return [name for name, _, _ in poses], t


def write_drive_times(folder: str, out: str | None = None, **kw) -> tuple[str, np.ndarray]:
    """Writes times.txt (or `out`); returns its path and the times."""
    names, t = drive_times(folder, **kw)
    path = out or os.path.join(folder, "times.txt")
    with open(path, "w") as f:
        for name, s in zip(names, t):
            f.write(f"{name} {s:.6f}\n")
    return path, t
