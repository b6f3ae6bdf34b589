"""Post-training int8 quantisation of a converted model (issue #4).

    python3 -m aprt_tools quantize model.aprt --calibration FRAMES -o model_int8.aprt

1. Calibration: the fp32 graph (engine_ir semantics, the runtime's) runs over
   the calibration frames -- a DeepLoc-layout folder (poses.txt + images, or
   just images) preprocessed exactly as the runtime does; for a LiDAR BEV
   model a LiDAR sequence (lidar_poses.txt + KITTI scans) as histograms with
   the model's geometry; or a .npy of preprocessed inputs [N, H, W, C] -- and
   the input values of every op the policy makes int8 are collected.
2. Ranges per activation tensor (uint8, asymmetric, per tensor): `minmax`,
   `percentile` (the p-th percentile of |values| at either end) or `mse` (the
   clipping range that minimises the quantisation error of the collected
   values). Weights: int8, symmetric, per output channel (max |w| / 127).
3. Policy: LINEAR ops of more than one row outside the backbone (the
   transformers' projections and feed-forward layers) become int8; everything
   else -- the backbone (found from the graph: whatever leads to a depthwise
   convolution or squeeze-excite, the 1x1 convolutions right after one, and the
   input projections reading its feature maps; `--backbone` makes its 1x1 and depthwise convolutions int8 too,
   at a measured accuracy cost, see docs/int8.md), LayerNorm, attention, GELU, the single-row decoder and the
   pose heads -- stays fp32. `--fp32-ops REGEX` keeps more ops in fp32 by name. The policy is written into the file as the
   int8 dtype of each chosen op's weights, and described in the 'quantization'
   metadata.
"""

from __future__ import annotations

import glob
import json
import os
import re
from dataclasses import dataclass, field

import numpy as np

from ..model_bin import spec
from ..model_bin.reader import read
from ..model_bin.writer import serialise
from . import engine_ir
from .engine_ir import Tensor

METHODS = ("minmax", "percentile", "mse")
_SAMPLES_PER_FRAME = 1 << 16  # values kept per op and frame for percentile / mse


class CalibrationError(ValueError):
    """The calibration data cannot be used; the message says why."""


# ---------------------------------------------------------------------------
# Calibration frames.


def _image_files(folder: str) -> list:
    poses = os.path.join(folder, "poses.txt")
    if os.path.exists(poses):
        from ..dataset import read_poses

        try:
            return [os.path.join(folder, name) for name, _, _ in read_poses(folder)]
        except ValueError as e:
            raise CalibrationError(f"calibration: {e}") from None
    files = []
    for pattern in ("*.png", "*.jpg", "*.jpeg", "images/*.png", "images/*.jpg"):
        files += glob.glob(os.path.join(folder, pattern))
    return sorted(files)


def _prepare_image(path: str, meta: dict) -> np.ndarray:
    import torch
    from PIL import Image
    from torch.nn import functional as F

    from ..preprocess import crop_resize

    _, h, w, c = meta["input_shape"]
    try:
        with Image.open(path) as im:
            rgb = np.asarray(im.convert("RGB"))
    except OSError as e:
        raise CalibrationError(f"calibration: cannot read image {path}: {e}") from None
    if c != 3 or h != w:
        raise CalibrationError(f"calibration: images need a 3-channel square input; the model "
                               f"takes {h}x{w}x{c} (pass preprocessed tensors as .npy)")
    if meta.get("resize_policy", spec.RESIZE_SHORTER_THEN_CENTER_CROP) == spec.RESIZE_STRETCH:
        x = torch.from_numpy(rgb.copy()).permute(2, 0, 1).float().unsqueeze(0) / 255.0
        x = F.interpolate(x, size=(h, w), mode="bilinear", align_corners=False)[0]
    else:
        x = crop_resize(rgb, h)
    mean = torch.tensor(meta["norm_mean"]).view(-1, 1, 1)
    std = torch.tensor(meta["norm_std"]).view(-1, 1, 1)
    return ((x - mean) / std).permute(1, 2, 0).numpy()[None].astype(np.float32)


def _lidar_inputs(folder: str, meta: dict, limit: int) -> list:
    """A LiDAR sequence (lidar_poses.txt + scans) as a LiDAR model's inputs: BEV
    histograms or sampled points, with the model's own geometry."""
    from ..dataset import read_poses
    from ..lidar_bev import BEV_KEYS, bev_histogram, read_kitti
    from ..lidar_points import POINTS_KEYS, points_features

    if "bev" not in meta and "points" not in meta:
        raise CalibrationError("calibration: a LiDAR sequence calibrates a LiDAR model only; this "
                               "model has neither 'bev' nor 'points' geometry")
    try:
        names = [n for n, _, _ in read_poses(folder, "lidar_poses.txt")]
    except ValueError as e:
        raise CalibrationError(f"calibration: {e}") from None
    bev = dict(zip(BEV_KEYS, meta["bev"])) if "bev" in meta else None
    grid = meta["input_shape"][1]  # BEV: the grid side; points: the sample count
    mean = np.asarray(meta["norm_mean"], np.float32)
    std = np.asarray(meta["norm_std"], np.float32)
    out = []
    for i in np.unique(np.linspace(0, len(names) - 1, min(limit, len(names))).astype(int)):
        try:
            scan = read_kitti(os.path.join(folder, names[i]))
        except (OSError, ValueError) as e:
            raise CalibrationError(f"calibration: {e}") from None
        if "points" in meta:  # [1, N, 1, 6]
            f, _ = points_features(scan, grid, dict(zip(POINTS_KEYS, meta["points"])), mean, std)
            out.append(f[None, :, None, :].astype(np.float32))
            continue
        h = bev_histogram(scan, grid, bev)
        out.append(((h - mean) / std)[None].astype(np.float32))
    return out


def load_calibration(path: str, meta: dict, limit: int) -> list:
    """Calibration inputs as [1, H, W, C] float32 arrays (at most `limit`, spread evenly)."""
    shape = tuple(meta["input_shape"])
    if not os.path.exists(path):
        raise CalibrationError(f"calibration: {path} does not exist")
    if os.path.isdir(path) and meta.get("modality") in (spec.MODALITY_LIDAR_BEV,
                                                        spec.MODALITY_LIDAR_POINTS):
        if not os.path.exists(os.path.join(path, "lidar_poses.txt")):
            raise CalibrationError(f"calibration: {path} has no lidar_poses.txt (a LiDAR model "
                                   "calibrates on LiDAR scans, or on a .npy of its inputs)")
        return _lidar_inputs(path, meta, limit)
    if os.path.isdir(path):
        files = _image_files(path)
        if not files:
            raise CalibrationError(f"calibration: {path} holds no images (png/jpg, or poses.txt "
                                   "naming them)")
        pick = np.unique(np.linspace(0, len(files) - 1, min(limit, len(files))).astype(int))
        return [_prepare_image(files[i], meta) for i in pick]
    try:
        arr = np.load(path, allow_pickle=False)
    except (OSError, ValueError) as e:
        raise CalibrationError(f"calibration: {path} is neither a folder of images nor a .npy "
                               f"array: {e}") from None
    if arr.ndim == 3:
        arr = arr[None]
    if arr.ndim != 4 or tuple(arr.shape[1:]) != shape[1:]:
        raise CalibrationError(f"calibration: {path} has shape {list(arr.shape)}; the model's "
                               f"input is [N, {shape[1]}, {shape[2]}, {shape[3]}] (NHWC, "
                               "preprocessed)")
    if arr.shape[0] == 0:
        raise CalibrationError(f"calibration: {path} holds no frames")
    if not np.isfinite(arr).all():
        raise CalibrationError(f"calibration: {path} has non-finite values")
    pick = np.unique(np.linspace(0, arr.shape[0] - 1, min(limit, arr.shape[0])).astype(int))
    return [arr[i:i + 1].astype(np.float32) for i in pick]


# ---------------------------------------------------------------------------
# Ranges.


@dataclass
class Observed:
    lo: float = np.inf
    hi: float = -np.inf
    samples: list = field(default_factory=list)

    def add(self, x: np.ndarray, rng: np.random.Generator):
        x = x.reshape(-1)
        self.lo, self.hi = min(self.lo, float(x.min())), max(self.hi, float(x.max()))
        if x.size > _SAMPLES_PER_FRAME:
            x = rng.choice(x, _SAMPLES_PER_FRAME, replace=False)
        self.samples.append(x.astype(np.float32))


def _affine(lo: float, hi: float):
    lo, hi = min(lo, 0.0), max(hi, 0.0)  # zero must be exact (padding, ReLU)
    scale = max((hi - lo) / 255.0, 1e-8)
    zero = int(np.clip(np.rint(-lo / scale), 0, 255))
    return float(np.float32(scale)), zero


def _qerror(v: np.ndarray, scale: float, zero: int) -> float:
    q = engine_ir.quantize_u8(v, scale, zero)
    return float(np.mean(((q - zero) * scale - v) ** 2))


def choose_range(obs: Observed, method: str, percentile: float):
    """(scale, zero point) for one activation tensor."""
    if method == "minmax":
        return _affine(obs.lo, obs.hi)
    v = np.concatenate(obs.samples)
    if method == "percentile":
        lo, hi = np.percentile(v, [100.0 - percentile, percentile])
        return _affine(float(lo), float(hi))
    # mse: shrink the min-max range step by step; keep the best.
    best, best_err = _affine(obs.lo, obs.hi), np.inf
    for frac in np.linspace(1.0, 0.3, 36):
        cand = _affine(obs.lo * frac, obs.hi * frac)
        err = _qerror(v, *cand)
        if err < best_err:
            best, best_err = cand, err
    return best


def quantize_weights(w: np.ndarray):
    """int8 symmetric per output channel: (q [N, K] int8, scales [N] f32 > 0)."""
    w = np.asarray(w, np.float32)
    amax = np.abs(w).max(axis=1)
    scales = np.where(amax > 0, amax / 127.0, 1.0).astype(np.float32)
    q = np.clip(np.rint(w / scales[:, None]), -127, 127).astype(np.int8)
    return q, scales


# ---------------------------------------------------------------------------
# The policy and the rewrite.


def backbone_ops(eg) -> set:
    """ids of the convolutional backbone's ops, found from the graph's structure:
    every op from which a depthwise convolution or squeeze-excite is reachable,
    the 1x1 convolutions (LINEAR) that read such an op's output directly, and
    the LINEAR ops reading the backbone's feature maps (the input projections:
    measured to cost the most accuracy of the non-backbone ops, docs/int8.md)."""
    conv = (spec.OP_DWCONV2D, spec.OP_SQUEEZE_EXCITE)
    producer = {id(t): op for op in eg.ops for t in op.outputs}
    reach = set()
    for op in reversed(eg.ops):  # consumers come later: one backward pass suffices
        if op.code in conv or any(id(u) in reach for t in op.outputs for u in eg.users(t)):
            reach.add(id(op))
    for op in eg.ops:
        src = producer.get(id(op.inputs[0]))
        if op.code == spec.OP_LINEAR and src is not None and src.code in conv:
            reach.add(id(op))
    readers = [op for op in eg.ops if op.code == spec.OP_LINEAR and id(op) not in reach and
               id(producer.get(id(op.inputs[0]))) in reach]
    return reach | {id(op) for op in readers}


def int8_candidates(eg, fp32_ops: str | None, backbone: bool = False) -> list:
    keep = re.compile(fp32_ops) if fp32_ops else None
    skip = set() if backbone else backbone_ops(eg)
    out = []
    for op in eg.ops:
        if op.inputs[1].dtype != spec.DTYPE_F32 or (keep and keep.search(op.name)):
            continue
        if op.code == spec.OP_DWCONV2D and backbone:
            out.append(op)
            continue
        if op.code != spec.OP_LINEAR or id(op) in skip:
            continue
        rows = int(np.prod(op.inputs[0].shape[:-1]))
        if rows <= 1:  # single-row decoder and heads: no gain, only error
            continue
        out.append(op)
    return out


def _pose_dev(a: np.ndarray, b: np.ndarray, meta: dict):
    """Position (m) and rotation (deg) apart of two outputs of one model (an
    ensemble's merged first, as the runtime merges them)."""
    from ..ensemble_merge import merge

    if a.size > 13 and a.size % 13 == 0:
        a, b = merge(a.reshape(1, -1))[0][0], merge(b.reshape(1, -1))[0][0]
    span = np.asarray(meta["pose_max"]) - np.asarray(meta["pose_min"])
    dp = float(np.linalg.norm((a[:3] - b[:3]) * span))
    qa, qb = a[3:7] / np.linalg.norm(a[3:7]), b[3:7] / np.linalg.norm(b[3:7])
    dq = float(np.degrees(2 * np.arccos(np.clip(abs(float(qa @ qb)), 0.0, 1.0))))
    return dp, dq


@dataclass
class QuantReport:
    ops: list = field(default_factory=list)  # (name, rows, k, n, scale, zero)
    frames: int = 0
    deviation_m: list = field(default_factory=list)
    deviation_deg: list = field(default_factory=list)
    sensitivity: list = field(default_factory=list)  # (op, max m, max deg) with it alone int8
    attention: list = field(default_factory=list)  # ATTENTION ops with int8 scores, or in bf16
    attention_precision: str = "int8 scores"

    def text(self) -> str:
        dm, dd = np.asarray(self.deviation_m), np.asarray(self.deviation_deg)
        att = (f" (+ {len(self.attention)} attentions, {self.attention_precision})"
               if self.attention else "")
        return (f"{len(self.ops)} ops int8{att}, calibrated on {self.frames} frames; "
                f"int8 vs fp32 on those frames: position p50 {np.median(dm):.4f} / max "
                f"{dm.max():.4f} m, orientation p50 {np.median(dd):.4f} / max {dd.max():.4f} deg")


def quantize_model(data: bytes, calibration: str, *, method: str = "percentile",
                   percentile: float = 99.99, frames: int = 64, fp32_ops: str | None = None,
                   backbone: bool = False, sensitivity: bool = False, seed: int = 0,
                   int8_attention: bool = False, bf16_attention: bool = False):
    """fp32 model_bin bytes -> (int8 model_bin bytes, QuantReport)."""
    if int8_attention and bf16_attention:
        raise CalibrationError("calibration: attention int8 or bf16, not both")
    if method not in METHODS:
        raise CalibrationError(f"calibration: method {method!r} (one of {', '.join(METHODS)})")
    if not 50.0 < percentile <= 100.0:
        raise CalibrationError(f"calibration: percentile {percentile} (50 < p <= 100)")
    if frames < 1:
        raise CalibrationError(f"calibration: {frames} frames (at least 1)")
    eg, meta = read(data)
    if "quantization" in meta:
        raise CalibrationError("calibration: the model is already quantised; start from fp32")
    inputs = load_calibration(calibration, meta, frames)
    ops = int8_candidates(eg, fp32_ops, backbone)
    if not ops:
        raise CalibrationError("calibration: no op qualifies for int8 under this policy")
    inp = next(t for t in eg.tensors if t.kind == spec.KIND_INPUT)
    out = next(t for t in eg.tensors if t.kind == spec.KIND_OUTPUT)
    rng = np.random.default_rng(seed)
    observed = {id(op): Observed() for op in ops}
    fp32_out = []
    for x in inputs:
        vals = engine_ir.run(eg, {inp: x})
        for op in ops:
            observed[id(op)].add(vals[id(op.inputs[0])], rng)
        fp32_out.append(vals[id(out)].reshape(-1))
    report = QuantReport(frames=len(inputs))
    plans = {}
    for op in ops:
        scale, zero = choose_range(observed[id(op)], method, percentile)
        w = op.inputs[1]
        if op.code == spec.OP_DWCONV2D:  # [KH, KW, C]: channels last
            q, scales = quantize_weights(w.data.reshape(-1, w.shape[-1]).T)
            q = np.ascontiguousarray(q.T.reshape(w.shape))
        else:
            q, scales = quantize_weights(w.data)
        qs = eg.add(Tensor(w.name + ".qscale", (len(scales),), spec.KIND_CONST, scales))
        qw = eg.add(Tensor(w.name + ".int8", w.shape, spec.KIND_CONST, q, dtype=spec.DTYPE_I8,
                           qscale=qs))
        plans[id(op)] = (w, qw, scale, zero)

    def set_int8(op, on: bool):
        w, qw, scale, zero = plans[id(op)]
        op.inputs[1] = qw if on else w
        if on:
            op.params.update(input_scale=scale, input_zero=zero)
        else:
            op.params.pop("input_scale", None)
            op.params.pop("input_zero", None)

    def deviations():
        dm, dd = [], []
        for x, ref in zip(inputs, fp32_out):
            got = engine_ir.run(eg, {inp: x})[id(out)].reshape(-1)
            m, d = _pose_dev(np.asarray(got, np.float64), np.asarray(ref, np.float64), meta)
            dm.append(m)
            dd.append(d)
        return dm, dd

    if sensitivity:  # each op alone in int8: which ones cost accuracy
        for op in ops:
            set_int8(op, True)
            dm, dd = deviations()
            set_int8(op, False)
            report.sensitivity.append((op.name, float(np.max(dm)), float(np.max(dd))))
    for op in ops:
        set_int8(op, True)
        w, _, scale, zero = plans[id(op)]
        k, n = (int(np.prod(w.shape[:-1])), w.shape[-1]) if op.code == spec.OP_DWCONV2D else \
            (w.shape[1], w.shape[0])
        report.ops.append((op.name, int(np.prod(op.inputs[0].shape[:-1])), k, n, scale, zero))
    if int8_attention or bf16_attention:
        # Q K^T in int8 (dynamic per row and head; FORMAT.md), softmax and P V fp32; or
        # Q, K, V and the weights in bf16, softmax fp32.
        keep = re.compile(fp32_ops) if fp32_ops else None
        for op in eg.ops:
            if op.code == spec.OP_ATTENTION and not (keep and keep.search(op.name)):
                op.params["scores"] = 1 if int8_attention else 2
                report.attention.append(op.name)
        report.attention_precision = "int8 scores" if int8_attention else "bf16"
    eg.prune()
    report.deviation_m, report.deviation_deg = deviations()
    # Insertion order: what `aprt info` shows first (method, data, policy), the op list last.
    meta["quantization"] = json.dumps(dict(
        method=method, percentile=percentile if method == "percentile" else None,
        calibration=os.path.basename(os.path.normpath(calibration)), frames=len(inputs),
        policy=("LINEAR of more than one row" + (", backbone 1x1 and depthwise included"
                                                 if backbone else
                                                 ", backbone and input projections fp32") +
                (f", fp32 by name: {fp32_ops}" if fp32_ops else "") +
                (", attention scores int8 (Q and K per row and head)" if int8_attention else "") +
                (", attention in bf16 (Q, K, V and the weights)" if bf16_attention else "")),
        scheme="u8 activations per tensor (asymmetric), s8 weights per channel (symmetric), "
               "int32 accumulation",
        int8_ops=[r[0] for r in report.ops],
        **{"bf16_attention" if bf16_attention else "int8_attention": report.attention}))
    return serialise(eg, meta), report
