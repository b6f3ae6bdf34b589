"""Several models of one configuration as one model file: an ensemble.

Networks trained apart (or continued from one another) make partly
independent errors, and the part that is their own averages out (Deep
Ensembles, Lakshminarayanan et al. 2017). Here the members' graphs are laid
side by side in one engine graph on the shared input, their 13 outputs
concatenated and averaged by one LINEAR op (weights 1/n): the runtime needs
nothing new, and the file is checked, signed, quantised and evaluated as any
other. The confidence outputs (log error scales) are averaged the same way
and the averaged head is calibrated again on the validation drive, as for a
single model (`confidence.py`); the rotation outputs are averaged and the
runtime normalises the quaternion as it does for one network.

  python3 -m aprt_tools ensemble A.aprt B.aprt [...] -o OUT.aprt --val DRIVE
"""

from __future__ import annotations

import hashlib
import json
import os

import numpy as np

from .model_bin import reader, spec
from .convert.engine_ir import EngineGraph, Op, Tensor

# Keys that must agree for the members to be one model: the input, its
# normalisation, the output's position bounds, the architecture.
_SAME = ("input_shape", "modality", "norm_mean", "norm_std", "pose_min", "pose_max",
         "resize_policy")
OUTPUTS = 13  # position 3, quaternion 4, log error scales 6 (AprConfig.uncertainty)


class EnsembleError(ValueError):
    pass


def _comparable(key: str, value):
    """The configuration without its training record ('extra': data, steps,
    minutes), which differs between members by design."""
    if key == "config_json" and value is not None:
        cfg = json.loads(value)
        cfg.pop("extra", None)
        return cfg
    return value


def _prefix(i: int) -> str:
    """Member i's tensors and ops are named m<i>:<its own name>."""
    return f"m{i}:"


def _member(graph: EngineGraph, prefix: str, name: str,
            shared_input: Tensor) -> tuple[list, list, Tensor]:
    """The member's tensors (renamed, its input replaced by the shared one),
    its ops, and its output turned into an activation."""
    inputs = [t for t in graph.tensors if t.kind == spec.KIND_INPUT]
    outputs = [t for t in graph.tensors if t.kind == spec.KIND_OUTPUT]
    if len(inputs) != 1 or len(outputs) != 1:
        raise EnsembleError(f"{name}: {len(inputs)} inputs and {len(outputs)} outputs "
                            "(an ensemble takes single-input, single-output models)")
    if outputs[0].shape != (1, OUTPUTS):
        raise EnsembleError(f"{name}: output {outputs[0].shape}, not (1, {OUTPUTS}): every "
                            "member needs the confidence outputs (train with --uncertainty)")
    if any(t.kind == spec.KIND_CONST and t.dtype != spec.DTYPE_F32 for t in graph.tensors):
        raise EnsembleError(f"{name}: an int8 file; build the ensemble from the fp32 files "
                            "and quantise it afterwards")
    swap = {id(inputs[0]): shared_input}
    tensors = []
    for t in graph.tensors:
        if t.kind == spec.KIND_INPUT:
            continue
        t.name = f"{prefix}{t.name}"
        if t.kind == spec.KIND_OUTPUT:
            t.kind = spec.KIND_ACTIVATION
        tensors.append(t)
    for op in graph.ops:
        op.name = f"{prefix}{op.name}"
        op.inputs = [swap.get(id(t), t) if t is not None else None for t in op.inputs]
    return tensors, graph.ops, outputs[0]


def build(files: list[bytes], names: list[str]) -> tuple[EngineGraph, dict]:
    """Model files (bytes) -> the ensemble's graph and metadata (without a
    calibration: its 'uncertainty' is removed)."""
    if not 2 <= len(files) <= spec.MAX_OP_INPUTS:
        raise EnsembleError(f"{len(files)} members: an ensemble takes 2 to "
                            f"{spec.MAX_OP_INPUTS}")
    read = [reader.read(f) for f in files]
    meta0 = dict(read[0][1])
    for (g, meta), name in zip(read[1:], names[1:]):
        for key in _SAME + ("config_json",):
            if _comparable(key, meta.get(key)) != _comparable(key, meta0.get(key)):
                raise EnsembleError(f"{name}: {key} differs from {names[0]}'s; an ensemble's "
                                    "members share one input, configuration and position bounds "
                                    "(continue or train them from one configuration)")
    if "ensemble" in meta0:
        raise EnsembleError(f"{names[0]} is itself an ensemble; give its members")
    shape0 = next(t.shape for t in read[0][0].tensors if t.kind == spec.KIND_INPUT)
    out = EngineGraph()
    shared = out.add(Tensor("input", shape0, spec.KIND_INPUT))
    member_outputs = []
    for i, (g, _) in enumerate(read):
        tensors, ops, pose = _member(g, _prefix(i), names[i], shared)
        out.tensors.extend(tensors)
        out.ops.extend(ops)
        member_outputs.append(pose)
    n = len(read)
    stacked = out.add(Tensor("ensemble/members", (1, OUTPUTS * n)))
    out.ops.append(Op(spec.OP_CONCAT, "ensemble/concat", member_outputs, [stacked]))
    weight = out.const("ensemble/mean.weight",
                       np.tile(np.eye(OUTPUTS, dtype=np.float32), (1, n)) / np.float32(n))
    bias = out.const("ensemble/mean.bias", np.zeros(OUTPUTS, np.float32))
    pose = out.add(Tensor("pose", (1, OUTPUTS), spec.KIND_OUTPUT))
    out.ops.append(Op(spec.OP_LINEAR, "ensemble/mean", [stacked, weight, bias], [pose],
                      {"act": 0}))
    meta0.pop("uncertainty", None)
    meta0["ensemble"] = n
    meta0["source_name"] = "ensemble of " + ", ".join(os.path.basename(n) for n in names)
    # The ensemble's identity: its members' sources, in order.
    meta0["source_sha256"] = hashlib.sha256(b"".join(bytes(m["source_sha256"])
                                                     for _, m in read)).digest()
    return out, meta0


def extract(data: bytes, index: int) -> bytes:
    """Member `index` of an ensemble file as a model file of its own (its
    graph, renamed back; the ensemble's metadata without the ensemble's
    calibration, which belongs to the average): to continue training from it
    (`train --init`) or to calibrate and evaluate it alone."""
    from .model_bin.writer import serialise

    graph, meta = reader.read(data)
    n = meta.get("ensemble")
    if not n:
        raise EnsembleError("not an ensemble file (no 'ensemble' key)")
    if not 0 <= index < n:
        raise EnsembleError(f"member {index}: the file has members 0 to {n - 1}")
    prefix = _prefix(index)
    mean = next(op for op in graph.ops if op.name == "ensemble/mean")
    concat = next(op for op in graph.ops if op.name == "ensemble/concat")
    pose, out = concat.inputs[index], mean.outputs[0]
    ops = [op for op in graph.ops if op.name.startswith(prefix)]
    member = EngineGraph()
    member.ops = ops
    for op in ops:
        op.name = op.name[len(prefix):]
        op.outputs = [out if t is pose else t for t in op.outputs]
    out.name = pose.name[len(prefix):]
    keep = {id(t) for op in ops for t in op.inputs + op.outputs if t is not None}
    keep |= {id(t.qscale) for t in graph.tensors if id(t) in keep and t.qscale is not None}
    for t in graph.tensors:
        if id(t) in keep and t is not pose:
            if t.kind != spec.KIND_INPUT and t is not out:
                t.name = t.name[len(prefix):]
            member.add(t)
    meta.pop("ensemble")
    meta.pop("uncertainty", None)
    meta.pop("val_error", None)
    meta["source_name"] = f"member {index} of {meta.get('source_name', 'an ensemble')}"
    return serialise(member, meta)


def member_outputs(files: list[bytes], folder: str):
    """Each member's raw outputs on a labelled drive, and the truth: the
    PyTorch side of the ensemble (the engine graph averages exactly these)."""
    from .confidence import outputs_on
    from .model_bin import to_torch

    raws = []
    for data in files:
        model, cfg = to_torch.load(data, None)
        raw, pos, quat = outputs_on(model, cfg, folder)
        raws.append(raw)
    return raws, pos, quat, cfg


def calibrated(files: list[bytes], names: list[str], val: str):
    """The ensemble file's bytes, its confidence calibrated on the labelled
    drive `val` (the members' averaged outputs, as the graph computes them:
    the runtime refuses confidence outputs without a calibration), and a report."""
    from .confidence import coverage, fit
    from .dataset import orientation_error_deg
    from .model_bin.writer import serialise

    graph, meta = build(files, names)
    raws, pos, quat, cfg = member_outputs(files, val)
    raw = np.mean(raws, axis=0)
    k_pos, k_rot = fit(raw, pos, quat, cfg.pose_min, cfg.pose_max)
    cov = coverage(raw, pos, quat, cfg.pose_min, cfg.pose_max, k_pos, k_rot)
    meta["uncertainty"] = [k_pos, k_rot]
    lo, hi = np.asarray(cfg.pose_min), np.asarray(cfg.pose_max)
    position = np.linalg.norm(raw[:, :3] * (hi - lo) + lo - pos, axis=1)
    # The same measures as `train` records for one network.
    angle = [orientation_error_deg(q, t) for q, t in zip(raw[:, 3:7], quat)]
    meta["val_error"] = [float(np.median(position)), float(np.median(angle))]
    report = (f"{len(files)} members, {len(graph.ops)} ops; validation median "
              f"{meta['val_error'][0]:.2f} m, {meta['val_error'][1]:.2f} deg; k_position {k_pos:.3f}, "
              f"k_rotation {k_rot:.3f} on {len(raw)} frames of {val}: {100 * cov[0]:.1f} % / "
              f"{100 * cov[1]:.1f} % of the position / yaw errors inside the 95 % regions")
    return serialise(graph, meta), report
