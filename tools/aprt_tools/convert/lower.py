"""Lowering of the rewritten ONNX graph to engine ops.

Every dynamic ONNX tensor is represented as a *view*: an engine tensor plus an
integer array, shaped like the ONNX tensor, holding each element's flat
position in the engine tensor. Pure layout ops (Reshape, Transpose, Squeeze,
Flatten, Gather of a constant index, ...) only transform that array, so they
cost nothing at run time. A compute op checks that each operand's view is the
layout it reads (NHWC for convolutions, row-major rows for matrix products,
the head-split of a row-major matrix for attention) and refuses the graph,
naming the node, if not.
"""

from __future__ import annotations

import numpy as np

from ..model_bin import spec
from ..onnx.evaluate import UnsupportedOnnx, run_node
from ..onnx.graph import Graph, Node
from .engine_ir import EngineGraph, Op, Tensor


def nhwc_view(n, c, h, w):
    """Index array, shaped NCHW, of an NHWC tensor."""
    return np.arange(n * h * w * c).reshape(n, h, w, c).transpose(0, 3, 1, 2)


def rows_view(shape):
    return np.arange(int(np.prod(shape))).reshape(shape)


def heads_view(rows, heads, dim, keys_transposed=False):
    """(heads, rows, dim) -- or (heads, dim, rows) -- view of a [rows, heads*dim] matrix."""
    v = np.arange(rows * heads * dim).reshape(rows, heads, dim)
    return v.transpose(1, 2, 0) if keys_transposed else v.transpose(1, 0, 2)


class PendingPad:
    def __init__(self, source: str, pads: list):
        self.source, self.pads = source, pads


class Lowering:
    def __init__(self, g: Graph):
        self.g = g
        self.eg = EngineGraph()
        self.view = {}  # onnx name -> (Tensor, idx)
        self.pending = {}  # onnx name -> PendingPad

    # -- helpers -----------------------------------------------------------
    def fail(self, node: Node, msg: str):
        raise UnsupportedOnnx(f"node {node.name!r} ({node.op}): {msg}")

    def get(self, node: Node, name: str):
        if name in self.pending:
            self.fail(node, "reads a Pad output; padding is only supported in front of a Conv")
        if name not in self.view:
            self.fail(node, f"input {name!r} has no engine tensor")
        return self.view[name]

    def need(self, node: Node, name: str, expected: np.ndarray, what: str) -> Tensor:
        if self.g.is_const(name):  # e.g. the decoder's first query: lay the constant out
            value = np.asarray(self.g.const(name), np.float32)
            if value.shape != expected.shape:
                self.fail(node, f"constant {name!r} has shape {value.shape}, not {expected.shape}")
            data = np.zeros(expected.size, np.float32)
            data[expected.reshape(-1)] = value.reshape(-1)
            return self.eg.const(name, data)
        t, idx = self.get(node, name)
        if idx.shape != expected.shape or not np.array_equal(idx, expected) or \
                t.numel != expected.size:
            self.fail(node, f"input {name!r} is not laid out as {what}; the engine would need a "
                            "copy it does not have")
        return t

    def act_tensor(self, name: str, shape) -> Tensor:
        if len(shape) > spec.MAX_RANK:
            raise UnsupportedOnnx(f"tensor {name!r} has rank {len(shape)} > {spec.MAX_RANK}")
        return self.eg.add(Tensor(name, tuple(int(s) for s in shape)))

    def emit(self, code, node, inputs, outputs, **params):
        op = Op(code, node.name, inputs, outputs, params)
        self.eg.ops.append(op)
        return op

    def engine_const_like(self, node, name, const, x_name):
        """Rearrange constant `const` (broadcast to x's ONNX shape) into x's engine layout."""
        t, idx = self.get(node, x_name)
        flat = idx.reshape(-1)
        if flat.size != t.numel or not np.array_equal(np.sort(flat), np.arange(t.numel)):
            self.fail(node, "a constant operand meets an input whose layout repeats elements")
        data = np.zeros(t.numel, np.float32)
        data[flat] = np.broadcast_to(np.asarray(const, np.float32), idx.shape).reshape(-1)
        return self.eg.const(name, data.reshape(t.shape))

    # -- driver ------------------------------------------------------------
    def run(self) -> EngineGraph:
        g = self.g
        shape = g.shape(g.input_name)
        if len(shape) != 4 or shape[0] != 1:
            raise UnsupportedOnnx(f"input {g.input_name!r} has shape {shape}; expected (1, C, H, W)")
        n, c, h, w = shape
        t = self.eg.add(Tensor("input", (1, h, w, c), spec.KIND_INPUT))
        self.view[g.input_name] = (t, nhwc_view(n, c, h, w))
        for node in g.nodes:
            handler = getattr(self, "op_" + node.op.replace(".", "_"), None)
            if handler is None:
                if node.op in LAYOUT:
                    self.layout(node)
                    continue
                self.fail(node, "operator not supported by the aprt engine")
            handler(node)
        for name, label in zip(g.output_names, g.output_labels):
            t, idx = self.view[name]
            if not np.array_equal(idx, rows_view(idx.shape)) or t.numel != idx.size:
                raise UnsupportedOnnx(f"graph output {label!r} is not a contiguous engine tensor")
            t.kind, t.name, t.shape = spec.KIND_OUTPUT, label, tuple(idx.shape)
        return self.eg

    # -- layout ops ----------------------------------------------------------
    def layout(self, node: Node):
        dyn = [i for i in node.inputs if i and not self.g.is_const(i)]
        if node.op == "Concat":
            bases = {id(self.get(node, i)[0]) for i in dyn}
            if len(bases) != 1 or len(dyn) != len(node.inputs):
                return self.op_Concat_compute(node)
        if len(dyn) != 1 and node.op != "Concat":
            self.fail(node, "layout op with more than one dynamic input")
        base = self.get(node, dyn[0])[0]
        ins = [self.view[i][1] if i in self.view else self.g.const(i) if i else None
               for i in node.inputs]
        outs = run_node(_as_onnx(node), ins)
        for name, idx in zip(node.outputs, outs):
            self.view[name] = (base, np.asarray(idx))

    # -- compute ops ---------------------------------------------------------
    def op_Pad(self, node: Node):
        g = self.g
        pads = node.attrs.get("pads")
        if pads is None:
            pads = g.const(node.inputs[1])
        if node.attrs.get("mode", b"constant") not in (b"constant", "constant"):
            self.fail(node, "only constant (zero) padding is supported")
        if len(node.inputs) > 2 and node.inputs[2] and np.any(g.const(node.inputs[2]) != 0):
            self.fail(node, "only zero padding is supported")
        pads = [int(p) for p in np.asarray(pads).reshape(-1)]
        if len(pads) != 8 or any(pads[i] for i in (0, 1, 4, 5)) or min(pads) < 0:
            self.fail(node, f"pads {pads}: only non-negative spatial padding of NCHW is supported")
        src = node.inputs[0]
        if src in self.pending:  # Pad after Pad
            prev = self.pending[src]
            pads = [a + b for a, b in zip(prev.pads, pads)]
            src = prev.source
        self.pending[node.outputs[0]] = PendingPad(src, pads)

    def op_Conv(self, node: Node):
        g = self.g
        x = node.inputs[0]
        extra = [0] * 8
        if x in self.pending:
            extra, x = self.pending[x].pads, self.pending[x].source
        w = g.const(node.inputs[1])
        if w is None or w.ndim != 4:
            self.fail(node, "weights must be a constant 4-D tensor")
        w = np.asarray(w, np.float32)
        b = (np.asarray(g.const(node.inputs[2]), np.float32).reshape(-1)
             if len(node.inputs) > 2 and node.inputs[2] else np.zeros(w.shape[0], np.float32))
        a = node.attrs
        if list(a.get("dilations", [1, 1])) != [1, 1]:
            self.fail(node, "dilated convolution is not supported")
        if a.get("auto_pad", b"NOTSET") not in (b"NOTSET", "NOTSET"):
            self.fail(node, "auto_pad is not supported")
        p = list(a.get("pads", [0, 0, 0, 0]))  # t, l, b, r
        pads = (p[0] + extra[2], p[1] + extra[3], p[2] + extra[6], p[3] + extra[7])
        stride = tuple(int(s) for s in a.get("strides", [1, 1]))
        group = int(a.get("group", 1))
        n, cin, h, wd = g.shape(x)
        cout, cin_g, kh, kw = w.shape
        xin = self.need(node, x, nhwc_view(n, cin, h, wd), "NHWC")
        _, _, oh, ow = g.shape(node.outputs[0])
        y = self.act_tensor(node.outputs[0], (1, oh, ow, cout))
        self.view[node.outputs[0]] = (y, nhwc_view(1, cout, oh, ow))
        name = node.name
        if group == 1 and kh == kw == 1 and stride == (1, 1) and not any(pads):
            wt = self.eg.const(name + ".weight", w[:, :, 0, 0])
            self.emit(spec.OP_LINEAR, node, [xin, wt, self.eg.const(name + ".bias", b)], [y],
                      act=spec.ACT_NONE)
        elif group == cin == cout and cin_g == 1:
            wt = self.eg.const(name + ".weight", w[:, 0].transpose(1, 2, 0))  # KH, KW, C
            self.emit(spec.OP_DWCONV2D, node, [xin, wt, self.eg.const(name + ".bias", b)], [y],
                      stride=stride, pads=pads, act=spec.ACT_NONE)
        elif group == 1:
            wt = self.eg.const(name + ".weight", w.transpose(0, 2, 3, 1))  # Co, KH, KW, Ci
            self.emit(spec.OP_CONV2D, node, [xin, wt, self.eg.const(name + ".bias", b)], [y],
                      stride=stride, pads=pads, act=spec.ACT_NONE)
        else:
            self.fail(node, f"grouped convolution with {group} groups is not supported")

    def _unary_same_layout(self, node: Node, code, **params):
        t, idx = self.get(node, node.inputs[0])
        y = self.act_tensor(node.outputs[0], t.shape)
        self.view[node.outputs[0]] = (y, idx)
        self.emit(code, node, [t], [y], **params)

    def op_aprt_Silu(self, node):
        self._unary_same_layout(node, spec.OP_ACTIVATION, act=spec.ACT_SILU)

    def op_aprt_Gelu(self, node):
        self._unary_same_layout(node, spec.OP_ACTIVATION, act=spec.ACT_GELU)

    def op_Sigmoid(self, node):
        self._unary_same_layout(node, spec.OP_ACTIVATION, act=spec.ACT_SIGMOID)

    def op_Relu(self, node):
        self._unary_same_layout(node, spec.OP_ACTIVATION, act=spec.ACT_RELU)

    def op_Add(self, node: Node):
        g = self.g
        a, b = node.inputs
        out_shape = g.shape(node.outputs[0])
        if g.is_const(a):
            a, b = b, a
        ta, ia = self.get(node, a)
        if g.shape(a) != out_shape:
            self.fail(node, "broadcasting a dynamic operand is not supported")
        if g.is_const(b):
            tb = self.engine_const_like(node, node.name + ".const", g.const(b), a)
        else:
            tb, ib = self.get(node, b)
            if g.shape(b) != out_shape or not np.array_equal(ia, ib) or ta.numel != tb.numel:
                self.fail(node, "operands have different layouts")
        y = self.act_tensor(node.outputs[0], ta.shape)
        self.view[node.outputs[0]] = (y, ia)
        self.emit(spec.OP_ADD, node, [ta, tb], [y])

    def op_aprt_LayerNorm(self, node: Node):
        x = node.inputs[0]
        shape = self.g.shape(x)
        t = self.need(node, x, rows_view(shape), "contiguous rows")
        y = self.act_tensor(node.outputs[0], t.shape)
        self.view[node.outputs[0]] = (y, rows_view(shape))
        gamma = self.eg.const(node.name + ".weight", node.params["gamma"])
        beta = self.eg.const(node.name + ".bias", node.params["beta"])
        self.emit(spec.OP_LAYERNORM, node, [t, gamma, beta], [y], eps=node.params["eps"])

    def op_aprt_Linear(self, node: Node):
        x = node.inputs[0]
        shape = self.g.shape(x)
        w, b = node.params["w"], node.params["b"]
        if shape[-1] != w.shape[1]:
            self.fail(node, f"input width {shape[-1]} does not match weights {w.shape}")
        t = self.need(node, x, rows_view(shape), "contiguous rows")
        out_shape = self.g.shape(node.outputs[0])
        y = self.act_tensor(node.outputs[0], out_shape)
        self.view[node.outputs[0]] = (y, rows_view(out_shape))
        self.emit(spec.OP_LINEAR, node, [t, self.eg.const(node.name + ".weight", w),
                                         self.eg.const(node.name + ".bias", b)], [y],
                  act=spec.ACT_NONE)

    def op_aprt_SqueezeExcite(self, node: Node):
        x = node.inputs[0]
        n, c, h, w = self.g.shape(x)
        t = self.need(node, x, nhwc_view(n, c, h, w), "NHWC")
        y = self.act_tensor(node.outputs[0], t.shape)
        self.view[node.outputs[0]] = (y, nhwc_view(n, c, h, w))
        p = node.params
        ws = [self.eg.const(f"{node.name}.{k}", p[k]) for k in ("w1", "b1", "w2", "b2")]
        self.emit(spec.OP_SQUEEZE_EXCITE, node, [t] + ws, [y])

    def op_aprt_Attention(self, node: Node):
        qh, kt, vh = node.inputs
        heads, lq, d = self.g.shape(qh)
        _, _, lk = self.g.shape(kt)
        e = heads * d
        q = self.need(node, qh, heads_view(lq, heads, d), f"{heads} heads of a [{lq}, {e}] matrix")
        k = self.need(node, kt, heads_view(lk, heads, d, keys_transposed=True),
                      f"{heads} transposed heads of a [{lk}, {e}] matrix")
        v = self.need(node, vh, heads_view(lk, heads, d), f"{heads} heads of a [{lk}, {e}] matrix")
        for t in (q, k, v):
            if t.shape[-1] != e:
                self.fail(node, f"tensor {t.name!r} of shape {t.shape} is not [L, {e}]")
        y = self.act_tensor(node.outputs[0], (lq, e))
        self.view[node.outputs[0]] = (y, heads_view(lq, heads, d))
        self.emit(spec.OP_ATTENTION, node, [q, k, v], [y], heads=heads,
                  scale=float(node.params["scale"]))

    # -- the points modality's ops (model/point_ops.py; FORMAT.md "Point ops") --
    def xyz_operand(self, node: Node, name: str) -> Tensor:
        """Coordinates (1, 3, N, 1) that are the first three columns of an engine
        tensor's rows (the input's features, or an op's [N, 3] output)."""
        shape = self.g.shape(name)
        if len(shape) != 4 or shape[0] != 1 or shape[1] != 3 or shape[3] != 1:
            self.fail(node, f"coordinates {name!r} have shape {shape}, not (1, 3, N, 1)")
        t, idx = self.get(node, name)
        width = t.shape[-1]
        n = shape[2]
        want = (np.arange(n)[None, :] * width + np.arange(3)[:, None])[None, :, :, None]
        if width < 3 or t.numel != n * width or not np.array_equal(idx, want):
            self.fail(node, f"coordinates {name!r} are not the first three columns of a row "
                            "tensor; the engine would need a copy it does not have")
        return t

    def nchw_operand(self, node: Node, name: str) -> Tensor:
        n, c, h, w = self.g.shape(name)
        return self.need(node, name, nhwc_view(n, c, h, w), "NHWC")

    def nhwc_out(self, node: Node, name: str | None = None) -> Tensor:
        name = name or node.outputs[0]
        n, c, h, w = self.g.shape(name)
        y = self.act_tensor(name, (1, h, w, c))
        self.view[name] = (y, nhwc_view(1, c, h, w))
        return y

    def op_FarthestPointSample(self, node: Node):
        x = self.xyz_operand(node, node.inputs[0])
        if int(node.attrs["count"]) > x.numel // x.shape[-1]:
            self.fail(node, f"samples {node.attrs['count']} of {x.numel // x.shape[-1]} points")
        self.emit(spec.OP_FPS, node, [x], [self.nhwc_out(node)])

    def op_BallGroup(self, node: Node):
        p = self.xyz_operand(node, node.inputs[0])
        c = self.xyz_operand(node, node.inputs[1])
        f = self.nchw_operand(node, node.inputs[2]) if len(node.inputs) > 2 and node.inputs[2] \
            else None
        self.emit(spec.OP_BALL_GROUP, node, [p, c, f], [self.nhwc_out(node)],
                  radius=float(node.attrs["radius"]))

    def op_ThreeInterpolate(self, node: Node):
        t = self.xyz_operand(node, node.inputs[0])
        k = self.xyz_operand(node, node.inputs[1])
        f = self.nchw_operand(node, node.inputs[2])
        self.emit(spec.OP_THREE_INTERP, node, [t, k, f], [self.nhwc_out(node)])

    def op_GridTokens(self, node: Node):
        p = self.xyz_operand(node, node.inputs[0])
        f = self.nchw_operand(node, node.inputs[1])
        a = node.attrs
        self.emit(spec.OP_GRID_TOKENS, node, [p, f], [self.nhwc_out(node)],
                  groups=int(a["groups"]), gx=int(a["gx"]), gy=int(a["gy"]))

    def op_ReduceMax(self, node: Node):
        """Max over the neighbours of a grouped map (1, C, S, K) -> (1, C, S, 1)."""
        axes = node.attrs.get("axes")
        if axes is None and len(node.inputs) > 1 and node.inputs[1]:
            axes = self.g.const(node.inputs[1])
        shape = self.g.shape(node.inputs[0])
        axes = None if axes is None else [int(a) % len(shape) for a in np.asarray(axes).reshape(-1)]
        if len(shape) != 4 or axes != [3] or not node.attrs.get("keepdims", 1):
            self.fail(node, "only a max over the last axis of a (1, C, S, K) map is supported")
        x = self.nchw_operand(node, node.inputs[0])
        self.emit(spec.OP_GROUP_MAX, node, [x], [self.nhwc_out(node)])

    def op_Concat_compute(self, node: Node):
        g = self.g
        rank = len(g.shape(node.outputs[0]))
        axis = int(node.attrs["axis"]) % rank
        if rank == 4 and axis == 1 and all(not g.is_const(i) for i in node.inputs):
            # channels of NHWC maps: a row-wise concatenation of their [H*W, C] rows
            if len(node.inputs) > spec.MAX_OP_INPUTS:
                self.fail(node, "concatenation inputs must be at most 8 dynamic tensors")
            ins = [self.nchw_operand(node, i) for i in node.inputs]
            self.emit(spec.OP_CONCAT, node, ins, [self.nhwc_out(node)])
            return
        if axis != len(g.shape(node.outputs[0])) - 1:
            self.fail(node, "concatenation of separate tensors is only supported on the last axis")
        if any(g.is_const(i) for i in node.inputs) or len(node.inputs) > spec.MAX_OP_INPUTS:
            self.fail(node, "concatenation inputs must be at most 8 dynamic tensors")
        ins = [self.need(node, i, rows_view(g.shape(i)), "contiguous rows") for i in node.inputs]
        out_shape = g.shape(node.outputs[0])
        y = self.act_tensor(node.outputs[0], out_shape)
        self.view[node.outputs[0]] = (y, rows_view(out_shape))
        self.emit(spec.OP_CONCAT, node, ins, [y])


LAYOUT = {"Reshape", "Flatten", "Squeeze", "Unsqueeze", "Transpose", "Identity", "Gather",
          "Slice", "Split", "Concat", "Expand", "Tile"}


def _as_onnx(node: Node):
    import onnx

    n = onnx.helper.make_node(node.op, [f"i{k}" for k in range(len(node.inputs))],
                              [f"o{k}" for k in range(len(node.outputs))], name=node.name)
    for k, v in node.attrs.items():
        n.attribute.append(onnx.helper.make_attribute(k, v))
    return n


def lower(g: Graph) -> tuple[EngineGraph, dict]:
    lw = Lowering(g)
    eg = lw.run()
    return eg, lw.view
