"""The raw-points trunk of APR-Transformer (DESIGN.md 4.3): PointNet++ with
height-grouped grid tokens.

The paper names the pieces and leaves the details open; this file fixes them
and is the definition the runtime follows (docs/lidar.md):

- input: (B, 6, N, 1) -- N points (farthest-point sampled from the scan,
  lidar_points.py), channels x, y, z divided by the coordinate scale
  ("absolute") and the same minus their mean ("relative");
- four set-abstraction levels (single scale, Qi et al. 2017): farthest-point
  sampling of the level's centroids from the previous level's points, a ball
  query of `nsample` neighbours within `radius` (normalised units), the
  neighbours' coordinates relative to the centroid ++ their features through
  a shared MLP (1 x 1 convolution, BatchNorm, ReLU), max over the neighbours;
- feature propagation from the deepest level back to the first (1024
  points): inverse-distance interpolation from the 3 nearest coarser points,
  ++ the level's own features, a shared MLP; the propagation to the input
  points and the segmentation head of PointNet++ are not there;
- tokens: the first level's points split into `groups` by height and each
  group into a gx x gy grid by x and y, max-pooled per cell (point_ops.py);
  learned positional encodings along the three axes, summed (height, x, y
  tables of d_model each).
"""

from __future__ import annotations

import torch
from torch import nn

from . import point_ops as ops


def points_config(tiny: bool = False) -> dict:
    """The 'points' configuration (DESIGN.md 4.3: 20 m crop, 4096 points,
    1024/256/64/16 centroids, 8 x 4 x 4 tokens), or a small one for tests."""
    if tiny:
        return dict(crop_radius_m=20.0, coord_scale_m=20.0, samples=512,
                    sa=[dict(npoint=128, radius=0.15, nsample=8, mlp=[16, 16, 32]),
                        dict(npoint=64, radius=0.3, nsample=8, mlp=[32, 32, 48]),
                        dict(npoint=16, radius=0.6, nsample=8, mlp=[48, 48, 64]),
                        dict(npoint=8, radius=1.0, nsample=8, mlp=[64, 64, 64])],
                    fp=[[64, 64], [64, 48], [48, 40]],
                    tokens=dict(groups=8, gx=4, gy=4))
    return dict(crop_radius_m=20.0, coord_scale_m=20.0, samples=4096,
                sa=[dict(npoint=1024, radius=0.1, nsample=32, mlp=[32, 32, 64]),
                    dict(npoint=256, radius=0.2, nsample=32, mlp=[64, 64, 128]),
                    dict(npoint=64, radius=0.4, nsample=32, mlp=[128, 128, 256]),
                    dict(npoint=16, radius=0.8, nsample=32, mlp=[256, 256, 512])],
                fp=[[256, 256], [256, 256], [256, 128]],
                tokens=dict(groups=8, gx=4, gy=4))


def check_points_config(p: dict) -> None:
    sa, fp, tok = p["sa"], p["fp"], p["tokens"]
    if len(sa) < 2 or len(fp) != len(sa) - 1:
        raise ValueError(f"points: {len(sa)} set-abstraction levels need {len(sa) - 1} "
                         f"propagation layers, not {len(fp)}")
    prev = p["samples"]
    for i, level in enumerate(sa):
        if not 0 < level["npoint"] <= prev:
            raise ValueError(f"points: level {i + 1} samples {level['npoint']} of {prev} points")
        if level["radius"] <= 0 or level["nsample"] < 1:
            raise ValueError(f"points: level {i + 1} needs radius > 0 and nsample >= 1")
        prev = level["npoint"]
    if sa[-1]["npoint"] < 3:
        raise ValueError("points: the deepest level needs >= 3 points to interpolate from")
    cells = tok["groups"] * tok["gx"] * tok["gy"]
    if sa[0]["npoint"] % cells:
        raise ValueError(f"points: {sa[0]['npoint']} first-level points do not split into "
                         f"{tok['groups']} x {tok['gx']} x {tok['gy']} cells")


def shared_mlp(c_in: int, widths) -> nn.Sequential:
    layers = []
    for c in widths:
        layers += [nn.Conv2d(c_in, c, 1, bias=False), nn.BatchNorm2d(c), nn.ReLU()]
        c_in = c
    return nn.Sequential(*layers)


class SetAbstraction(nn.Module):
    def __init__(self, npoint: int, radius: float, nsample: int, c_in: int, mlp):
        super().__init__()
        self.npoint, self.radius, self.nsample = npoint, radius, nsample
        self.mlp = shared_mlp(c_in + 3, mlp)

    def forward(self, xyz, feats):
        centers = ops.farthest_point_sample(xyz, self.npoint)
        g = ops.ball_group(xyz, centers, feats, self.radius, self.nsample)
        return centers, self.mlp(g).amax(dim=3, keepdim=True)


class FeaturePropagation(nn.Module):
    def __init__(self, c_coarse: int, c_skip: int, mlp):
        super().__init__()
        self.mlp = shared_mlp(c_coarse + c_skip, mlp)

    def forward(self, xyz_fine, xyz_coarse, feats_fine, feats_coarse):
        up = ops.three_interpolate(xyz_fine, xyz_coarse, feats_coarse)
        return self.mlp(torch.cat([up, feats_fine], dim=1))


class PointNet2(nn.Module):
    """(B, 6, N, 1) -> first-level coordinates (B, 3, S1, 1), features (B, C, S1, 1)."""

    def __init__(self, p: dict, in_channels: int = 6):
        super().__init__()
        check_points_config(p)
        self.sa = nn.ModuleList()
        widths = [in_channels]
        for level in p["sa"]:
            self.sa.append(SetAbstraction(level["npoint"], level["radius"], level["nsample"],
                                          widths[-1], level["mlp"]))
            widths.append(level["mlp"][-1])
        self.fp = nn.ModuleList()
        coarse = widths[-1]
        for i, mlp in enumerate(p["fp"]):  # deepest first
            skip = widths[len(widths) - 2 - i]
            self.fp.append(FeaturePropagation(coarse, skip, mlp))
            coarse = mlp[-1]
        self.out_channels = coarse

    def forward(self, x):
        xyz, feats = x[:, :3], x
        levels = []
        for sa in self.sa:
            xyz, feats = sa(xyz, feats)
            levels.append((xyz, feats))
        xyz_c, f_c = levels[-1]
        for i, fp in enumerate(self.fp):
            xyz_f, f_f = levels[len(levels) - 2 - i]
            f_c = fp(xyz_f, xyz_c, f_f, f_c)
            xyz_c = xyz_f
        return xyz_c, f_c


class PointTokenEmbedding(nn.Module):
    """Learned encodings along height, x and y, summed: (1, d, groups, gx * gy)."""

    def __init__(self, groups: int, gx: int, gy: int, d_model: int):
        super().__init__()
        self.groups, self.gx, self.gy = groups, gx, gy
        self.height_embed = nn.Embedding(groups, d_model)
        self.x_embed = nn.Embedding(gx, d_model)
        self.y_embed = nn.Embedding(gy, d_model)
        for e in (self.height_embed, self.x_embed, self.y_embed):
            nn.init.uniform_(e.weight)

    def forward(self, tokens: torch.Tensor) -> torch.Tensor:
        h = self.height_embed.weight[:, None, None, :]
        x = self.x_embed.weight[None, :, None, :]
        y = self.y_embed.weight[None, None, :, :]
        pos = (h + x + y).reshape(self.groups, self.gx * self.gy, -1)  # (G, gx*gy, d)
        return pos.permute(2, 0, 1).unsqueeze(0).repeat(tokens.shape[0], 1, 1, 1)


class PointTrunk(nn.Module):
    """PointNet++ and the grid tokenisation: (B, 6, N, 1) -> tokens (B, C, G, gx * gy)."""

    def __init__(self, p: dict):
        super().__init__()
        self.body = PointNet2(p)
        self.tokens = dict(p["tokens"])

    def forward(self, x):
        xyz, feats = self.body(x)
        t = self.tokens
        return ops.grid_tokens(xyz, feats, t["groups"], t["gx"], t["gy"])
