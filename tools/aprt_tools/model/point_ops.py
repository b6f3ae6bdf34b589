"""The PointNet++ primitives of the raw-points modality (DESIGN.md 4.3), as
the runtime's engine ops compute them (model_bin/FORMAT.md, ops 11..15;
kernels/points/pointnet__ref.cc). This file is their definition.

Every index an op picks depends only on coordinates, so the engine must pick
the same ones bit for bit. The arithmetic is therefore fixed here, not left to
a library: squared distances are (dx*dx + dy*dy) + dz*dz in float32, without
fused multiply-adds, and every tie goes to the lower point index.

- farthest_point_sample: index 0 first; then the point farthest (squared
  distance) from all chosen so far. Needs count <= N.
- ball_group: for each centre, the first `k` points in index order with
  d2 < radius * radius (float32); fewer: the rest repeat the first found; none:
  index 0. Output channels: the point minus the centre (3), then the point's
  features.
- three_interpolate: for each target, the three known points with the
  smallest d2 (lowest index on ties); weights 1 / (d2 + 1e-8) normalised by
  their sum; the weighted sum of those points' features.
- grid_tokens: points sorted by z (stable) and cut into `groups` equal
  groups; each group sorted by x and cut into `gx` slabs; each slab sorted by
  y and cut into `gy` cells; a token is the channel-wise max over a cell's
  points. Token t = (group * gx + slab) * gy + cell.

Tensors: coordinates (B, 3, N, 1), features (B, C, N, 1), grouped (B, C, S, K)
-- 1 x 1 convolutions over them are the shared MLPs, and the engine's NHWC
layout of each is the row matrix its ops read.

In an ONNX export (torch.onnx.is_in_onnx_export()) each op becomes one node of
the custom domain "aprt" that the converter maps onto its engine op; with
`portable` set, the export spells them in standard ONNX ops instead (for
ONNX Runtime, which has no such ops; FPS becomes an unrolled loop).
"""

from __future__ import annotations

import torch

DOMAIN = "aprt"
EPS = 1e-8

# Set by export_onnx(..., portable=True): trace the plain torch implementations.
_portable = [False]


class portable_export:
    def __enter__(self):
        _portable[0] = True

    def __exit__(self, *exc):
        _portable[0] = False


def _custom() -> bool:
    return torch.onnx.is_in_onnx_export() and not _portable[0]


def _points(xyz: torch.Tensor) -> torch.Tensor:
    """(B, 3, N, 1) -> (B, N, 3)."""
    return xyz[:, :3, :, 0].transpose(1, 2)


def sq_dist(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """a (B, M, 3), b (B, N, 3) -> (B, M, N): (dx*dx + dy*dy) + dz*dz."""
    dx = a[:, :, None, 0] - b[:, None, :, 0]
    dy = a[:, :, None, 1] - b[:, None, :, 1]
    dz = a[:, :, None, 2] - b[:, None, :, 2]
    return (dx * dx + dy * dy) + dz * dz


def _sort_stable(x: torch.Tensor, dim: int, first: int | None = None):
    """(values, indices) of the `first` smallest along `dim`, ascending, lower
    index first on ties. The portable ONNX spells it TopK (whose ties ONNX
    defines the same way; torch's exporter has no stable Sort)."""
    if _portable[0]:
        return torch.topk(x, first or x.shape[dim], dim=dim, largest=False, sorted=True)
    v, i = torch.sort(x, dim=dim, stable=True)
    if first is not None:
        v, i = v.narrow(dim, 0, first), i.narrow(dim, 0, first)
    return v, i


def _gather_rows(x: torch.Tensor, idx: torch.Tensor) -> torch.Tensor:
    """x (B, N, C), idx (B, ...) -> (B, ..., C)."""
    b = x.shape[0]
    flat = idx.reshape(b, -1)
    out = torch.gather(x, 1, flat[..., None].expand(b, flat.shape[1], x.shape[2]))
    return out.reshape(*idx.shape, x.shape[2])


# -- the plain torch implementations (training, eager inference, portable ONNX) --

@torch.no_grad()
def fps_indices(p: torch.Tensor, count: int) -> torch.Tensor:
    """p (B, N, 3) -> (B, count) int64."""
    b, n, _ = p.shape
    if count > n:
        raise ValueError(f"farthest-point sampling of {count} from {n} points")
    batch = torch.arange(b)
    dist = torch.full((b, n), float("inf"), dtype=p.dtype)
    far = torch.zeros(b, dtype=torch.int64)
    picked = []
    for _ in range(count):
        picked.append(far)
        c = p[batch, far]  # (B, 3)
        dx = p[:, :, 0] - c[:, 0:1]
        dy = p[:, :, 1] - c[:, 1:2]
        dz = p[:, :, 2] - c[:, 2:3]
        dist = torch.minimum(dist, (dx * dx + dy * dy) + dz * dz)
        far = torch.argmax(dist, dim=1)  # the first maximum: lowest index on ties
    return torch.stack(picked, dim=1)


@torch.jit.script
def _fps_loop(p: torch.Tensor, count: int) -> torch.Tensor:
    """fps_indices as a scripted loop: the portable export's spelling (one ONNX
    Loop instead of `count` unrolled steps, which tracing takes hours over)."""
    b = p.size(0)
    n = p.size(1)
    dist = torch.full([b, n], float("inf"))
    far = torch.zeros([b], dtype=torch.long)
    out = [far]
    for _ in range(count - 1):
        c = torch.gather(p, 1, far.view(b, 1, 1).expand(b, 1, 3))
        dx = p[:, :, 0] - c[:, :, 0]
        dy = p[:, :, 1] - c[:, :, 1]
        dz = p[:, :, 2] - c[:, :, 2]
        dist = torch.minimum(dist, (dx * dx + dy * dy) + dz * dz)
        far = torch.argmax(dist, dim=1)
        out.append(far)
    return torch.stack(out, 1)


def fps_plain(xyz: torch.Tensor, count: int) -> torch.Tensor:
    p = _points(xyz)
    idx = _fps_loop(p.contiguous(), count) if _portable[0] else fps_indices(p, count)
    sel = _gather_rows(p, idx)  # (B, S, 3)
    return sel.transpose(1, 2)[..., None]


@torch.no_grad()
def ball_indices(p: torch.Tensor, c: torch.Tensor, radius: float, k: int) -> torch.Tensor:
    """p (B, N, 3), c (B, S, 3) -> (B, S, k) int64."""
    n = p.shape[1]
    r = torch.tensor(radius, dtype=torch.float32)
    inside = sq_dist(c, p) < r * r
    order = torch.arange(n).expand(inside.shape)
    cand = torch.where(inside, order, torch.full_like(order, n))
    if k > n:  # fewer points than k: the missing slots repeat the first found
        cand = torch.cat([cand, torch.full_like(cand[..., :1], n).expand(
            *cand.shape[:-1], k - n)], dim=-1)
    cand = torch.topk(cand, k, dim=-1, largest=False, sorted=True).values
    first = cand[..., :1]
    first = torch.where(first == n, torch.zeros_like(first), first)
    return torch.where(cand == n, first.expand_as(cand), cand)


def ball_group_plain(xyz, centers, feats, radius: float, k: int) -> torch.Tensor:
    p, c = _points(xyz), _points(centers)
    idx = ball_indices(p, c, radius, k)  # (B, S, K)
    rel = _gather_rows(p, idx) - c[:, :, None, :]  # (B, S, K, 3)
    parts = [rel]
    if feats is not None:
        parts.append(_gather_rows(feats[..., 0].transpose(1, 2), idx))  # (B, S, K, C)
    return torch.cat(parts, dim=-1).permute(0, 3, 1, 2)


@torch.no_grad()
def three_nn(t: torch.Tensor, k: torch.Tensor):
    """t (B, N1, 3) targets, k (B, N2, 3) known -> (d2, idx) (B, N1, 3)."""
    return _sort_stable(sq_dist(t, k), -1, 3)


def three_interpolate_plain(xyz1, xyz2, feats2) -> torch.Tensor:
    d, idx = three_nn(_points(xyz1), _points(xyz2))
    recip = 1.0 / (d + EPS)
    norm = (recip[..., 0:1] + recip[..., 1:2]) + recip[..., 2:3]
    w = recip / norm  # (B, N1, 3)
    f = _gather_rows(feats2[..., 0].transpose(1, 2), idx)  # (B, N1, 3, C)
    out = (w[..., 0:1] * f[:, :, 0] + w[..., 1:2] * f[:, :, 1]) + w[..., 2:3] * f[:, :, 2]
    return out.transpose(1, 2)[..., None]


@torch.no_grad()
def grid_order(p: torch.Tensor, groups: int, gx: int, gy: int) -> torch.Tensor:
    """p (B, N, 3) -> (B, groups, gx, gy, N / (groups gx gy)) point indices."""
    b, n, _ = p.shape
    if n % (groups * gx * gy):
        raise ValueError(f"{n} points do not split into {groups} x {gx} x {gy} cells")
    idx = _sort_stable(p[:, :, 2], 1)[1].reshape(b, groups, -1)
    xs = torch.gather(p[:, :, 0], 1, idx.reshape(b, -1)).reshape(idx.shape)
    idx = torch.gather(idx, 2, _sort_stable(xs, 2)[1])
    idx = idx.reshape(b, groups, gx, -1)
    ys = torch.gather(p[:, :, 1], 1, idx.reshape(b, -1)).reshape(idx.shape)
    idx = torch.gather(idx, 3, _sort_stable(ys, 3)[1])
    return idx.reshape(b, groups, gx, gy, -1)


def grid_tokens_plain(xyz, feats, groups: int, gx: int, gy: int) -> torch.Tensor:
    order = grid_order(_points(xyz), groups, gx, gy)
    f = _gather_rows(feats[..., 0].transpose(1, 2), order)  # (B, G, gx, gy, per, C)
    tok = f.amax(dim=4)  # (B, G, gx, gy, C)
    b, c = tok.shape[0], tok.shape[-1]
    return tok.reshape(b, groups, gx * gy, c).permute(0, 3, 1, 2)


# -- ONNX: one custom node per op -------------------------------------------
# Shapes travel as plain arguments: the exporter's shape inference does not
# know these ops and forgets any type set on their outputs.

def _typed(node, like, sizes):
    node.setType(like.type().with_sizes(sizes))
    return node


class _Fps(torch.autograd.Function):
    @staticmethod
    def forward(ctx, xyz, count):
        return fps_plain(xyz, count)

    @staticmethod
    def symbolic(g, xyz, count):
        return _typed(g.op(f"{DOMAIN}::FarthestPointSample", xyz, count_i=count), xyz,
                      [1, 3, count, 1])


class _BallGroup(torch.autograd.Function):
    @staticmethod
    def forward(ctx, xyz, centers, feats, radius, k, s, c):
        return ball_group_plain(xyz, centers, feats, radius, k)

    @staticmethod
    def symbolic(g, xyz, centers, feats, radius, k, s, c):
        return _typed(g.op(f"{DOMAIN}::BallGroup", xyz, centers, feats, radius_f=radius,
                           nsample_i=k), xyz, [1, 3 + c, s, k])


class _ThreeInterpolate(torch.autograd.Function):
    @staticmethod
    def forward(ctx, xyz1, xyz2, feats2, n1, c):
        return three_interpolate_plain(xyz1, xyz2, feats2)

    @staticmethod
    def symbolic(g, xyz1, xyz2, feats2, n1, c):
        return _typed(g.op(f"{DOMAIN}::ThreeInterpolate", xyz1, xyz2, feats2), xyz1,
                      [1, c, n1, 1])


class _GridTokens(torch.autograd.Function):
    @staticmethod
    def forward(ctx, xyz, feats, groups, gx, gy, c):
        return grid_tokens_plain(xyz, feats, groups, gx, gy)

    @staticmethod
    def symbolic(g, xyz, feats, groups, gx, gy, c):
        return _typed(g.op(f"{DOMAIN}::GridTokens", xyz, feats, groups_i=groups, gx_i=gx,
                           gy_i=gy), xyz, [1, c, groups, gx * gy])


# -- what the model calls ------------------------------------------------------

def farthest_point_sample(xyz: torch.Tensor, count: int) -> torch.Tensor:
    """xyz (B, >=3, N, 1) -> (B, 3, count, 1): the sampled points' coordinates."""
    return _Fps.apply(xyz, count) if _custom() else fps_plain(xyz, count)


def ball_group(xyz, centers, feats, radius: float, k: int) -> torch.Tensor:
    """-> (B, 3 + C, S, k)."""
    if _custom():
        return _BallGroup.apply(xyz, centers, feats, float(radius), int(k), int(centers.shape[2]),
                                int(feats.shape[1]))
    return ball_group_plain(xyz, centers, feats, radius, k)


def three_interpolate(xyz1, xyz2, feats2) -> torch.Tensor:
    """targets xyz1 (B, 3, N1, 1), known xyz2 (B, 3, N2, 1), feats2 (B, C, N2, 1) -> (B, C, N1, 1)."""
    if _custom():
        return _ThreeInterpolate.apply(xyz1, xyz2, feats2, int(xyz1.shape[2]),
                                       int(feats2.shape[1]))
    return three_interpolate_plain(xyz1, xyz2, feats2)


def grid_tokens(xyz, feats, groups: int, gx: int, gy: int) -> torch.Tensor:
    """-> (B, C, groups, gx * gy)."""
    if _custom():
        return _GridTokens.apply(xyz, feats, int(groups), int(gx), int(gy), int(feats.shape[1]))
    return grid_tokens_plain(xyz, feats, groups, gx, gy)
