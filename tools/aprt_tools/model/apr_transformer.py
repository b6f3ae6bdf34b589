"""APR-Transformer, image modality (DESIGN.md section 4.1), and the same
network on LiDAR: a BEV histogram through the image trunk (4.2) or raw points
through PointNet++ (4.3, model/pointnet2.py).

Two branches share one EfficientNet trunk: the stride-16 map (reduction_4)
feeds the position transformer, the stride-8 map (reduction_3) the
orientation transformer; a points model feeds both its grid tokens. Each branch decodes one learned query; an MLP head
regresses (x, y, z) min-max normalised and (qw, qx, qy, qz) unnormalised.
The state_dict keys equal upstream's (GT-ARC/APR-Transformer).
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass, field

import torch
from torch import nn
from torch.nn import functional as F

from .efficientnet import EfficientNet
from .pointnet2 import PointTokenEmbedding, PointTrunk, points_config
from .transformer import Transformer

IMAGENET_MEAN = (0.485, 0.456, 0.406)
IMAGENET_STD = (0.229, 0.224, 0.225)
UNCERTAINTY_HIDDEN = 256  # width of the confidence heads' MLPs


@dataclass
class AprConfig:
    """Everything that fixes the network's shape; stored in model_bin metadata."""
    backbone: str = "efficientnet-b0"
    image_size: int = 224
    in_channels: int = 3
    hidden_dim: int = 256
    nheads: int = 8
    dim_feedforward: int = 256
    enc_layers: int = 6
    dec_layers: int = 6
    head_dim: int = 1024  # width of the regressor MLPs
    dropout: float = 0.0  # transformer dropout while training (DETR uses 0.1)
    pos_embed_cells: int = 50  # rows/cols of the learned position tables
    mean: tuple = IMAGENET_MEAN
    std: tuple = IMAGENET_STD
    # Training-set position bounds for min-max normalisation (metres).
    pose_min: tuple = (0.0, 0.0, 0.0)
    pose_max: tuple = (1.0, 1.0, 1.0)
    # LiDAR BEV models (in_channels 2): the histogram's geometry, keys of
    # lidar_bev.BEV_KEYS; the grid is image_size. None for camera models.
    bev: dict | None = None
    # LiDAR raw-points models (in_channels 6): crop, sampling, PointNet++
    # levels and tokens (pointnet2.points_config). None for the others.
    points: dict | None = None
    # Per-pose confidence: two more heads regress, from the decoder outputs,
    # the log scale of a Laplace error distribution per position axis (in the
    # normalised units of the position head) and per rotation axis (radians,
    # camera frame: x forward, y left, z up), appended as outputs 7..12.
    uncertainty: bool = False
    extra: dict = field(default_factory=dict)

    @staticmethod
    def named(name: str, image_size: int | None = None,
              bev_span_m: float = 32.0) -> "AprConfig":
        """Preset configurations: 'full' (upstream DeepLoc) and 'tiny' (tests);
        'bev' and 'tiny-bev' are the same networks on the LiDAR BEV histogram
        (DESIGN.md 4.2: 2 channels; 256 x 256 cells of 0.125 m, TransFuser's
        32 m square centred on the sensor, split 0.5 m above the ground for a
        sensor 1.9 m up, counts clipped at 5); 'points' and 'tiny-points' the
        raw-points modality (4.3: 20 m crop, 4096 points, PointNet++)."""
        bev = name.endswith("bev")
        pts = name.endswith("points")
        base = {"bev": "full", "tiny-bev": "tiny", "points": "full",
                "tiny-points": "tiny"}.get(name, name)
        if base == "full":
            cfg = AprConfig()
        elif base == "tiny":
            # Same trunk, a transformer small enough for second-long tests;
            # matches the upstream tiny sample in tests/golden/upstream.
            cfg = AprConfig(hidden_dim=32, nheads=8, dim_feedforward=32, enc_layers=1,
                            dec_layers=1, image_size=64)
        else:
            raise ValueError(f"unknown configuration {name!r} (full, tiny, bev, tiny-bev, points, "
                             "tiny-points)")
        if image_size is not None:
            cfg.image_size = image_size
        if bev:  # the grid is the input side over a square of bev_span_m (32: TransFuser's)
            if not 4.0 <= bev_span_m <= 400.0:
                raise ValueError(f"BEV span {bev_span_m} m: must be within 4..400 m")
            cfg.image_size = image_size or (256 if base == "full" else 64)
            cfg.in_channels = 2
            cfg.mean, cfg.std = (0.0, 0.0), (1.0, 1.0)  # histogram values are in [0, 1]
            half = bev_span_m / 2.0
            cfg.bev = dict(cell_m=bev_span_m / cfg.image_size, x_min=-half, y_min=-half,
                           height_threshold_m=-1.4, clip_count=5.0)
        if pts:  # the input is N points x 6 features; image_size is N
            cfg.points = points_config(tiny=base == "tiny")
            if image_size is not None:
                cfg.points["samples"] = image_size
            cfg.image_size = cfg.points["samples"]
            cfg.in_channels = 6
            cfg.backbone = "pointnet2"
            cfg.mean, cfg.std = (0.0,) * 6, (1.0,) * 6
        return cfg

    def input_shape(self) -> tuple:
        """(1, C, H, W) of the network's input: the image, or (1, 6, N, 1) points."""
        if self.points:
            return (1, self.in_channels, self.points["samples"], 1)
        return (1, self.in_channels, self.image_size, self.image_size)

    def to_json(self) -> str:
        return json.dumps(dataclasses.asdict(self), indent=1)

    @staticmethod
    def from_json(text: str) -> "AprConfig":
        d = json.loads(text)
        for k in ("mean", "std", "pose_min", "pose_max"):
            if k in d:
                d[k] = tuple(d[k])
        return AprConfig(**d)


class Backbone(nn.Module):
    def __init__(self, cfg: AprConfig):
        super().__init__()
        self.body = EfficientNet(cfg.backbone, cfg.image_size)
        if cfg.in_channels != 3:  # LiDAR BEV: same trunk, other stem width
            stem = self.body._conv_stem
            self.body._conv_stem = type(stem)(cfg.in_channels, stem.out_channels, 3, 2,
                                              image_size=(cfg.image_size, cfg.image_size))


class PositionEmbeddingLearned(nn.Module):
    """DETR's learned absolute position: column table ++ row table, 128 + 128."""

    def __init__(self, cells: int, d_model: int):
        super().__init__()
        self.row_embed = nn.Embedding(cells, d_model // 2)
        self.col_embed = nn.Embedding(cells, d_model // 2)
        nn.init.uniform_(self.row_embed.weight)
        nn.init.uniform_(self.col_embed.weight)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        h, w = x.shape[-2:]
        if h > self.row_embed.num_embeddings or w > self.col_embed.num_embeddings:
            raise ValueError(f"feature map {h}x{w} exceeds the {self.row_embed.num_embeddings}"
                             "-cell position tables")
        cols = self.col_embed(torch.arange(w, device=x.device))
        rows = self.row_embed(torch.arange(h, device=x.device))
        pos = torch.cat([cols.unsqueeze(0).repeat(h, 1, 1), rows.unsqueeze(1).repeat(1, w, 1)],
                        dim=-1)
        return pos.permute(2, 0, 1).unsqueeze(0).repeat(x.shape[0], 1, 1, 1)


class Joiner(nn.Sequential):
    """Holds the trunk at index 0 and the position tables at index 1 (upstream layout)."""


class PoseRegressor(nn.Module):
    def __init__(self, d_model: int, out_dim: int, hidden: int = 1024):
        super().__init__()
        self.fc_h = nn.Linear(d_model, hidden)
        self.fc_o = nn.Linear(hidden, out_dim)
        for p in self.parameters():
            if p.dim() > 1:
                nn.init.xavier_uniform_(p)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.fc_o(F.gelu(self.fc_h(x)))


class AprTransformer(nn.Module):
    def __init__(self, cfg: AprConfig):
        super().__init__()
        self.cfg = cfg
        if cfg.points:
            t = cfg.points["tokens"]
            self.backbone = Joiner(PointTrunk(cfg.points),
                                   PointTokenEmbedding(t["groups"], t["gx"], t["gy"],
                                                       cfg.hidden_dim))
            ch_rot = ch_t = self.backbone[0].body.out_channels
        else:
            self.backbone = Joiner(Backbone(cfg), PositionEmbeddingLearned(cfg.pos_embed_cells,
                                                                          cfg.hidden_dim))
            ch_rot, ch_t = self.backbone[0].body.endpoint_channels()

        def transformer():
            return Transformer(cfg.hidden_dim, cfg.nheads, cfg.enc_layers, cfg.dec_layers,
                               cfg.dim_feedforward, cfg.dropout)

        self.transformer_t = transformer()
        self.transformer_rot = transformer()
        self.input_proj_t = nn.Conv2d(ch_t, cfg.hidden_dim, kernel_size=1)
        self.input_proj_rot = nn.Conv2d(ch_rot, cfg.hidden_dim, kernel_size=1)
        self.query_embed_t = nn.Embedding(1, cfg.hidden_dim)
        self.query_embed_rot = nn.Embedding(1, cfg.hidden_dim)
        self.regressor_head_t = nn.Sequential(PoseRegressor(cfg.hidden_dim, 3, cfg.head_dim))
        self.regressor_head_rot = nn.Sequential(PoseRegressor(cfg.hidden_dim, 4, cfg.head_dim))
        if cfg.uncertainty:  # not upstream's: a checkpoint of upstream loads without them
            self.uncertainty_head_t = PoseRegressor(cfg.hidden_dim, 3, UNCERTAINTY_HIDDEN)
            self.uncertainty_head_rot = PoseRegressor(cfg.hidden_dim, 3, UNCERTAINTY_HIDDEN)

    def forward(self, img: torch.Tensor) -> torch.Tensor:
        """img: (N, C, S, S), already normalised, or points (N, 6, P, 1). Returns
        (N, 7): x y z qw qx qy qz; with cfg.uncertainty (N, 13): then the log
        Laplace scales of x y z (normalised units) and of the rotation about
        the camera's x y z axes (radians)."""
        if self.cfg.points:
            r3 = r4 = self.backbone[0](img)
        else:
            r3, r4 = self.backbone[0].body.endpoints(img)
        pos_embed = self.backbone[1]
        hs_t = self.transformer_t(self.input_proj_t(r4), pos_embed(r4), self.query_embed_t.weight)
        hs_rot = self.transformer_rot(self.input_proj_rot(r3), pos_embed(r3),
                                      self.query_embed_rot.weight)
        x_t = self.regressor_head_t[0](hs_t[:, 0, :])
        x_rot = self.regressor_head_rot[0](hs_rot[:, 0, :])
        if not self.cfg.uncertainty:
            return torch.cat([x_t, x_rot], dim=1)
        # The confidence heads read the decoder outputs but do not shape them
        # (detached while training): the pose is learned exactly as without them.
        h_t, h_rot = hs_t[:, 0, :], hs_rot[:, 0, :]
        if self.training:
            h_t, h_rot = h_t.detach(), h_rot.detach()
        s_t = self.uncertainty_head_t(h_t)
        s_rot = self.uncertainty_head_rot(h_rot)
        return torch.cat([x_t, x_rot, s_t, s_rot], dim=1)
