"""Training data: labelled sequences (images, LiDAR BEV histograms, LiDAR
points) loaded into memory as the network sees them, the photometric
augmentation, the held-out stretch."""

from __future__ import annotations

import math
import os

import numpy as np
import torch

from .dataset import load_image, read_poses
from .preprocess import crop_resize, normalise


def load_sequence(folder: str, size: int):
    poses = read_poses(folder)
    imgs = torch.empty((len(poses), 3, size, size), dtype=torch.uint8)
    for i, (name, _, _) in enumerate(poses):
        imgs[i] = (crop_resize(load_image(folder, name), size) * 255.0 + 0.5).clamp(0, 255).to(torch.uint8)
    pos = torch.tensor(np.stack([p for _, p, _ in poses]), dtype=torch.float32)
    quat = torch.tensor(np.stack([q / np.linalg.norm(q) for _, _, q in poses]), dtype=torch.float32)
    return imgs, pos, quat


def load_lidar_sequence(folder: str, grid: int, bev: dict):
    """LiDAR scans (lidar_poses.txt + KITTI .bin) as BEV histograms stored like
    images: uint8 = round(255 * value); the clip counts used here (1..255
    dividing 255 or not) come back as value = round(255 k / clip) / 255."""
    from .lidar_bev import bev_histogram, read_kitti

    poses = read_poses(folder, "lidar_poses.txt")
    imgs = torch.empty((len(poses), 2, grid, grid), dtype=torch.uint8)
    for i, (name, _, _) in enumerate(poses):
        h = bev_histogram(read_kitti(os.path.join(folder, name)), grid, bev)
        imgs[i] = torch.from_numpy(np.rint(h * 255.0).astype(np.uint8)).permute(2, 0, 1)
    pos = torch.tensor(np.stack([p for _, p, _ in poses]), dtype=torch.float32)
    quat = torch.tensor(np.stack([q / np.linalg.norm(q) for _, _, q in poses]), dtype=torch.float32)
    return imgs, pos, quat


def load_points_sequence(folder: str, points: dict, log=print, inputs: str | None = None,
                         every: int = 1):
    """LiDAR scans (lidar_poses.txt + KITTI .bin) as the raw-points input
    (lidar_points.py: crop, farthest-point sampling, features): float32
    (N, 6, samples, 1), computed once (no augmentation for LiDAR). With
    `inputs`, the array `aprt inputs --every EVERY` wrote of the same sequence
    (the runtime's own preprocessing, the same values, ~15x faster)."""
    from .lidar_bev import read_kitti
    from .lidar_points import points_features_many

    poses = read_poses(folder, "lidar_poses.txt")[::every]
    if inputs:
        arr = np.load(inputs, mmap_mode="r")
        want = (len(poses), points["samples"], 1, 6)
        if tuple(arr.shape) != want:
            raise ValueError(f"{inputs} has shape {list(arr.shape)}; {folder} with every {every} "
                             f"and {points['samples']} samples needs {list(want)} (aprt inputs "
                             f"--model MODEL --data {folder} --every {every})")
        feats = np.ascontiguousarray(arr[:, :, 0, :], np.float32)
        log(f"train: {len(poses)} scans' inputs from {inputs}")
    else:
        feats = np.zeros((len(poses), points["samples"], 6), np.float32)
        chunk = 256
        for a in range(0, len(poses), chunk):
            scans = [read_kitti(os.path.join(folder, name)) for name, _, _ in poses[a:a + chunk]]
            feats[a:a + chunk], _ = points_features_many(scans, points["samples"], points)
            log(f"train: sampled {min(a + chunk, len(poses))}/{len(poses)} scans")
    x = torch.from_numpy(feats).permute(0, 2, 1).unsqueeze(-1).contiguous()
    pos = torch.tensor(np.stack([p for _, p, _ in poses]), dtype=torch.float32)
    quat = torch.tensor(np.stack([q / np.linalg.norm(q) for _, _, q in poses]), dtype=torch.float32)
    return x, pos, quat


def network_input(frames: torch.Tensor, cfg) -> torch.Tensor:
    """What the network sees of stored frames: points as they are; images and
    histograms stored as uint8, scaled and normalised."""
    if cfg.points:
        return frames
    return normalise(frames.float() / 255.0, cfg.mean, cfg.std)


# RGB <-> YIQ (NTSC): Y is the luma, (I, Q) the chroma plane that a hue
# rotation turns and a saturation change scales.
_RGB_TO_YIQ = torch.tensor([[0.299, 0.587, 0.114],
                            [0.596, -0.274, -0.322],
                            [0.211, -0.523, 0.312]])
_YIQ_TO_RGB = torch.linalg.inv(_RGB_TO_YIQ)


def chroma_matrices(hue_rad: torch.Tensor, saturation: torch.Tensor) -> torch.Tensor:
    """(N,) hue rotations and saturation factors -> (N, 3, 3) RGB colour matrices
    that keep the luma: the chroma plane turned by the hue and scaled."""
    n = hue_rad.shape[0]
    c, s = torch.cos(hue_rad) * saturation, torch.sin(hue_rad) * saturation
    m = torch.zeros(n, 3, 3)
    m[:, 0, 0] = 1.0
    m[:, 1, 1], m[:, 1, 2], m[:, 2, 1], m[:, 2, 2] = c, -s, s, c
    return _YIQ_TO_RGB @ m @ _RGB_TO_YIQ


def augment(x: torch.Tensor, gen: torch.Generator, strength: float = 1.0,
            chroma: bool = False) -> torch.Tensor:
    """x: (N, 3, S, S) in [0, 1]; lighting and sensor changes, never geometry.

    strength in [0, 1] blends between the clean and the fully augmented image.
    chroma: also turn the hue (+-25 deg) and scale the saturation (0.2-1.4, a
    tenth of the frames grey), so that a place is not known by its facade
    colours alone: an unseen light (dusk's orange sun, purple sky) moves them.
    Off by default, which keeps the random stream of runs made without it."""
    if strength <= 0.0:
        return x
    clean = x
    n = x.shape[0]
    r = lambda *shape: torch.rand(*shape, generator=gen)
    gain = 0.75 + 0.5 * r(n, 3, 1, 1)
    bright = 0.5 + 0.8 * r(n, 1, 1, 1)
    # White balance: a colour-temperature shift, warm (a low sun: red up, blue
    # down to 0.6) or cool (shade), correlated across the channels as light is;
    # independent gains alone reach a red/blue ratio of 1.7, a low sun's is ~3.
    temp = 2 * r(n, 1, 1, 1) - 1
    white = torch.cat([1 + 0.2 * temp, torch.ones_like(temp), 1 - 0.4 * temp], dim=1)
    x = x * gain * bright * white
    if chroma:
        hue = (2 * r(n) - 1) * math.radians(25.0)
        sat = torch.where(r(n) < 0.1, torch.zeros(n), 0.2 + 1.2 * r(n))
        x = torch.einsum("nij,njhw->nihw", chroma_matrices(hue, sat), x)
    mean = x.mean(dim=(1, 2, 3), keepdim=True)
    x = (x - mean) * (0.6 + 0.8 * r(n, 1, 1, 1)) + mean
    haze = 0.35 * r(n, 1, 1, 1)
    haze_color = 0.4 + 0.5 * r(n, 3, 1, 1)
    x = x * (1 - haze) + haze_color * haze
    x = x.clamp(0, 1) ** (0.8 + 0.45 * r(n, 1, 1, 1))
    x = x + 0.02 * torch.randn(x.shape, generator=gen)
    return (clean + strength * (x.clamp(0, 1) - clean)).clamp(0, 1)


def split_holdout(n: int, fraction: float = 0.1):
    """Train / validation indices: a contiguous stretch of the route is held out."""
    k = max(1, int(n * fraction))
    start = (n - k) // 2
    val = np.arange(start, start + k)
    train = np.concatenate([np.arange(0, max(0, start - 5)), np.arange(start + k + 5, n)])
    return train, val


def _load(folders, modality, size, cfg, log, inputs, inputs_every):
    """The frames, positions and quaternions of one or more sequences, concatenated."""
    parts = []
    for folder in folders:
        if modality == "bev":
            parts.append(load_lidar_sequence(folder, size, cfg.bev))
        elif modality == "points":
            parts.append(load_points_sequence(folder, cfg.points, log, inputs, inputs_every))
        else:
            parts.append(load_sequence(folder, size))
    if len(parts) == 1:
        return parts[0]
    return tuple(torch.cat([p[k] for p in parts]) for k in range(3))
