"""odometry.txt for a labelled sequence: the speed and yaw rate its vehicle's
bus would have carried (wheel odometry and a gyro), with their errors.

The poses are the camera's; base_link (the vehicle's reference point, the
rear axle for aprt_synth's drives) sits `camera_to_base_link` behind it
(dataset.json, or --camera-xy). Between frames k and k+1 the vehicle's base
moves along an arc: the sample at frame k holds its speed along the heading
and its yaw rate until frame k+1 (what drivers/input/odometry.h integrates).
Any sideways motion of the base (the renderer's lane weaving) is not in the
samples -- a real vehicle's odometry cannot see it either -- and counts as
odometry error to the filter.

The errors, each drawn once per drive or per sample from --seed:
  speed    scale error uniform in +-scale (tyre radius), plus white noise
  yaw rate bias uniform in +-bias (a gyro's), plus white noise
The clock is the sequence's: times.txt, or 25 Hz without one (the runtime's
assumption for such a sequence)."""

from __future__ import annotations

import json
import math
import os

import numpy as np

from .dataset import read_poses

FRAME_PERIOD_S = 0.04  # a sequence without times.txt: 25 Hz


def _yaw(q) -> float:
    w, x, y, z = q
    return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


def _times(folder: str, names: list) -> np.ndarray:
    path = os.path.join(folder, "times.txt")
    if not os.path.exists(path):
        return np.arange(len(names)) * FRAME_PERIOD_S
    t = {}
    with open(path) as f:
        for line in f:
            parts = line.split()
            if len(parts) == 2 and not parts[0].startswith("#"):
                t[parts[0]] = float(parts[1])
    missing = [n for n in names if n not in t]
    if missing:
        raise ValueError(f"{path} has no time for {missing[0]} ({len(missing)} frames)")
    return np.array([t[n] for n in names])


def camera_xy(folder: str) -> tuple[float, float]:
    """The camera's x, y on base_link from dataset.json (0, 0 without one)."""
    path = os.path.join(folder, "dataset.json")
    if not os.path.exists(path):
        return 0.0, 0.0
    with open(path) as f:
        xyz = json.load(f).get("camera_to_base_link", {}).get("xyz", [0.0, 0.0, 0.0])
    return float(xyz[0]), float(xyz[1])


def odometry(folder: str, speed_scale: float = 0.01, speed_noise: float = 0.05,
             yaw_rate_bias_dps: float = 0.2, yaw_rate_noise_dps: float = 0.5, seed: int = 1,
             camera: tuple[float, float] | None = None) -> np.ndarray:
    """[N, 3]: seconds, speed (m/s), yaw rate (rad/s) at each frame's time."""
    if min(speed_scale, speed_noise, yaw_rate_bias_dps, yaw_rate_noise_dps) < 0:
        raise ValueError("the error magnitudes must not be negative")
    poses = read_poses(folder)
    names = [n for n, _, _ in poses]
    t = _times(folder, names)
    cx, cy = camera if camera is not None else camera_xy(folder)
    yaw = np.array([_yaw(q) for _, _, q in poses])
    cam = np.array([p[:2] for _, p, _ in poses])
    # base_link = camera - R(yaw) (cx, cy)
    base = cam - np.stack([np.cos(yaw) * cx - np.sin(yaw) * cy,
                           np.sin(yaw) * cx + np.cos(yaw) * cy], axis=1)
    n = len(poses)
    speed = np.zeros(n)
    rate = np.zeros(n)
    for k in range(n - 1):
        dt = t[k + 1] - t[k]
        if not dt > 0:
            raise ValueError(f"frame {names[k + 1]}: time {t[k + 1]} is not after {t[k]}")
        dyaw = (yaw[k + 1] - yaw[k] + math.pi) % (2 * math.pi) - math.pi
        d = base[k + 1] - base[k]
        # The chord's part along the mean heading; an arc with that chord is
        # longer by (a/2)/sin(a/2) for a turn of a.
        mid = yaw[k] + dyaw / 2
        along = math.cos(mid) * d[0] + math.sin(mid) * d[1]
        arc = along * ((dyaw / 2) / math.sin(dyaw / 2) if abs(dyaw) > 1e-9 else 1.0)
        speed[k] = arc / dt
        rate[k] = dyaw / dt
    if n > 1:
        speed[-1], rate[-1] = speed[-2], rate[-2]
    rng = np.random.default_rng(seed)
    scale = 1 + rng.uniform(-speed_scale, speed_scale)
    bias = math.radians(rng.uniform(-yaw_rate_bias_dps, yaw_rate_bias_dps))
    speed = speed * scale + rng.normal(0, speed_noise, n) if speed_noise > 0 else speed * scale
    rate = rate + bias + (rng.normal(0, math.radians(yaw_rate_noise_dps), n)
                          if yaw_rate_noise_dps > 0 else 0)
    return np.stack([t, speed, rate], axis=1)


def write_odometry(folder: str, out: str | None = None, **kw) -> tuple[str, np.ndarray]:
    """Writes odometry.txt (or `out`); returns its path and the samples."""
    samples = odometry(folder, **kw)
    path = out or os.path.join(folder, "odometry.txt")
    args = " ".join(f"{k}={v}" for k, v in sorted(kw.items()) if v is not None)
    with open(path, "w") as f:
        f.write("# seconds speed_mps yaw_rate_radps (python3 -m aprt_tools odometry"
                f"{' ' + args if args else ''})\n")
        for s in samples:
            f.write(f"{s[0]:.6f} {s[1]:.5f} {s[2]:.6f}\n")
    return path, samples
