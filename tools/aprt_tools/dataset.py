"""Labelled sequences in the DeepLoc layout: poses.txt ("name x y z qw qx qy qz")
beside the images it names."""

from __future__ import annotations

import math
import os

import numpy as np
from PIL import Image


def read_poses(folder: str, filename: str = "poses.txt"):
    """[(name, position[3], quaternion wxyz[4])], in file order (lidar_poses.txt for
    LiDAR sequences)."""
    path = os.path.join(folder, filename)
    out = []
    with open(path) as f:
        for n, line in enumerate(f, 1):
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            parts = line.split()
            if len(parts) != 8:
                raise ValueError(f"{path}:{n}: expected 'name x y z qw qx qy qz', got {line!r}")
            vals = [float(v) for v in parts[1:]]
            if not all(math.isfinite(v) for v in vals):
                raise ValueError(f"{path}:{n}: non-finite pose")
            out.append((parts[0], np.array(vals[:3]), np.array(vals[3:])))
    if not out:
        raise ValueError(f"{path}: no poses")
    return out


def load_image(folder: str, name: str) -> np.ndarray:
    with Image.open(os.path.join(folder, name)) as im:
        return np.asarray(im.convert("RGB"))


def position_error(p, q):
    return float(np.linalg.norm(np.asarray(p) - np.asarray(q)))


def orientation_error_deg(q1, q2):
    """Angle of the rotation between two unit quaternions (sign-invariant)."""
    a = np.asarray(q1, float)
    b = np.asarray(q2, float)
    a = a / np.linalg.norm(a)
    b = b / np.linalg.norm(b)
    d = min(1.0, abs(float(np.dot(a, b))))
    return math.degrees(2 * math.acos(d))
