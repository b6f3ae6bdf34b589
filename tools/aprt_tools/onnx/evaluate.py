"""A small ONNX interpreter on numpy (heavy ops through torch).

The converter uses it twice: to fold everything that does not depend on the
image (shapes, masks, position tables, reshape targets, branches of `If`)
into constants, and to record every intermediate tensor for one probe input,
so each lowered engine op can be checked against what ONNX computes. It
covers the operators that PyTorch's exporter emits for APR-Transformer at
opsets 13 and 17, nothing more; anything else is refused by name.
"""

from __future__ import annotations

import math

import numpy as np
import onnx
import torch
from onnx import numpy_helper
from torch.nn import functional as F


class UnsupportedOnnx(Exception):
    """The graph uses something aprt cannot represent; the message names the node."""


def attrs_of(node: onnx.NodeProto) -> dict:
    return {a.name: onnx.helper.get_attribute_value(a) for a in node.attribute}


def _axes(node_attrs, inputs, index):
    if len(inputs) > index and inputs[index] is not None:
        return [int(a) for a in np.asarray(inputs[index]).reshape(-1)]
    return node_attrs.get("axes")


def _reduce(fn, a, x, inputs):
    axes = _axes(a, inputs, 1)
    keep = bool(a.get("keepdims", 1))
    axes = tuple(range(x.ndim)) if axes is None else tuple(int(v) % x.ndim for v in axes)
    return fn(x, axis=axes, keepdims=keep)


def _conv(a, x, w, b=None):
    groups = int(a.get("group", 1))
    strides = a.get("strides", [1, 1])
    dil = a.get("dilations", [1, 1])
    pads = a.get("pads", [0, 0, 0, 0])
    if a.get("auto_pad", b"NOTSET") not in (b"NOTSET", "NOTSET"):
        raise UnsupportedOnnx("Conv auto_pad is not supported; export with explicit pads")
    t = torch.from_numpy(np.array(x, dtype=np.float32))
    t = F.pad(t, (pads[1], pads[3], pads[0], pads[2]))
    out = F.conv2d(t, torch.from_numpy(np.array(w, dtype=np.float32)),
                   None if b is None else torch.from_numpy(np.array(b, dtype=np.float32)),
                   stride=tuple(strides), dilation=tuple(dil), groups=groups)
    return out.numpy()


def _pad(a, x, pads=None, value=None):
    if pads is None:
        pads = a["pads"]
    pads = [int(p) for p in np.asarray(pads).reshape(-1)]
    mode = a.get("mode", b"constant")
    mode = mode.decode() if isinstance(mode, bytes) else mode
    if mode != "constant":
        raise UnsupportedOnnx(f"Pad mode {mode!r} is not supported")
    r = x.ndim
    v = 0 if value is None or np.asarray(value).size == 0 else np.asarray(value).reshape(-1)[0]
    if any(p < 0 for p in pads):
        raise UnsupportedOnnx("Pad with negative pads is not supported")
    return np.pad(x, [(pads[i], pads[i + r]) for i in range(r)], constant_values=v)


def _slice(x, starts, ends, axes=None, steps=None):
    starts = np.asarray(starts).reshape(-1)
    ends = np.asarray(ends).reshape(-1)
    axes = list(range(len(starts))) if axes is None else np.asarray(axes).reshape(-1)
    steps = [1] * len(starts) if steps is None else np.asarray(steps).reshape(-1)
    sl = [slice(None)] * x.ndim
    for s, e, ax, st in zip(starts, ends, axes, steps):
        ax = int(ax) % x.ndim
        n = x.shape[ax]
        s, e, st = int(s), int(e), int(st)
        # ONNX clamps like Python slicing, with huge sentinels for "to the end".
        s = max(min(s, n), -n - 1) if s < 0 else min(s, n)
        e = max(e, -n - 1) if e < 0 else min(e, n)
        if st < 0 and e < -n:
            e = None
        sl[ax] = slice(s, e, st)
    return x[tuple(sl)]


def _resize_nearest(a, x, roi, scales, sizes):
    mode = a.get("mode", b"nearest")
    mode = mode.decode() if isinstance(mode, bytes) else mode
    if mode != "nearest":
        raise UnsupportedOnnx(f"Resize mode {mode!r} is not supported")
    if sizes is not None and np.asarray(sizes).size:
        out_shape = [int(v) for v in np.asarray(sizes)]
    else:
        out_shape = [int(math.floor(d * s)) for d, s in zip(x.shape, np.asarray(scales))]
    ctm = a.get("coordinate_transformation_mode", b"half_pixel")
    ctm = ctm.decode() if isinstance(ctm, bytes) else ctm
    rnd = a.get("nearest_mode", b"round_prefer_floor")
    rnd = rnd.decode() if isinstance(rnd, bytes) else rnd
    idx = []
    for d_in, d_out in zip(x.shape, out_shape):
        scale = d_out / d_in
        o = np.arange(d_out, dtype=np.float64)
        if ctm == "asymmetric":
            src = o / scale
        elif ctm == "half_pixel":
            src = (o + 0.5) / scale - 0.5
        elif ctm == "align_corners":
            src = o * (d_in - 1) / max(d_out - 1, 1)
        else:
            raise UnsupportedOnnx(f"Resize coordinate mode {ctm!r} is not supported")
        if rnd == "floor":
            i = np.floor(src)
        elif rnd == "ceil":
            i = np.ceil(src)
        elif rnd == "round_prefer_ceil":
            i = np.floor(src + 0.5)
        else:
            i = np.ceil(src - 0.5)
        idx.append(np.clip(i.astype(np.int64), 0, d_in - 1))
    return x[np.ix_(*idx)]


def _erf(x):
    return torch.erf(torch.from_numpy(np.array(x))).numpy()


def _layer_norm(a, x, scale, bias=None):
    axis = int(a.get("axis", -1)) % x.ndim
    eps = float(a.get("epsilon", 1e-5))
    axes = tuple(range(axis, x.ndim))
    mean = x.mean(axis=axes, keepdims=True)
    var = ((x - mean) ** 2).mean(axis=axes, keepdims=True)
    y = (x - mean) / np.sqrt(var + eps) * scale
    return y if bias is None else y + bias


ONNX_DTYPES = {1: np.float32, 6: np.int32, 7: np.int64, 9: np.bool_, 11: np.float64,
               10: np.float16, 2: np.uint8, 3: np.int8}


def _cast(a, x):
    to = int(a["to"])
    if to not in ONNX_DTYPES:
        raise UnsupportedOnnx(f"Cast to ONNX type {to} is not supported")
    return np.asarray(x).astype(ONNX_DTYPES[to])


def _gemm(a, x, w, c=None):
    if a.get("transA", 0):
        x = x.T
    if a.get("transB", 0):
        w = w.T
    y = float(a.get("alpha", 1.0)) * (x @ w)
    if c is not None:
        y = y + float(a.get("beta", 1.0)) * c
    return y.astype(np.float32)


def _split(a, x, split=None, n_out=1):
    axis = int(a.get("axis", 0)) % x.ndim
    if split is None:
        split = a.get("split")
    if split is None:
        size = x.shape[axis] // n_out
        split = [size] * n_out
    bounds = np.cumsum([0] + [int(s) for s in np.asarray(split).reshape(-1)])
    return [np.take(x, np.arange(bounds[i], bounds[i + 1]), axis=axis) for i in range(n_out)]


def _softmax(a, x):
    axis = int(a.get("axis", -1))
    m = x.max(axis=axis, keepdims=True)
    e = np.exp(x - m)
    return e / e.sum(axis=axis, keepdims=True)


def _squeeze(a, x, axes=None):
    axes = axes if axes is not None else a.get("axes")
    if axes is None:
        return np.squeeze(x)
    return np.squeeze(x, axis=tuple(int(v) % x.ndim for v in np.asarray(axes).reshape(-1)))


def _unsqueeze(a, x, axes=None):
    axes = axes if axes is not None else a.get("axes")
    axes = sorted(int(v) for v in np.asarray(axes).reshape(-1))
    out_rank = np.ndim(x) + len(axes)
    y = np.asarray(x)
    for ax in sorted(v % out_rank for v in axes):
        y = np.expand_dims(y, ax)
    return y


def _flatten(a, x):
    axis = int(a.get("axis", 1)) % (x.ndim + 1) if x.ndim else 0
    lead = int(np.prod(x.shape[:axis])) if axis else 1
    return x.reshape(lead, -1)


def _reshape(a, x, shape):
    shape = [int(v) for v in np.asarray(shape).reshape(-1)]
    if not a.get("allowzero", 0):
        shape = [x.shape[i] if v == 0 else v for i, v in enumerate(shape)]
    return x.reshape(shape)


def _as_f32(x):
    x = np.asarray(x)
    return x.astype(np.float32) if x.dtype == np.float64 else x


# Every operator the interpreter knows: (attrs, *inputs) -> output or list of outputs.
OPS = {
    "Identity": lambda a, x: x,
    "Dropout": lambda a, x, *r: x,
    "Add": lambda a, x, y: _as_f32(np.add(x, y)),
    "Sub": lambda a, x, y: _as_f32(np.subtract(x, y)),
    "Mul": lambda a, x, y: _as_f32(np.multiply(x, y)),
    "Div": lambda a, x, y: (np.floor_divide(x, y) if np.asarray(x).dtype.kind in "iu"
                            else _as_f32(np.divide(x, y))),
    "Pow": lambda a, x, y: _as_f32(np.power(x, y)),
    "Sqrt": lambda a, x: np.sqrt(x),
    "Neg": lambda a, x: -x,
    "Abs": lambda a, x: np.abs(x),
    "Exp": lambda a, x: np.exp(x),
    "Erf": lambda a, x: _erf(x),
    "Sigmoid": lambda a, x: (1.0 / (1.0 + np.exp(-x))).astype(np.asarray(x).dtype),
    "Tanh": lambda a, x: np.tanh(x),
    "Relu": lambda a, x: np.maximum(x, 0),
    "Softmax": _softmax,
    "MatMul": lambda a, x, y: _as_f32(np.matmul(x, y)),
    "Gemm": _gemm,
    "Conv": _conv,
    "Pad": lambda a, x, pads=None, value=None, *axes: _pad(a, x, pads, value),
    "GlobalAveragePool": lambda a, x: x.mean(axis=tuple(range(2, x.ndim)), keepdims=True),
    "ReduceMean": lambda a, x, *r: _reduce(np.mean, a, x, (x,) + r),
    "ReduceMax": lambda a, x, *r: _reduce(np.max, a, x, (x,) + r),
    "ReduceMin": lambda a, x, *r: _reduce(np.min, a, x, (x,) + r),
    "ReduceSum": lambda a, x, *r: _reduce(np.sum, a, x, (x,) + r),
    "LayerNormalization": _layer_norm,
    "Shape": lambda a, x: np.asarray(np.shape(x), dtype=np.int64)[
        slice(a.get("start", 0), a.get("end", None))],
    "Size": lambda a, x: np.asarray(np.size(x), dtype=np.int64),
    "Reshape": _reshape,
    "Flatten": _flatten,
    "Squeeze": _squeeze,
    "Unsqueeze": _unsqueeze,
    "Transpose": lambda a, x: np.transpose(x, a.get("perm")),
    "Concat": lambda a, *xs: np.concatenate([np.asarray(v) for v in xs], axis=int(a["axis"])),
    "Gather": lambda a, x, i: np.take(x, np.asarray(i).astype(np.int64), axis=int(a.get("axis", 0))),
    "Slice": lambda a, x, s, e, ax=None, st=None: _slice(x, s, e, ax, st),
    "Expand": lambda a, x, s: x * np.ones([int(v) for v in np.asarray(s)], dtype=np.asarray(x).dtype),
    "Tile": lambda a, x, r: np.tile(x, [int(v) for v in np.asarray(r)]),
    "Cast": _cast,
    "ConstantOfShape": lambda a, s: np.full([int(v) for v in np.asarray(s)],
                                            numpy_helper.to_array(a["value"]).reshape(-1)[0]
                                            if "value" in a else np.float32(0)),
    "Range": lambda a, s, l, d: np.arange(s, l, d).astype(np.asarray(s).dtype),
    "Equal": lambda a, x, y: np.equal(x, y),
    "Less": lambda a, x, y: np.less(x, y),
    "Greater": lambda a, x, y: np.greater(x, y),
    "Not": lambda a, x: np.logical_not(x),
    "And": lambda a, x, y: np.logical_and(x, y),
    "Or": lambda a, x, y: np.logical_or(x, y),
    "Where": lambda a, c, x, y: np.where(c, x, y),
    "Min": lambda a, *xs: np.minimum.reduce(xs),
    "Max": lambda a, *xs: np.maximum.reduce(xs),
    "Resize": lambda a, x, roi=None, scales=None, sizes=None: _resize_nearest(a, x, roi, scales, sizes),
}


def _point_op(fn):
    """An 'aprt' domain node (model/point_ops.py) through its torch definition."""
    def run(a, *xs):
        from ..model import point_ops

        ts = [None if x is None else torch.from_numpy(np.ascontiguousarray(x, np.float32))
              for x in xs]
        with torch.no_grad():
            return fn(point_ops, a, *ts).numpy()
    return run


# The custom domain of points models' exports (tools/aprt_tools/model/point_ops.py).
APRT_OPS = {
    "FarthestPointSample": _point_op(lambda o, a, x: o.fps_plain(x, int(a["count"]))),
    "BallGroup": _point_op(lambda o, a, x, c, f=None: o.ball_group_plain(
        x, c, f, float(a["radius"]), int(a["nsample"]))),
    "ThreeInterpolate": _point_op(lambda o, a, t, k, f: o.three_interpolate_plain(t, k, f)),
    "GridTokens": _point_op(lambda o, a, x, f: o.grid_tokens_plain(
        x, f, int(a["groups"]), int(a["gx"]), int(a["gy"]))),
}


def constant_value(node: onnx.NodeProto) -> np.ndarray:
    a = attrs_of(node)
    if "value" in a:
        return numpy_helper.to_array(a["value"])
    for key, dt in (("value_float", np.float32), ("value_int", np.int64)):
        if key in a:
            return np.asarray(a[key], dtype=dt)
    for key, dt in (("value_floats", np.float32), ("value_ints", np.int64)):
        if key in a:
            return np.asarray(a[key], dtype=dt)
    raise UnsupportedOnnx(f"Constant node {node.name!r} has no supported value attribute")


def run_node(node: onnx.NodeProto, inputs: list) -> list:
    """Evaluate one node; `inputs` holds numpy arrays (None for omitted inputs)."""
    if node.op_type == "Constant":
        return [constant_value(node)]
    fn = APRT_OPS.get(node.op_type) if node.domain == "aprt" else OPS.get(node.op_type)
    if fn is None and node.op_type != "Split" or node.domain not in ("", "ai.onnx", "aprt"):
        raise UnsupportedOnnx(f"node {node.name!r}: operator {node.op_type!r} is not supported")
    a = attrs_of(node)
    if node.op_type == "Split":
        split = inputs[1] if len(inputs) > 1 else None
        return _split(a, inputs[0], split, len(node.output))
    try:
        out = fn(a, *inputs)
    except UnsupportedOnnx as e:
        raise UnsupportedOnnx(f"node {node.name!r} ({node.op_type}): {e}") from None
    except Exception as e:  # numpy shape errors and the like: report the node
        raise UnsupportedOnnx(f"node {node.name!r} ({node.op_type}) failed to evaluate: {e}") from None
    return out if isinstance(out, list) else [out]


OPS["Split"] = None  # handled in run_node (needs the output count)


def run_graph(graph: onnx.GraphProto, values: dict, on_node=None) -> dict:
    """Evaluate `graph` in order, adding every output to `values` (name -> array).

    `If` nodes run the branch their condition selects, with the outer scope
    visible. `on_node(node, values)` is called after each node.
    """
    for node in graph.node:
        ins = [values[i] if i else None for i in node.input]
        for i, name in enumerate(node.input):
            if name and name not in values:
                raise UnsupportedOnnx(f"node {node.name!r} reads {name!r}, which nothing produces")
        if node.op_type == "If":
            a = attrs_of(node)
            branch = a["then_branch"] if bool(np.asarray(ins[0]).reshape(-1)[0]) else a["else_branch"]
            inner = dict(values)
            run_graph(branch, inner, on_node)
            outs = [inner[o.name] for o in branch.output]
            for k, v in inner.items():  # expose the branch's intermediates too
                values.setdefault(k, v)
        else:
            outs = run_node(node, ins)
        for name, v in zip(node.output, outs):
            if name:
                values[name] = v
        if on_node:
            on_node(node, values)
    return values


def initial_values(model: onnx.ModelProto) -> dict:
    return {t.name: numpy_helper.to_array(t) for t in model.graph.initializer}


def run_model(model: onnx.ModelProto, feeds: dict) -> list:
    values = initial_values(model)
    values.update(feeds)
    run_graph(model.graph, values)
    return [values[o.name] for o in model.graph.output]
