"""The image transform the network is trained with -- and that the runtime's
preprocessing kernel reproduces (docs/preprocessing.md):

1. crop the centred square of side min(W, H) (offset (W - side) // 2, (H - side) // 2);
2. resize it to S x S, bilinear, half-pixel centres (align_corners=False, no
   antialiasing), in float, from 8-bit values scaled to [0, 1];
3. normalise per channel: (v - mean) / std.
"""

from __future__ import annotations

import numpy as np
import torch
from torch.nn import functional as F

from .model.apr_transformer import IMAGENET_MEAN, IMAGENET_STD


def crop_resize(rgb: np.ndarray, size: int) -> torch.Tensor:
    """uint8 HxWx3 -> float32 3xSxS in [0, 1]."""
    h, w = rgb.shape[:2]
    side = min(h, w)
    y0, x0 = (h - side) // 2, (w - side) // 2
    sq = torch.from_numpy(np.ascontiguousarray(rgb[y0:y0 + side, x0:x0 + side]))
    x = sq.permute(2, 0, 1).float().unsqueeze(0) / 255.0
    if side != size:
        x = F.interpolate(x, size=(size, size), mode="bilinear", align_corners=False)
    return x[0]


def normalise(x: torch.Tensor, mean=None, std=None) -> torch.Tensor:
    mean = IMAGENET_MEAN if mean is None else mean
    std = IMAGENET_STD if std is None else std
    m = torch.tensor(mean, dtype=x.dtype).view(-1, 1, 1)
    s = torch.tensor(std, dtype=x.dtype).view(-1, 1, 1)
    return (x - m) / s


def prepare(rgb: np.ndarray, size: int) -> torch.Tensor:
    return normalise(crop_resize(rgb, size))
