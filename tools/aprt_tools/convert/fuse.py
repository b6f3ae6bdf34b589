"""Engine-level rewrites: single-query attention algebra, and epilogues folded
into the op that produces their input.

- Attention with one query over one key is its value: the op disappears (and
  with it the query and key projections).
- Attention with one query over many keys whose keys and values are
  projections of the same memory becomes CROSS_ATTENTION_1Q, which never
  projects the memory: score_h = (W_k,h^T q_h) . (m + pos) (the key bias adds
  the same to every score and cancels in the softmax), out_h = W_v,h (sum_j
  a_j m_j) + b_v,h (the weights sum to one).
- ACTIVATION after CONV2D / DWCONV2D / LINEAR becomes that op's `act`.
- ADD of two activations becomes the `residual` input of the later producer
  (CONV2D or LINEAR), added after its activation.
- ADD of a constant that is the same for every row becomes part of a LINEAR's
  bias (e.g. the decoder's constant first-layer output added to a projection).
Each fusion requires the intermediate tensor to have no other reader.
"""

from __future__ import annotations

import numpy as np

from ..model_bin import spec
from .engine_ir import EngineGraph, Op

EPILOGUE_OPS = (spec.OP_CONV2D, spec.OP_DWCONV2D, spec.OP_LINEAR)
RESIDUAL_OPS = (spec.OP_CONV2D, spec.OP_LINEAR)


def _sole_reader(eg: EngineGraph, t, op: Op) -> bool:
    return t.kind == spec.KIND_ACTIVATION and eg.users(t) == [op]


def _has_residual(op: Op) -> bool:
    return len(op.inputs) > 3 and op.inputs[3] is not None


def _replace_output(eg: EngineGraph, producer: Op, fused: Op):
    """`producer` now writes what `fused` wrote; `fused` disappears."""
    old, new = producer.outputs[0], fused.outputs[0]
    producer.outputs[0] = new
    eg.ops.remove(fused)
    del old


def fuse_activations(eg: EngineGraph) -> bool:
    for op in eg.ops:
        if op.code != spec.OP_ACTIVATION:
            continue
        src = eg.producer(op.inputs[0])
        if src is None or src.code not in EPILOGUE_OPS or src.params.get("act", 0) or \
                _has_residual(src) or not _sole_reader(eg, op.inputs[0], op):
            continue
        src.params["act"] = op.params["act"]
        _replace_output(eg, src, op)
        return True
    return False


def fuse_residuals(eg: EngineGraph) -> bool:
    for op in eg.ops:
        if op.code != spec.OP_ADD or any(t.kind != spec.KIND_ACTIVATION and t.kind !=
                                         spec.KIND_INPUT for t in op.inputs):
            continue
        a, b = op.inputs
        pa, pb = eg.producer(a), eg.producer(b)
        order = {id(o): i for i, o in enumerate(eg.ops)}
        # The later producer takes the other operand as its residual.
        cands = sorted([(pa, a, b), (pb, b, a)], key=lambda c: -order.get(id(c[0]), -1))
        for prod, mine, other in cands:
            if prod is None or prod.code not in RESIDUAL_OPS or _has_residual(prod) or \
                    not _sole_reader(eg, mine, op) or mine.numel != other.numel:
                continue
            while len(prod.inputs) < 3:
                prod.inputs.append(None)
            prod.inputs = prod.inputs[:3] + [other]
            _replace_output(eg, prod, op)
            return True
    return False


def fuse_constant_adds(eg: EngineGraph) -> bool:
    for op in eg.ops:
        if op.code != spec.OP_ADD or op.inputs[1].kind != spec.KIND_CONST:
            continue
        x, c = op.inputs
        src = eg.producer(x)
        if src is None or src.code != spec.OP_LINEAR or src.params.get("act", 0) or \
                not _sole_reader(eg, x, op):
            continue
        n = src.inputs[1].shape[0]
        rows = c.data.reshape(-1, n)
        if not np.all(rows == rows[0]):
            continue
        bias = src.inputs[2]
        if len(eg.users(bias)) != 1:
            continue
        bias.data = (bias.data + rows[0]).astype(np.float32)
        _replace_output(eg, src, op)
        return True
    return False


def _rows(t) -> int:
    return int(np.prod(t.shape[:-1]))


def _plain_linear(eg: EngineGraph, t, reader: Op):
    """The LINEAR (no activation, no residual) writing `t`, if `reader` is its only reader."""
    op = eg.producer(t)
    if op is None or op.code != spec.OP_LINEAR or op.params.get("act", 0) or _has_residual(op):
        return None
    return op if _sole_reader(eg, t, reader) else None


def _redirect(eg: EngineGraph, old, new):
    for op in eg.ops:
        op.inputs = [new if t is old else t for t in op.inputs]
    if old.kind == spec.KIND_OUTPUT:
        raise ValueError("cannot redirect a graph output")


def single_query_attention(eg: EngineGraph) -> bool:
    for op in eg.ops:
        if op.code != spec.OP_ATTENTION or _rows(op.inputs[0]) != 1:
            continue
        q, k, v = op.inputs
        out = op.outputs[0]
        if _rows(k) == 1 and out.kind == spec.KIND_ACTIVATION:
            # softmax over a single key is exactly 1: the output is the value row.
            eg.ops.remove(op)
            _redirect(eg, out, v)
            return True
        kl, vl = _plain_linear(eg, k, op), _plain_linear(eg, v, op)
        if kl is None or vl is None:
            continue
        memory = vl.inputs[0]
        key_in = kl.inputs[0]
        pos, add = None, None
        if key_in is not memory:
            # key input = memory + pos; the sum may be shared by several layers' key
            # projections (it stays until its last reader is fused).
            add = eg.producer(key_in)
            if add is None or add.code != spec.OP_ADD or memory not in add.inputs:
                continue
            pos = add.inputs[1] if add.inputs[0] is memory else add.inputs[0]
        fused = Op(spec.OP_CROSS_ATTENTION_1Q, op.name,
                   [q, memory, pos, kl.inputs[1], kl.inputs[2], vl.inputs[1], vl.inputs[2]],
                   [out], dict(heads=op.params["heads"], scale=op.params["scale"]))
        at = eg.ops.index(op)
        eg.ops[at] = fused
        eg.ops.remove(kl)
        eg.ops.remove(vl)  # a shared memory + pos is left to remove_dead_ops
        return True
    return False


def remove_dead_ops(eg: EngineGraph) -> bool:
    for op in reversed(eg.ops):
        t = op.outputs[0]
        if t.kind != spec.KIND_OUTPUT and not eg.users(t):
            eg.ops.remove(op)
            return True
    return False


def fuse(eg: EngineGraph, single_query: bool = True) -> None:
    steps = (single_query_attention, remove_dead_ops) if single_query else ()
    for step in steps + (fuse_activations, fuse_residuals, fuse_constant_adds, remove_dead_ops):
        while step(eg):
            pass
    eg.prune()
