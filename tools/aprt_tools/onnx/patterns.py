"""Rewrites of the folded ONNX graph into the engine's vocabulary.

First `simplify` removes nodes that are identities once constants are known
(adding zeros, multiplying by one, zero padding, same-shape reshapes, ...).
Then each matcher replaces one subgraph by a macro node whose op name starts
with "aprt." and whose weights sit in `Node.params`:

    aprt.LayerNorm   ReduceMean/Sub/Pow/ReduceMean/Add/Sqrt/Div/Mul/Add, or LayerNormalization
    aprt.Gelu        x * 0.5 * (1 + erf(x / sqrt 2))
    aprt.Silu        x * sigmoid(x)
    aprt.SqueezeExcite  x * sigmoid(W2 silu(W1 mean_hw(x) + b1) + b2)
    aprt.Linear      MatMul by a constant (+ bias Add), or Gemm
    aprt.Attention   softmax(scale * Qh Kh^T) Vh, on head-split views

BatchNorm after a convolution is folded into it. Whatever is left must be a
Conv, a residual/positional Add, a Concat or a pure layout op; `lower.py`
refuses anything else with the node's name.
"""

from __future__ import annotations

import math

import numpy as np

from .evaluate import UnsupportedOnnx
from .graph import Graph, Node

LAYOUT_OPS = {"Reshape", "Flatten", "Squeeze", "Unsqueeze", "Transpose", "Identity", "Gather",
              "Slice", "Expand", "Tile"}


def _scalar(g: Graph, name: str):
    v = g.const(name)
    if v is None or np.size(v) != 1:
        return None
    return float(np.asarray(v).reshape(-1)[0])


def _all_equal(g: Graph, name: str, value: float) -> bool:
    v = g.const(name)
    return v is not None and np.size(v) > 0 and bool(np.all(np.asarray(v) == value))


def _dyn_inputs(g: Graph, n: Node) -> list:
    return [i for i in n.inputs if i and not g.is_const(i)]


def _identity_source(g: Graph, n: Node):
    """The input that `n` merely forwards, or None."""
    ins = n.inputs
    out = n.outputs[0] if n.outputs else None
    if n.op in ("Identity", "Dropout"):
        return ins[0]
    if out is None or len(n.outputs) != 1:
        return None
    dyn = _dyn_inputs(g, n)
    same = lambda i: g.shape(i) == g.shape(out) and g.values[i].dtype == g.values[out].dtype
    if n.op == "Add" and len(dyn) == 1:
        other = ins[1] if ins[0] == dyn[0] else ins[0]
        if _all_equal(g, other, 0.0) and same(dyn[0]):
            return dyn[0]
    if n.op == "Sub" and len(dyn) == 1 and ins[0] == dyn[0] and _all_equal(g, ins[1], 0.0) \
            and same(dyn[0]):
        return dyn[0]
    if n.op == "Mul" and len(dyn) == 1:
        other = ins[1] if ins[0] == dyn[0] else ins[0]
        if _all_equal(g, other, 1.0) and same(dyn[0]):
            return dyn[0]
    if n.op == "Div" and len(dyn) == 1 and ins[0] == dyn[0] and _all_equal(g, ins[1], 1.0) \
            and same(dyn[0]):
        return dyn[0]
    if n.op == "Pad" and len(ins) > 1 and _all_equal(g, ins[1], 0):
        return ins[0]
    if n.op == "Pad" and "pads" in n.attrs and not any(n.attrs["pads"]):
        return ins[0]
    if n.op in ("Cast", "Expand", "Reshape", "Squeeze", "Unsqueeze", "Flatten", "Tile", "Slice",
                "Concat") and len(dyn) == 1 and ins[0] == dyn[0] and same(dyn[0]):
        if n.op == "Concat" and len(ins) != 1:
            return None
        return dyn[0]
    if n.op == "Transpose" and list(n.attrs.get("perm", [])) == sorted(n.attrs.get("perm", [])):
        return ins[0]
    if n.op == "Where" and g.is_const(ins[0]):
        c = np.asarray(g.const(ins[0]))
        pick = ins[1] if c.all() else ins[2] if not c.any() else None
        if pick is not None and not g.is_const(pick) and same(pick):
            return pick
    return None


def simplify(g: Graph) -> None:
    changed = True
    while changed:
        changed = False
        for n in list(g.nodes):
            src = _identity_source(g, n)
            if src is None:
                continue
            out = n.outputs[0]
            g.nodes.remove(n)
            g.rename_uses(out, src)
            g.reindex()
            changed = True


# ---------------------------------------------------------------------------
# Matchers. Each returns True when it rewrote something.


def _single_user(g: Graph, name: str, op: str = None):
    users = g.consumers(name)
    if len(users) != 1 or name in g.output_names:
        return None
    if op is not None and users[0].op != op:
        return None
    return users[0]


def fold_batchnorm(g: Graph) -> bool:
    for bn in g.nodes:
        if bn.op != "BatchNormalization":
            continue
        conv = g.producer.get(bn.inputs[0])
        if conv is None or conv.op != "Conv" or _single_user(g, conv.outputs[0]) is not bn:
            raise UnsupportedOnnx(f"node {bn.name!r} (BatchNormalization): only BatchNorm "
                                  "directly after a convolution is supported")
        scale, bias, mean, var = (np.asarray(g.const(i), dtype=np.float64) for i in bn.inputs[1:5])
        eps = float(bn.attrs.get("epsilon", 1e-5))
        k = scale / np.sqrt(var + eps)
        w = np.asarray(g.const(conv.inputs[1]), dtype=np.float64)
        b = np.asarray(g.const(conv.inputs[2]), dtype=np.float64) if len(conv.inputs) > 2 and \
            conv.inputs[2] else np.zeros(w.shape[0])
        wname, bname = conv.name + "/bn_folded_w", conv.name + "/bn_folded_b"
        g.consts[wname] = (w * k.reshape(-1, 1, 1, 1)).astype(np.float32)
        g.consts[bname] = ((b - mean) * k + bias).astype(np.float32)
        conv.inputs = [conv.inputs[0], wname, bname]
        g.nodes.remove(bn)
        g.rename_uses(bn.outputs[0], conv.outputs[0])
        g.values[conv.outputs[0]] = g.values[bn.outputs[0]]
        g.reindex()
        return True
    return False


def match_layernorm(g: Graph) -> bool:
    for n in g.nodes:
        if n.op == "LayerNormalization":
            x = n.inputs[0]
            axis = int(n.attrs.get("axis", -1)) % len(g.shape(x))
            if axis != len(g.shape(x)) - 1:
                raise UnsupportedOnnx(f"node {n.name!r}: LayerNormalization over axis {axis} "
                                      "(only the last axis is supported)")
            d = g.shape(x)[-1]
            gamma = np.asarray(g.const(n.inputs[1]), np.float32).reshape(d)
            beta = (np.asarray(g.const(n.inputs[2]), np.float32).reshape(d)
                    if len(n.inputs) > 2 and n.inputs[2] else np.zeros(d, np.float32))
            new = Node("aprt.LayerNorm", n.name, [x], [n.outputs[0]],
                       params=dict(gamma=gamma, beta=beta, eps=float(n.attrs.get("epsilon", 1e-5))))
            g.replace([n], [new])
            return True
        m = _match_decomposed_layernorm(g, n)
        if m:
            removed, x, gamma, beta, eps = m
            name = removed[-1].name.rsplit("/", 1)[0] or removed[-1].name
            new = Node("aprt.LayerNorm", name, [x], [removed[-1].outputs[0]],
                       params=dict(gamma=gamma, beta=beta, eps=eps))
            g.replace(removed, [new], position_of=removed[-1])
            return True
    return False


def _last_axis_mean(g: Graph, node, x) -> bool:
    if node is None or node.op != "ReduceMean" or node.inputs[0] != x:
        return False
    axes = node.attrs.get("axes")
    if axes is None and len(node.inputs) > 1:
        axes = [int(v) for v in np.asarray(g.const(node.inputs[1])).reshape(-1)]
    r = len(g.shape(x))
    return axes is not None and [a % r for a in axes] == [r - 1] and node.attrs.get("keepdims", 1)


def _match_decomposed_layernorm(g: Graph, div: Node):
    """Div(Sub(x, mean(x)), Sqrt(Add(mean(Pow(Sub, 2)), eps))), then optionally
    Mul(gamma) and Add(beta) (absent when they were 1 and 0 and folded away)."""
    p = g.producer.get
    if div.op != "Div":
        return None
    sub, sqrt = p(div.inputs[0]), p(div.inputs[1])
    if sub is None or sub.op != "Sub" or sqrt is None or sqrt.op != "Sqrt":
        return None
    x = sub.inputs[0]
    rm1 = p(sub.inputs[1])
    if not _last_axis_mean(g, rm1, x):
        return None
    add_eps = p(sqrt.inputs[0])
    if add_eps is None or add_eps.op != "Add":
        return None
    rm2 = next((p(i) for i in add_eps.inputs if p(i) is not None and p(i).op == "ReduceMean"), None)
    eps_name = next((i for i in add_eps.inputs if g.is_const(i)), None)
    if rm2 is None or eps_name is None:
        return None
    pw = p(rm2.inputs[0])
    if pw is None or pw.op != "Pow" or pw.inputs[0] != sub.outputs[0] or _scalar(g, pw.inputs[1]) != 2.0:
        return None
    if not _last_axis_mean(g, rm2, pw.outputs[0]):
        return None
    d = g.shape(x)[-1]
    removed = [rm1, sub, pw, rm2, add_eps, sqrt, div]
    gamma, beta = np.ones(d, np.float32), np.zeros(d, np.float32)
    tail = div
    for op, is_scale in (("Mul", True), ("Add", False)):
        nxt = _single_user(g, tail.outputs[0], op)
        c = next((i for i in nxt.inputs if g.is_const(i)), None) if nxt is not None else None
        if c is None or np.size(g.const(c)) not in (1, d) or g.shape(nxt.outputs[0]) != g.shape(x):
            continue
        v = np.broadcast_to(np.asarray(g.const(c), np.float32).reshape(-1), (d,)).copy()
        if is_scale:
            gamma = v
        else:
            beta = v
        removed.append(nxt)
        tail = nxt
    for node in removed[:-1]:
        for o in node.outputs:
            if not g.only_used_by(o, removed):
                return None
    return removed, x, gamma, beta, _scalar(g, eps_name)


def match_gelu(g: Graph) -> bool:
    """x * 0.5 * (1 + erf(x / sqrt 2)), whichever way the two Muls associate."""
    p = g.producer.get
    for erf in g.nodes:
        if erf.op != "Erf":
            continue
        scale = p(erf.inputs[0])
        if scale is None or scale.op not in ("Div", "Mul"):
            continue
        x = next((i for i in scale.inputs if not g.is_const(i)), None)
        c = next((_scalar(g, i) for i in scale.inputs if g.is_const(i)), None)
        if x is None or c is None or (scale.op == "Div" and scale.inputs[0] != x):
            continue
        if abs((1.0 / c if scale.op == "Div" else c) - 1 / math.sqrt(2)) > 1e-6:
            continue
        add1 = _single_user(g, erf.outputs[0], "Add")
        if add1 is None or next((_scalar(g, i) for i in add1.inputs if g.is_const(i)), None) != 1.0:
            continue
        m1 = _single_user(g, add1.outputs[0], "Mul")
        if m1 is None:
            continue
        other = next((i for i in m1.inputs if i != add1.outputs[0]), None)
        m2 = _single_user(g, m1.outputs[0], "Mul")
        if other == x and m2 is not None and any(_scalar(g, i) == 0.5 for i in m2.inputs):
            removed = [scale, erf, add1, m1, m2]  # (x * (1 + erf)) * 0.5
        elif _scalar(g, other) == 0.5 and m2 is not None and x in m2.inputs:
            removed = [scale, erf, add1, m1, m2]  # x * ((1 + erf) * 0.5)
        elif p(other) is not None and p(other).op == "Mul" and \
                sorted(p(other).inputs, key=lambda i: i == x) and x in p(other).inputs and \
                any(_scalar(g, i) == 0.5 for i in p(other).inputs):
            removed = [scale, erf, add1, p(other), m1]  # (x * 0.5) * (1 + erf)
        else:
            continue
        out = removed[-1].outputs[0]
        if not all(g.only_used_by(o, removed) for r in removed[:-1] for o in r.outputs):
            continue
        g.replace(removed, [Node("aprt.Gelu", erf.name.rsplit("/", 1)[0], [x], [out])],
                  position_of=removed[-1])
        return True
    return False


def match_silu(g: Graph) -> bool:
    for sig in g.nodes:
        if sig.op != "Sigmoid":
            continue
        mul = _single_user(g, sig.outputs[0], "Mul")
        x = sig.inputs[0]
        if mul is None or sorted(mul.inputs) != sorted([x, sig.outputs[0]]):
            continue
        g.replace([sig, mul], [Node("aprt.Silu", mul.name.rsplit("/", 1)[0], [x],
                                    [mul.outputs[0]])])
        return True
    return False


def _conv1x1(g: Graph, node, src):
    """(W [N, K], b [N]) of a 1x1 stride-1 unpadded Conv on `src`, else None."""
    if node is None or node.op != "Conv" or node.inputs[0] != src:
        return None
    w = g.const(node.inputs[1])
    if w is None or w.ndim != 4 or w.shape[2:] != (1, 1) or int(node.attrs.get("group", 1)) != 1:
        return None
    if any(node.attrs.get("pads", [0, 0, 0, 0])) or list(node.attrs.get("strides", [1, 1])) != [1, 1]:
        return None
    b = g.const(node.inputs[2]) if len(node.inputs) > 2 and node.inputs[2] else np.zeros(w.shape[0])
    return np.asarray(w, np.float32)[:, :, 0, 0], np.asarray(b, np.float32)


def match_squeeze_excite(g: Graph) -> bool:
    p = g.producer.get
    for gap in g.nodes:
        if gap.op not in ("GlobalAveragePool", "ReduceMean"):
            continue
        x = gap.inputs[0]
        if gap.op == "ReduceMean":
            axes = gap.attrs.get("axes")
            if axes is None or sorted(a % 4 for a in axes) != [2, 3] or not gap.attrs.get("keepdims", 1):
                continue
        c1 = _single_user(g, gap.outputs[0], "Conv")
        r1 = _conv1x1(g, c1, gap.outputs[0])
        act = _single_user(g, c1.outputs[0], "aprt.Silu") if r1 else None
        c2 = _single_user(g, act.outputs[0], "Conv") if act else None
        r2 = _conv1x1(g, c2, act.outputs[0]) if c2 else None
        sig = _single_user(g, c2.outputs[0], "Sigmoid") if r2 else None
        mul = _single_user(g, sig.outputs[0], "Mul") if sig else None
        if mul is None or sorted(mul.inputs) != sorted([x, sig.outputs[0]]):
            continue
        del p
        new = Node("aprt.SqueezeExcite", gap.name.rsplit("/", 1)[0], [x], [mul.outputs[0]],
                   params=dict(w1=r1[0], b1=r1[1], w2=r2[0], b2=r2[1]))
        g.replace([gap, c1, act, c2, sig, mul], [new])
        return True
    return False


def match_linear(g: Graph) -> bool:
    for n in g.nodes:
        if n.op == "Gemm":
            x, wn = n.inputs[0], n.inputs[1]
            w = g.const(wn)
            if w is None or g.is_const(x) or n.attrs.get("transA", 0):
                raise UnsupportedOnnx(f"node {n.name!r} (Gemm): needs a constant B and an "
                                      "untransposed dynamic A")
            w = np.asarray(w, np.float32)
            w = w if n.attrs.get("transB", 0) else w.T
            alpha, beta = float(n.attrs.get("alpha", 1.0)), float(n.attrs.get("beta", 1.0))
            b = np.zeros(w.shape[0], np.float32)
            if len(n.inputs) > 2 and n.inputs[2]:
                c = g.const(n.inputs[2])
                if c is None or np.size(c) not in (1, w.shape[0]):
                    raise UnsupportedOnnx(f"node {n.name!r} (Gemm): C must be a constant row")
                b = np.broadcast_to(np.asarray(c, np.float32).reshape(-1), (w.shape[0],)) * beta
            new = Node("aprt.Linear", n.name, [x], [n.outputs[0]],
                       params=dict(w=(w * alpha).astype(np.float32), b=b.astype(np.float32)))
            g.replace([n], [new])
            return True
        if n.op == "MatMul" and g.is_const(n.inputs[1]) and not g.is_const(n.inputs[0]):
            w = np.asarray(g.const(n.inputs[1]), np.float32)
            if w.ndim != 2:
                raise UnsupportedOnnx(f"node {n.name!r} (MatMul): constant operand of rank {w.ndim}")
            removed, out = [n], n.outputs[0]
            b = np.zeros(w.shape[1], np.float32)
            add = _single_user(g, out, "Add")
            if add is not None:
                bias = next((i for i in add.inputs if g.is_const(i)), None)
                if bias is not None and np.size(g.const(bias)) == w.shape[1] and \
                        g.shape(add.outputs[0]) == g.shape(out):
                    b = np.asarray(g.const(bias), np.float32).reshape(-1)
                    removed, out = [n, add], add.outputs[0]
            new = Node("aprt.Linear", n.name.rsplit("/", 1)[0], [n.inputs[0]], [out],
                       params=dict(w=np.ascontiguousarray(w.T), b=b))
            g.replace(removed, [new])
            return True
    return False


def _strip_scale(g: Graph, name: str):
    """Walk back through Mul/Div by constant scalars: (source name, factor, nodes)."""
    factor, nodes = 1.0, []
    while True:
        n = g.producer.get(name)
        if n is None or n.op not in ("Mul", "Div") or len(g.consumers(name)) != 1:
            return name, factor, nodes
        dyn = [i for i in n.inputs if not g.is_const(i)]
        c = next((_scalar(g, i) for i in n.inputs if g.is_const(i)), None)
        if len(dyn) != 1 or c is None or (n.op == "Div" and n.inputs[0] != dyn[0]):
            return name, factor, nodes
        factor *= (1.0 / c) if n.op == "Div" else c
        nodes.append(n)
        name = dyn[0]


def match_attention(g: Graph) -> bool:
    for sm in g.nodes:
        if sm.op != "Softmax":
            continue
        s = sm.inputs[0]
        rank = len(g.shape(s))
        if int(sm.attrs.get("axis", -1)) % rank != rank - 1:
            raise UnsupportedOnnx(f"node {sm.name!r} (Softmax): only the last axis is supported")
        scores, f0, n0 = _strip_scale(g, s)
        mm1 = g.producer.get(scores)
        if mm1 is None or mm1.op != "MatMul" or len(g.consumers(scores)) != 1:
            raise UnsupportedOnnx(f"node {sm.name!r} (Softmax): not part of a recognised "
                                  "attention pattern (softmax(Q K^T) V)")
        qh, f1, n1 = _strip_scale(g, mm1.inputs[0])
        kt, f2, n2 = _strip_scale(g, mm1.inputs[1])
        mm2 = _single_user(g, sm.outputs[0], "MatMul")
        if mm2 is None or mm2.inputs[0] != sm.outputs[0]:
            raise UnsupportedOnnx(f"node {sm.name!r} (Softmax): its output must feed one MatMul "
                                  "with the values")
        vh = mm2.inputs[1]
        shapes = [g.shape(qh), g.shape(kt), g.shape(vh)]
        if any(len(sh) != 3 for sh in shapes) or shapes[0][2] != shapes[1][1] or \
                shapes[1][2] != shapes[2][1]:
            raise UnsupportedOnnx(f"node {sm.name!r}: attention operands of shapes {shapes} "
                                  "(expected (heads, Lq, d), (heads, d, Lk), (heads, Lk, d))")
        removed = n0 + [mm1] + n1 + n2 + [sm, mm2]
        name = sm.name.rsplit("/", 1)[0]
        new = Node("aprt.Attention", name, [qh, kt, vh], [mm2.outputs[0]],
                   params=dict(scale=f0 * f1 * f2, heads=shapes[0][0]))
        g.replace(removed, [new], position_of=mm2)
        return True
    return False


MATCHERS = (fold_batchnorm, match_layernorm, match_gelu, match_silu, match_squeeze_excite,
            match_attention, match_linear)


def rewrite(g: Graph) -> None:
    simplify(g)
    for matcher in MATCHERS:
        while matcher(g):
            pass
    simplify(g)
