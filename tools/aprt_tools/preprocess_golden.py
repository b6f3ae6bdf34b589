"""Frames in every supported pixel format and what the training transform makes of
them, for the runtime's preprocessing tests (tests/unit/preprocess_test.cc).

For each case: <case>.raw (the frame bytes), <case>.f32 (expected NHWC input
tensor), and a line in cases.txt: "case format width height stride size".
YUV frames are converted to RGB with the integer BT.601 formula of
runtime/base/image.h before the transform, exactly as the runtime does.
Also writes rgb.png, whose expected tensor is png.f32 (decoder + transform),
and LiDAR scans with the BEV histogram the training uses (lidar_bev.py):
bev_<k>.bin (KITTI), bev_<k>.f32, and a line in bev.txt:
"name grid cell_m x_min y_min height_threshold_m clip_count".
"""

from __future__ import annotations

import os

import numpy as np
from PIL import Image

from .preprocess import prepare


def yuv_to_rgb(y, u, v):
    c, d, e = y.astype(np.int32) - 16, u.astype(np.int32) - 128, v.astype(np.int32) - 128
    r = (298 * c + 409 * e + 128) >> 8
    g = (298 * c - 100 * d - 208 * e + 128) >> 8
    b = (298 * c + 516 * d + 128) >> 8
    return np.clip(np.stack([r, g, b], -1), 0, 255).astype(np.uint8)


def write_cases(out: str, seed: int = 3):
    os.makedirs(out, exist_ok=True)
    rng = np.random.default_rng(seed)
    lines = []

    def emit(name, fmt, raw, rgb, w, h, stride, size):
        raw.astype(np.uint8).tofile(os.path.join(out, name + ".raw"))
        t = prepare(rgb, size).permute(1, 2, 0).contiguous().numpy().astype("<f4")
        t.tofile(os.path.join(out, name + ".f32"))
        lines.append(f"{name} {fmt} {w} {h} {stride} {size}")

    for (w, h, size) in ((64, 48, 32), (50, 75, 37), (40, 40, 40), (33, 21, 64)):
        rgb = rng.integers(0, 256, (h, w, 3), dtype=np.uint8)
        emit(f"rgb_{w}x{h}_{size}", "RGB24", rgb, rgb, w, h, w * 3, size)
        emit(f"bgr_{w}x{h}_{size}", "BGR24", rgb[:, :, ::-1], rgb, w, h, w * 3, size)
        gray = rng.integers(0, 256, (h, w), dtype=np.uint8)
        emit(f"gray_{w}x{h}_{size}", "GRAY8", gray, np.repeat(gray[:, :, None], 3, 2), w, h, w, size)
        if w % 2 == 0:
            y = rng.integers(16, 236, (h, w), dtype=np.uint8)
            u = rng.integers(16, 241, (h, w // 2), dtype=np.uint8)
            v = rng.integers(16, 241, (h, w // 2), dtype=np.uint8)
            rgb_yuv = yuv_to_rgb(y, np.repeat(u, 2, 1), np.repeat(v, 2, 1))
            yuyv = np.stack([y[:, 0::2], u, y[:, 1::2], v], -1).reshape(h, w * 2)
            uyvy = np.stack([u, y[:, 0::2], v, y[:, 1::2]], -1).reshape(h, w * 2)
            emit(f"yuyv_{w}x{h}_{size}", "YUYV", yuyv, rgb_yuv, w, h, w * 2, size)
            emit(f"uyvy_{w}x{h}_{size}", "UYVY", uyvy, rgb_yuv, w, h, w * 2, size)
            if h % 2 == 0:
                u2 = rng.integers(16, 241, (h // 2, w // 2), dtype=np.uint8)
                v2 = rng.integers(16, 241, (h // 2, w // 2), dtype=np.uint8)
                up = lambda p: np.repeat(np.repeat(p, 2, 0), 2, 1)
                rgb12 = yuv_to_rgb(y, up(u2), up(v2))
                uv = np.stack([u2, v2], -1).reshape(h // 2, w)
                emit(f"nv12_{w}x{h}_{size}", "NV12", np.concatenate([y, uv], 0), rgb12, w, h, w, size)
    with open(os.path.join(out, "cases.txt"), "w") as f:
        f.write("\n".join(lines) + "\n")
    rgb = rng.integers(0, 256, (30, 52, 3), dtype=np.uint8)
    Image.fromarray(rgb).save(os.path.join(out, "rgb.png"))
    prepare(rgb, 24).permute(1, 2, 0).contiguous().numpy().astype("<f4").tofile(
        os.path.join(out, "png.f32"))
    write_bev_cases(out, rng)
    write_points_cases(out, rng)
    return len(lines)


def write_bev_cases(out: str, rng):
    from .lidar_bev import bev_histogram

    lines = []
    for k, (grid, cell, x0, y0, thr, clip, n) in enumerate((
            (16, 0.5, -4.0, -4.0, -1.0, 3.0, 2000),
            (64, 0.125, -4.0, -3.0, 0.25, 5.0, 20000),
            (33, 0.3, -6.0, -2.5, -1.4, 1.0, 500))):
        pts = np.zeros((n, 4), np.float32)
        pts[:, 0] = rng.uniform(x0 - 2, x0 + grid * cell + 2, n)
        pts[:, 1] = rng.uniform(y0 - 2, y0 + grid * cell + 2, n)
        pts[:, 2] = rng.uniform(-3, 3, n)
        pts[:, 3] = rng.uniform(0, 1, n)
        # Points exactly on cell edges and on the height threshold, and clusters
        # that exceed the clip count.
        m = n // 10
        pts[:m, 0] = x0 + cell * rng.integers(0, grid, m)
        pts[:m, 1] = y0 + cell * rng.integers(0, grid, m)
        pts[m:2 * m, 2] = thr
        pts[2 * m:3 * m, :2] = pts[3 * m, :2]
        pts.tofile(os.path.join(out, f"bev_{k}.bin"))
        bev = dict(cell_m=cell, x_min=x0, y_min=y0, height_threshold_m=thr, clip_count=clip)
        bev_histogram(pts, grid, bev).astype("<f4").tofile(os.path.join(out, f"bev_{k}.f32"))
        lines.append(f"bev_{k} {grid} {cell!r} {x0!r} {y0!r} {thr!r} {clip!r}")
    with open(os.path.join(out, "bev.txt"), "w") as f:
        f.write("\n".join(lines) + "\n")


def write_points_cases(out: str, rng):
    """Scans and the raw-points input the training makes of them (lidar_points.py):
    points_<k>.bin (KITTI), points_<k>.f32 ([samples][6]), a line in points.txt:
    name samples crop_radius_m coord_scale_m enough(0/1). Cases: a street scene
    with points beyond the crop; exact duplicates and points on the crop
    circle; fewer points than samples (padded, not enough); NaN and Inf points."""
    from .lidar_points import points_features, synthetic_scene

    lines = []
    for k, (samples, radius, scale) in enumerate(((256, 20.0, 20.0), (512, 12.5, 10.0),
                                                   (300, 20.0, 25.0), (64, 8.0, 8.0))):
        pts = synthetic_scene(rng, n=6000 if k != 2 else 600, radius=25.0)
        if k == 1:
            pts[:200] = pts[200:400]  # duplicates: distance ties in the sampler
            ang = rng.uniform(0, 2 * np.pi, 50)
            pts[400:450, 0] = np.float32(radius) * np.cos(ang).astype(np.float32)
            pts[400:450, 1] = np.float32(radius) * np.sin(ang).astype(np.float32)
        if k == 2:
            pts = pts[np.hypot(pts[:, 0], pts[:, 1]) < radius][:200]  # fewer than the samples
        if k == 3:
            pts[::7, 0] = np.nan
            pts[3::11, 2] = np.inf
        pts = pts.astype(np.float32)
        pts.tofile(os.path.join(out, f"points_{k}.bin"))
        cfg = dict(crop_radius_m=radius, coord_scale_m=scale)
        f, ok = points_features(pts, samples, cfg)
        f.astype("<f4").tofile(os.path.join(out, f"points_{k}.f32"))
        lines.append(f"points_{k} {samples} {radius!r} {scale!r} {int(ok)}")
    with open(os.path.join(out, "points.txt"), "w") as f:
        f.write("\n".join(lines) + "\n")
