"""The engine's graph as the converter builds it, and what each op computes.

Layouts: feature maps are NHWC ([1, H, W, C]); token matrices are row-major
with the feature axis last. `run()` below is the numpy statement of every
op's semantics; the C++ reference kernels (kernels/<family>/*__ref) implement the same
and the converter checks each lowered graph against ONNX with it.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import torch

from ..model_bin import spec


@dataclass(eq=False)
class Tensor:
    name: str
    shape: tuple
    kind: int = spec.KIND_ACTIVATION
    data: np.ndarray | None = None  # constants only, already in engine layout
    dtype: int = spec.DTYPE_F32
    # Quantised constants (int8 weights): per-tensor scale, zero point, or the
    # Tensor of per-channel scales.
    scale: float = 0.0
    zero_point: int = 0
    qscale: "Tensor | None" = None

    @property
    def numel(self) -> int:
        return int(np.prod(self.shape))


@dataclass(eq=False)
class Op:
    code: int
    name: str
    inputs: list  # Tensor objects or None
    outputs: list
    params: dict = field(default_factory=dict)

    def __repr__(self):
        return f"{spec.OP_NAMES[self.code]}({self.name})"


@dataclass
class EngineGraph:
    tensors: list = field(default_factory=list)
    ops: list = field(default_factory=list)

    def add(self, t: Tensor) -> Tensor:
        self.tensors.append(t)
        return t

    def const(self, name: str, data: np.ndarray) -> Tensor:
        data = np.ascontiguousarray(data, dtype=np.float32)
        return self.add(Tensor(name, tuple(data.shape), spec.KIND_CONST, data))

    def producer(self, t: Tensor):
        return next((op for op in self.ops if t in op.outputs), None)

    def users(self, t: Tensor) -> list:
        return [op for op in self.ops if t in op.inputs]

    def prune(self):
        """Drop tensors nothing references."""
        used = {id(t) for op in self.ops for t in op.inputs + op.outputs if t is not None}
        used |= {id(t.qscale) for t in self.tensors if id(t) in used and t.qscale is not None}
        self.tensors = [t for t in self.tensors if id(t) in used or t.kind in
                        (spec.KIND_INPUT, spec.KIND_OUTPUT)]


# ---------------------------------------------------------------------------
# Semantics.


def activation(x: np.ndarray, act: int) -> np.ndarray:
    if act == spec.ACT_NONE:
        return x
    if act == spec.ACT_SILU:
        return x / (1.0 + np.exp(-x))
    if act == spec.ACT_GELU:
        return 0.5 * x * (1.0 + torch.erf(torch.from_numpy(x / np.sqrt(2.0))).numpy())
    if act == spec.ACT_SIGMOID:
        return 1.0 / (1.0 + np.exp(-x))
    if act == spec.ACT_RELU:
        return np.maximum(x, 0)
    raise ValueError(f"activation {act}")


def conv2d_nhwc(x, w, b, stride, pads, depthwise):
    """x [1,H,W,C]; w [Co,KH,KW,Ci] or [KH,KW,C] (depthwise); pads (t, l, b, r)."""
    t = torch.from_numpy(np.ascontiguousarray(x.transpose(0, 3, 1, 2), dtype=np.float64))
    t = torch.nn.functional.pad(t, (pads[1], pads[3], pads[0], pads[2]))
    if depthwise:
        wt = torch.from_numpy(np.ascontiguousarray(w.transpose(2, 0, 1)[:, None], np.float64))
        groups = w.shape[2]
    else:
        wt = torch.from_numpy(np.ascontiguousarray(w.transpose(0, 3, 1, 2), np.float64))
        groups = 1
    y = torch.nn.functional.conv2d(t, wt, torch.from_numpy(b.astype(np.float64)),
                                   stride=tuple(stride), groups=groups)
    return y.numpy().transpose(0, 2, 3, 1)


def quantize_u8(x: np.ndarray, scale: float, zero: int) -> np.ndarray:
    """The runtime's activation quantiser: float32 x * (1/scale), round half to
    even, + zero, clamped to 0..255 (kernels/gemm/qu8s8_gemm__ref.cc)."""
    inv = np.float32(1.0) / np.float32(scale)
    q = np.rint(np.asarray(x, np.float32) * inv) + np.float32(zero)
    return np.clip(q, 0, 255).astype(np.int64)


def quantised_linear(op: Op, ins: list) -> np.ndarray:
    """LINEAR with int8 weights, as the runtime computes it: exact integer
    accumulation, y = fma(acc, input_scale * w_scale[j], b[j]), then act, then R."""
    p = op.params
    x, b = ins[0], ins[2]
    w = op.inputs[1]
    k = w.shape[1]
    q = quantize_u8(x.reshape(-1, k), p["input_scale"], p["input_zero"]) - int(p["input_zero"])
    acc = q @ w.data.astype(np.int64).T
    ws = w.qscale.data if w.qscale is not None else np.full(w.shape[0], w.scale, np.float32)
    mult = (np.float32(p["input_scale"]) * ws.astype(np.float32)).astype(np.float64)
    y = acc.astype(np.float64) * mult + b
    y = activation(y, p.get("act", 0))
    if len(ins) > 3 and ins[3] is not None:
        y = y + ins[3].reshape(y.shape)
    return y


def _mult(op: Op, w: "Tensor") -> np.ndarray:
    """input scale x weight scale per channel, as the runtime's float32 product."""
    ws = w.qscale.data if w.qscale is not None else np.full(w.shape[-1], w.scale, np.float32)
    return (np.float32(op.params["input_scale"]) * ws.astype(np.float32)).astype(np.float64)


def quantised_dwconv(op: Op, ins: list) -> np.ndarray:
    """DWCONV2D with int8 weights [KH, KW, C]: the integer sums (exact in float64),
    y = acc * mult[c] + b[c], then act."""
    p = op.params
    zero = int(p["input_zero"])
    q = (quantize_u8(ins[0], p["input_scale"], zero) - zero).astype(np.float64)
    w = op.inputs[1]
    acc = conv2d_nhwc(q, w.data.astype(np.float64), np.zeros(w.shape[-1]), p["stride"],
                      p["pads"], True)
    return activation(acc * _mult(op, w) + ins[2], p.get("act", 0))


def _xyz(x: np.ndarray, t: Tensor) -> torch.Tensor:
    """The first three columns of a row tensor, as point_ops' (1, 3, N, 1) float32."""
    rows = np.asarray(x).reshape(-1, t.shape[-1])[:, :3].astype(np.float32)
    return torch.from_numpy(np.ascontiguousarray(rows.T))[None, :, :, None]


def _feats(x: np.ndarray, t: Tensor) -> torch.Tensor:
    rows = np.asarray(x).reshape(-1, t.shape[-1]).astype(np.float32)
    return torch.from_numpy(np.ascontiguousarray(rows.T))[None, :, :, None]


def point_op(op: Op, ins: list) -> np.ndarray:
    """The PointNet++ ops: model/point_ops.py is their definition (float32)."""
    from ..model import point_ops as po

    c, p, t = op.code, op.params, op.inputs
    with torch.no_grad():
        if c == spec.OP_FPS:
            s = int(np.prod(op.outputs[0].shape[:-1]))
            y = po.fps_plain(_xyz(ins[0], t[0]), s)[0, :, :, 0].T
        elif c == spec.OP_BALL_GROUP:
            k = op.outputs[0].shape[-2]
            f = None if t[2] is None else _feats(ins[2], t[2])
            y = po.ball_group_plain(_xyz(ins[0], t[0]), _xyz(ins[1], t[1]), f, p["radius"], k)
            y = y[0].permute(1, 2, 0)
        elif c == spec.OP_THREE_INTERP:
            y = po.three_interpolate_plain(_xyz(ins[0], t[0]), _xyz(ins[1], t[1]),
                                           _feats(ins[2], t[2]))[0, :, :, 0].T
        elif c == spec.OP_GRID_TOKENS:
            y = po.grid_tokens_plain(_xyz(ins[0], t[0]), _feats(ins[1], t[1]), p["groups"],
                                     p["gx"], p["gy"])[0].permute(1, 2, 0)
        else:
            raise ValueError(f"no semantics for op {op}")
    return y.numpy().astype(np.float64)


def run_op(op: Op, get) -> list:
    """Evaluate one op in float64; `get(tensor)` returns an input's value."""
    p = op.params
    ins = [None if t is None else np.asarray(get(t), np.float64) for t in op.inputs]
    c = op.code
    if c == spec.OP_DWCONV2D and op.inputs[1].dtype == spec.DTYPE_I8:
        y = quantised_dwconv(op, ins)
    elif c in (spec.OP_CONV2D, spec.OP_DWCONV2D):
        x, w, b = ins[0], ins[1], ins[2]
        y = conv2d_nhwc(x, w, b, p["stride"], p["pads"], c == spec.OP_DWCONV2D)
        y = activation(y, p.get("act", 0))
        if len(ins) > 3 and ins[3] is not None:
            y = y + ins[3].reshape(y.shape)
    elif c == spec.OP_LINEAR and op.inputs[1].dtype == spec.DTYPE_I8:
        y = quantised_linear(op, ins)
    elif c == spec.OP_LINEAR:
        x, w, b = ins[0], ins[1], ins[2]
        k = w.shape[1]
        y = x.reshape(-1, k) @ w.T + b
        y = activation(y, p.get("act", 0))
        if len(ins) > 3 and ins[3] is not None:
            y = y + ins[3].reshape(y.shape)
    elif c == spec.OP_SQUEEZE_EXCITE:
        x, w1, b1, w2, b2 = ins
        s = x.mean(axis=(1, 2)).reshape(-1)
        r = activation(w1 @ s + b1, spec.ACT_SILU)
        e = activation(w2 @ r + b2, spec.ACT_SIGMOID)
        y = x * e.reshape(1, 1, 1, -1)
    elif c == spec.OP_ADD:
        y = ins[0] + ins[1].reshape(ins[0].shape)
    elif c == spec.OP_LAYERNORM:
        x, gamma, beta = ins
        n = gamma.shape[0]
        r = x.reshape(-1, n)
        mean = r.mean(axis=1, keepdims=True)
        var = ((r - mean) ** 2).mean(axis=1, keepdims=True)
        y = (r - mean) / np.sqrt(var + p["eps"]) * gamma + beta
    elif c == spec.OP_ATTENTION:
        q, k, v = ins
        h = p["heads"]
        e = op.inputs[0].shape[-1]
        d = e // h
        q = q.reshape(-1, h, d).transpose(1, 0, 2)
        k = k.reshape(-1, h, d).transpose(1, 0, 2)
        v = v.reshape(-1, h, d).transpose(1, 0, 2)
        bf16 = p.get("scores") == 2  # bf16 attention (FORMAT.md; kernels/common/bf16.h)
        if p.get("scores") == 1:  # int8 scores: Q and K per row and head (qs8_attention.h)
            q, k = fake_quantize_rows(q), fake_quantize_rows(k)
        elif bf16:
            q, k, v = bf16_round(q), bf16_round(k), bf16_round(v)
        s = (q @ k.transpose(0, 2, 1)) * p["scale"]
        s = np.exp(s - s.max(axis=-1, keepdims=True))
        total = s.sum(axis=-1, keepdims=True)  # of the unrounded weights, as the engine sums
        y = ((bf16_round(s) if bf16 else s) @ v / total).transpose(1, 0, 2).reshape(-1, e)
    elif c == spec.OP_CROSS_ATTENTION_1Q:
        q, m, pos, wk, bk, wv, bv = ins
        h = p["heads"]
        e = wk.shape[0]
        d = e // h
        mem = m.reshape(-1, e)
        keys = mem + (pos.reshape(-1, e) if pos is not None else 0.0)
        q = q.reshape(e)
        out = np.empty(e)
        for hh in range(h):
            sl = slice(hh * d, (hh + 1) * d)
            qt = p["scale"] * (q[sl] @ wk[sl])  # W_k,h^T q_h; the bias term cancels in softmax
            s = keys @ qt
            a = np.exp(s - s.max())
            a /= a.sum()
            out[sl] = wv[sl] @ (a @ mem) + bv[sl]
        y = out
    elif c == spec.OP_ACTIVATION:
        y = activation(ins[0], p["act"])
    elif c == spec.OP_CONCAT:
        m = int(np.prod(op.outputs[0].shape[:-1]))
        y = np.concatenate([x.reshape(m, -1) for x in ins], axis=1)
    elif c == spec.OP_GROUP_MAX:
        x = ins[0]
        y = x.reshape(-1, x.shape[-2], x.shape[-1]).max(axis=1)
    elif c in (spec.OP_FPS, spec.OP_BALL_GROUP, spec.OP_THREE_INTERP, spec.OP_GRID_TOKENS):
        y = point_op(op, ins)
    else:
        raise ValueError(f"no semantics for op {op}")
    return [y.reshape(op.outputs[0].shape)]



def fake_quantize_rows(x: np.ndarray) -> np.ndarray:
    """Symmetric int8 per row (last axis) and back, rounding as the engine does
    (kernels/attention/qs8_attention.h): scale = max|x| / 127, q = rne(x * 127 / max|x|)."""
    x = np.asarray(x, np.float32)
    amax = np.abs(x).max(axis=-1, keepdims=True)
    inv = np.where(amax > 0, np.float32(127.0) / np.where(amax > 0, amax, 1), 0).astype(np.float32)
    q = np.rint(x * inv).astype(np.float32)
    return q * (amax / np.float32(127.0)).astype(np.float32)

def bf16_round(x: np.ndarray) -> np.ndarray:
    """To the nearest bfloat16 and back, ties to even, denormals to zero, NaN
    kept: the rounding of kernels/common/bf16.h (and of vcvtneps2bf16)."""
    x = np.ascontiguousarray(x, np.float32)
    u = x.view(np.uint32).astype(np.uint64)
    r = ((u + 0x7FFF + ((u >> 16) & 1)) >> 16 << 16).astype(np.uint32)
    r = np.where((u & 0x7F800000) == 0, u & 0x80000000, r).astype(np.uint32)
    y = r.view(np.float32).copy()
    y[np.isnan(x)] = np.nan
    return y.reshape(x.shape)


def run(graph: EngineGraph, feeds: dict, keep_all: bool = True) -> dict:
    """Run the graph; `feeds` maps input Tensor -> array. Returns Tensor id -> value."""
    vals = {id(t): np.asarray(v) for t, v in feeds.items()}
    for t in graph.tensors:
        if t.kind == spec.KIND_CONST:
            vals[id(t)] = t.data

    def get(t):
        return vals[id(t)]

    for op in graph.ops:
        for t, v in zip(op.outputs, run_op(op, get)):
            vals[id(t)] = v
    return vals
