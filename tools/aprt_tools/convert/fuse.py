"""Engine-level fusions: epilogues folded into the op that produces their input.

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


def fuse(eg: EngineGraph) -> None:
    for step in (fuse_activations, fuse_residuals, fuse_constant_adds):
        while step(eg):
            pass
    eg.prune()
