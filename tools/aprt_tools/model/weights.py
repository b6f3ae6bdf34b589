"""Weights whose outputs really depend on the input, for golden tests.

A freshly initialised APR-Transformer answers almost the same pose for every
image: BatchNorm running statistics are 0/1, so activations explode or vanish
through the trunk, and zero biases hide bias bugs. `vary()` randomises every
affine/bias parameter, then re-estimates BatchNorm statistics on smooth
random images, so that the network's outputs spread with the input.
"""

from __future__ import annotations

import torch
from torch import nn


def smooth_images(n: int, channels: int, size: int, generator: torch.Generator) -> torch.Tensor:
    """Normalised-looking images: low-frequency noise plus some fine texture."""
    coarse = torch.randn(n, channels, max(size // 16, 2), max(size // 16, 2), generator=generator)
    img = nn.functional.interpolate(coarse, size=(size, size), mode="bilinear",
                                    align_corners=False)
    return img + 0.3 * torch.randn(n, channels, size, size, generator=generator)


def point_inputs(n: int, cfg, generator: torch.Generator) -> torch.Tensor:
    """(n, 6, N, 1) network inputs of street-like synthetic scans, made by the
    runtime's preprocessing (lidar_points.py)."""
    import numpy as np

    from ..lidar_points import points_features, synthetic_scene

    rng = np.random.default_rng(int(torch.randint(0, 2**31 - 1, (1,), generator=generator)))
    xs = []
    for _ in range(n):
        f, _ = points_features(synthetic_scene(rng), cfg.points["samples"], cfg.points)
        xs.append(torch.from_numpy(f.T.copy())[:, :, None])
    return torch.stack(xs)


def sample_inputs(n: int, cfg, generator: torch.Generator) -> torch.Tensor:
    """Inputs that look like the modality's: smooth images or preprocessed scans."""
    if cfg.points:
        return point_inputs(n, cfg, generator)
    return smooth_images(n, cfg.in_channels, cfg.image_size, generator)


@torch.no_grad()
def vary(model: nn.Module, seed: int, batches: int = 4, batch_size: int = 4) -> nn.Module:
    gen = torch.Generator().manual_seed(seed)
    for name, p in model.named_parameters():
        if p.dim() == 1:
            if name.endswith("weight"):  # BatchNorm / LayerNorm scales
                p.copy_(1.0 + 0.25 * torch.randn(p.shape, generator=gen))
            else:
                p.copy_(0.1 * torch.randn(p.shape, generator=gen))
    # query embeddings are (1, d): make them clearly non-zero.
    for name, p in model.named_parameters():
        if "query_embed" in name:
            p.copy_(torch.randn(p.shape, generator=gen))
    bns = [m for m in model.modules() if isinstance(m, nn.BatchNorm2d)]
    for bn in bns:
        bn.reset_running_stats()
        bn.momentum = None  # cumulative average over the calibration batches
    model.train()
    cfg = model.cfg
    for _ in range(batches):
        model(sample_inputs(batch_size, cfg, gen))
    model.eval()
    return model
