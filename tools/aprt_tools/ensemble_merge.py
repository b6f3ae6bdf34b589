"""An ensemble's members' outputs merged into one network's: the runtime's
runtime/engine/ensemble_merge.cc, line for line, for the calibration and the
evaluation of ensemble files (FORMAT.md 1.5).

A file's output is its n members' 13 outputs side by side. Each network
regresses its quaternion up to sign, and networks trained apart pick
different signs in different places, so the quaternions are turned to the
sign of the member of largest norm before their mean; position and log
scales are plain means. The members' disagreement -- the population
standard deviation of their positions (normalised units) and the root mean
square of their rotations from the merged one (rad, camera axes) -- joins the
network's own sigma in quadrature (confidence.sigmas)."""

from __future__ import annotations

import numpy as np

OUTPUTS = 13


def _rotation_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(N, 4) unit a, b -> (N, 3) axis-angle of conj(a) * b, sign-free: the
    trainer's rotation error (train_loss.rotation_error_vector), in float64."""
    import torch

    from .train_loss import rotation_error_vector

    return rotation_error_vector(torch.from_numpy(np.ascontiguousarray(b)),
                                 torch.from_numpy(np.ascontiguousarray(a))).numpy()


def merge(raw: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(N, 13 n) -> (N, 13) merged outputs, (N, 3) position spread
    (normalised units), (N, 3) rotation spread (rad). One network's (N, 13)
    comes back as it is, with zero spreads."""
    raw = np.asarray(raw, np.float64)
    n_frames, width = raw.shape
    if width % OUTPUTS:
        raise ValueError(f"{width} outputs: not 13 per member")
    n = width // OUTPUTS
    if n == 1:
        return raw, np.zeros((n_frames, 3)), np.zeros((n_frames, 3))
    m = raw.reshape(n_frames, n, OUTPUTS)
    q = m[:, :, 3:7]
    ref = np.take_along_axis(q, np.argmax(np.sum(q * q, axis=2), axis=1)[:, None, None],
                             axis=1)
    sign = np.where(np.sum(q * ref, axis=2) < 0, -1.0, 1.0)
    aligned = m.copy()
    aligned[:, :, 3:7] *= sign[:, :, None]
    out = aligned.mean(axis=1)
    position_sd = m[:, :, :3].std(axis=1)
    mean_q = out[:, 3:7]
    norm = np.linalg.norm(mean_q, axis=1)
    ok = norm > 1e-6
    unit = mean_q / np.where(ok, norm, 1.0)[:, None]
    sq = np.zeros((n_frames, 3))
    for i in range(n):
        qi = q[:, i]
        ni = np.linalg.norm(qi, axis=1)
        d = _rotation_between(unit, qi / np.where(ni > 1e-6, ni, 1.0)[:, None])
        sq += np.where((ni > 1e-6)[:, None], d * d, np.inf)
    rotation_sd = np.where(ok[:, None], np.sqrt(sq / n), 0.0)
    # As the runtime's float outputs.
    return out.astype(np.float32).astype(np.float64), position_sd, rotation_sd
