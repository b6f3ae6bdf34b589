"""Calibrating the per-pose confidence (model_bin 1.3, 'uncertainty').

The confidence heads (AprConfig.uncertainty) regress, for every frame, the
log scale s of a Laplace distribution of the error on each position axis
(normalised units) and each rotation axis (radians, camera frame). A head
trained on the training drives is over-confident on drives it has not seen,
so its scales are multiplied by two factors fitted on the validation drive:

  k_pos  so that 95 % of the validation frames' horizontal position errors
         lie inside the 95 % ellipse: (ex/sx)^2 + (ey/sy)^2 <= 5.991 (chi^2,
         2 degrees of freedom), s = k_pos * sqrt(2) * exp(s_head) * extent;
  k_rot  so that 95 % of the yaw errors (rotation about the camera's z axis)
         lie within 1.96 sigma.

The test drive is never used here; `aprt eval` reports the coverage there.

  python3 -m aprt_tools confidence MODEL.aprt --val DRIVE [-o OUT.aprt]
"""

from __future__ import annotations

import math

import numpy as np
import torch

from .ensemble_merge import merge

CHI2_2D_95 = 5.991464547107979
Z_95 = 1.959963984540054


def sigmas(raw: np.ndarray, pose_min, pose_max, k_pos: float = 1.0, k_rot: float = 1.0):
    """(N, 13) network outputs -> position sigma (N, 3) m, rotation sigma (N, 3) rad.
    An ensemble's (N, 13 n) outputs are merged first, and the members' spread
    joins the network's own sigma in quadrature, as the runtime does
    (pose_decode.cc)."""
    raw, position_sd, rotation_sd = merge(raw)
    s = np.clip(raw[:, 7:13], -14.0, 6.0)
    extent = np.asarray(pose_max, np.float64) - np.asarray(pose_min, np.float64)
    b = math.sqrt(2.0) * np.exp(s)
    position = np.sqrt(b[:, :3] ** 2 + position_sd ** 2) * extent
    return k_pos * position, k_rot * np.sqrt(b[:, 3:] ** 2 + rotation_sd ** 2)


def rotation_errors(q_pred: np.ndarray, q_true: np.ndarray) -> np.ndarray:
    """(N, 3) axis-angle of conj(q_true) * q_pred in the camera frame (z: yaw)."""
    from .train_loss import rotation_error_vector

    return rotation_error_vector(torch.from_numpy(np.asarray(q_pred, np.float32)),
                                 torch.from_numpy(np.asarray(q_true, np.float32))).numpy()


def fit(raw: np.ndarray, pos_true: np.ndarray, quat_true: np.ndarray, pose_min, pose_max,
        coverage: float = 0.95):
    """The two calibration factors on one drive, and the coverage each gives."""
    lo, hi = np.asarray(pose_min), np.asarray(pose_max)
    pose = merge(raw)[0]
    pos = pose[:, :3] * (hi - lo) + lo
    sp, sr = sigmas(raw, pose_min, pose_max)
    e = pos - pos_true
    d2 = (e[:, 0] / sp[:, 0]) ** 2 + (e[:, 1] / sp[:, 1]) ** 2
    k_pos = math.sqrt(float(np.quantile(d2, coverage)) / CHI2_2D_95)
    yaw = np.abs(rotation_errors(pose[:, 3:7], quat_true)[:, 2])
    k_rot = float(np.quantile(yaw / sr[:, 2], coverage)) / Z_95
    return max(k_pos, 1e-3), max(k_rot, 1e-3)


def coverage(raw, pos_true, quat_true, pose_min, pose_max, k_pos, k_rot):
    """Shares of frames inside the published 95 % regions: horizontal position, yaw."""
    lo, hi = np.asarray(pose_min), np.asarray(pose_max)
    pose = merge(raw)[0]
    pos = pose[:, :3] * (hi - lo) + lo
    sp, sr = sigmas(raw, pose_min, pose_max, k_pos, k_rot)
    e = pos - pos_true
    d2 = (e[:, 0] / sp[:, 0]) ** 2 + (e[:, 1] / sp[:, 1]) ** 2
    yaw = np.abs(rotation_errors(pose[:, 3:7], quat_true)[:, 2])
    return float(np.mean(d2 <= CHI2_2D_95)), float(np.mean(yaw <= Z_95 * sr[:, 2]))


@torch.no_grad()
def outputs_on(model, cfg, folder: str, batch: int = 64):
    """The network's raw outputs on a labelled drive of the model's modality
    (camera frames, or LiDAR scans as the model's BEV histogram or points),
    with its truth."""
    from .train_data import _load, network_input

    modality = "points" if cfg.points else "bev" if cfg.bev else "image"
    imgs, pos, quat = _load([folder], modality, cfg.image_size, cfg, print, None, 1)
    model.eval()
    out = []
    for i in range(0, len(imgs), batch):
        out.append(model(network_input(imgs[i:i + batch], cfg)).double().numpy())
    return np.concatenate(out), pos.double().numpy(), quat.double().numpy()


def calibrate_file(data: bytes, val: str):
    """A model file with confidence outputs -> (the file with its calibration, report)."""
    from .model_bin import reader, to_torch
    from .model_bin.writer import serialise

    graph, meta = reader.read(data)
    out = next(t for t in graph.tensors if t.kind == 4)
    if int(np.prod(out.shape)) != 13:
        raise ValueError("the model has no confidence outputs (7 values, not 13): train it with "
                         "--uncertainty")
    meta.pop("uncertainty", None)
    cfg = to_torch.config_of(meta)
    model, _ = to_torch.load(data, None)
    raw, pos, quat = outputs_on(model, cfg, val)
    k_pos, k_rot = fit(raw, pos, quat, cfg.pose_min, cfg.pose_max)
    cov = coverage(raw, pos, quat, cfg.pose_min, cfg.pose_max, k_pos, k_rot)
    meta["uncertainty"] = [k_pos, k_rot]
    report = (f"k_position {k_pos:.3f}, k_rotation {k_rot:.3f} on {len(raw)} frames of {val}: "
              f"{100 * cov[0]:.1f} % of horizontal position errors and {100 * cov[1]:.1f} % of "
              "yaw errors inside the 95 % regions")
    return serialise(graph, meta), report
