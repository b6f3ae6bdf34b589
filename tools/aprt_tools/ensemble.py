"""Several models of one configuration as one model file: an ensemble.

Networks trained apart (or continued from one another) make partly
independent errors, and the part that is their own averages out (Deep
Ensembles, Lakshminarayanan et al. 2017). Here the members' graphs are laid
side by side in one engine graph on the shared input and their 13 outputs
concatenated into the file's output (FORMAT.md 1.5); the runtime merges them
(runtime/engine/ensemble_merge.h, mirrored by ensemble_merge.py): the mean of
the positions and log error scales, the mean of the quaternions turned to
one sign (networks trained apart regress q and -q in different places, so
the graph cannot average them), and the members' spread, which joins the
confidence -- where they disagree the pose says so. The merged confidence is
calibrated again on the validation drive, as for a single model
(`confidence.py`). The file is checked, signed, quantised and evaluated as
any other.

Members may have been trained on different drives, so each may normalise
its positions by its own bounds (the training set's extent). The
ensemble's bounds are the union of theirs, and a member whose bounds differ
gets one more op, `m<i>:rebound`: a LINEAR that maps its outputs to the
ensemble's bounds (positions to the same metres, position log-scales to
the same sigma in metres), so the mean is a mean in metres.

  python3 -m aprt_tools ensemble A.aprt B.aprt [...] -o OUT.aprt --val DRIVE
"""

from __future__ import annotations

import hashlib
import json
import os

import numpy as np

from .ensemble_merge import merge
from .model_bin import reader, spec
from .convert.engine_ir import EngineGraph, Op, Tensor

# Keys that must agree for the members to be one model: the input, its
# normalisation, the architecture (config_json). The position bounds may
# differ (see rebound()).
_SAME = ("input_shape", "modality", "norm_mean", "norm_std", "resize_policy")
OUTPUTS = 13  # position 3, quaternion 4, log error scales 6 (AprConfig.uncertainty)



class EnsembleError(ValueError):
    pass


def _comparable(key: str, value):
    """The configuration without its training record ('extra': data, steps,
    minutes) and its position bounds, which differ between members by design."""
    if key == "config_json" and value is not None:
        cfg = json.loads(value)
        for k in ("extra", "pose_min", "pose_max"):
            cfg.pop(k, None)
        return cfg
    return value


def _bounds(meta: dict) -> tuple[np.ndarray, np.ndarray]:
    return np.asarray(meta["pose_min"], np.float64), np.asarray(meta["pose_max"], np.float64)


def union_bounds(metas: list) -> tuple[np.ndarray, np.ndarray]:
    """The ensemble's position bounds: every member's within them."""
    return (np.min([_bounds(m)[0] for m in metas], axis=0),
            np.max([_bounds(m)[1] for m in metas], axis=0))


def rebound(lo, hi, lo_e, hi_e) -> tuple[np.ndarray, np.ndarray]:
    """(W, b) of the affine map y = W x + b from a member's 13 outputs, its
    positions normalised by its bounds lo..hi, to the same outputs under the
    ensemble's bounds lo_e..hi_e: the position p' = (p (hi - lo) + lo - lo_e)
    / (hi_e - lo_e), the same point in metres; the position log-scale
    s' = s + log((hi - lo) / (hi_e - lo_e)), the same sigma in metres
    (pose_decode.cc: sigma = k sqrt(2) exp(s) (hi - lo)); the quaternion and
    the rotation log-scales as they are."""
    ext, ext_e = np.asarray(hi) - np.asarray(lo), np.asarray(hi_e) - np.asarray(lo_e)
    w, b = np.eye(OUTPUTS), np.zeros(OUTPUTS)
    w[[0, 1, 2], [0, 1, 2]] = ext / ext_e
    b[:3] = (np.asarray(lo) - np.asarray(lo_e)) / ext_e
    b[7:10] = np.log(ext / ext_e)
    return w, b


def _set_bounds(meta: dict, lo, hi) -> None:
    """The metadata's position bounds, in both places they are recorded."""
    meta["pose_min"], meta["pose_max"] = [float(v) for v in lo], [float(v) for v in hi]
    if meta.get("config_json") is not None:
        cfg = json.loads(meta["config_json"])
        cfg["pose_min"], cfg["pose_max"] = meta["pose_min"], meta["pose_max"]
        meta["config_json"] = json.dumps(cfg, sort_keys=True)


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
    lo_e, hi_e = union_bounds([m for _, m in read])
    member_outputs = []
    for i, (g, meta) in enumerate(read):
        tensors, ops, pose = _member(g, _prefix(i), names[i], shared)
        out.tensors.extend(tensors)
        out.ops.extend(ops)
        lo, hi = _bounds(meta)
        if not (np.array_equal(lo, lo_e) and np.array_equal(hi, hi_e)):
            w, b = rebound(lo, hi, lo_e, hi_e)
            moved = out.add(Tensor(f"{_prefix(i)}pose_rebound", (1, OUTPUTS)))
            out.ops.append(Op(spec.OP_LINEAR, f"{_prefix(i)}rebound",
                              [pose, out.const(f"{_prefix(i)}rebound.weight", w),
                               out.const(f"{_prefix(i)}rebound.bias", b)], [moved], {"act": 0}))
            pose = moved
        member_outputs.append(pose)
    n = len(read)
    pose = out.add(Tensor("pose", (1, OUTPUTS * n), spec.KIND_OUTPUT))
    out.ops.append(Op(spec.OP_CONCAT, "ensemble/concat", member_outputs, [pose]))
    meta0.pop("uncertainty", None)
    _set_bounds(meta0, lo_e, hi_e)
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
    concat = next(op for op in graph.ops if op.name == "ensemble/concat")
    # The file's output: the concatenation (1.5), or a mean after it (1.4).
    last = next((op for op in graph.ops if op.name == "ensemble/mean"), concat)
    pose, out = concat.inputs[index], last.outputs[0]
    moved = next((op for op in graph.ops if op.name == f"{prefix}rebound"), None)
    if moved is not None:
        # The member's own bounds, from the map to the ensemble's (rebound()).
        w, b = np.asarray(moved.inputs[1].data, np.float64), np.asarray(moved.inputs[2].data,
                                                                          np.float64)
        lo_e, hi_e = _bounds(meta)
        lo = b[:3] * (hi_e - lo_e) + lo_e
        _set_bounds(meta, lo, lo + np.diag(w)[:3] * (hi_e - lo_e))
        pose = moved.inputs[0]
    ops = [op for op in graph.ops if op.name.startswith(prefix) and op is not moved]
    member = EngineGraph()
    member.ops = ops
    for op in ops:
        op.name = op.name[len(prefix):]
        op.outputs = [out if t is pose else t for t in op.outputs]
    out.name = pose.name[len(prefix):]
    out.shape = (1, OUTPUTS)  # the member's 13, not the ensemble's 13 n
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
    """Each member's raw outputs on a labelled drive, mapped to the
    ensemble's bounds, the truth, and a configuration with those bounds: the
    PyTorch side of the ensemble (the engine graph averages exactly these)."""
    from .confidence import outputs_on
    from .model_bin import to_torch

    metas = [reader.read(data)[1] for data in files]
    lo_e, hi_e = union_bounds(metas)
    raws = []
    for data, meta in zip(files, metas):
        model, cfg = to_torch.load(data, None)
        raw, pos, quat = outputs_on(model, cfg, folder)
        w, b = rebound(*_bounds(meta), lo_e, hi_e)
        raws.append(raw @ w.T + b)
    cfg.pose_min, cfg.pose_max = tuple(lo_e), tuple(hi_e)
    return raws, pos, quat, cfg


def calibrated(files: list[bytes], names: list[str], val: str):
    """The ensemble file's bytes, its confidence calibrated on the labelled
    drive `val` (the members' outputs as the graph gives them, merged as the
    runtime merges them: the runtime refuses confidence outputs without a
    calibration), and a report."""
    from .confidence import coverage, fit
    from .dataset import orientation_error_deg
    from .model_bin.writer import serialise

    graph, meta = build(files, names)
    raws, pos, quat, cfg = member_outputs(files, val)
    raw = np.concatenate(raws, axis=1)  # what the graph outputs
    k_pos, k_rot = fit(raw, pos, quat, cfg.pose_min, cfg.pose_max)
    cov = coverage(raw, pos, quat, cfg.pose_min, cfg.pose_max, k_pos, k_rot)
    meta["uncertainty"] = [k_pos, k_rot]
    lo, hi = np.asarray(cfg.pose_min), np.asarray(cfg.pose_max)
    merged = merge(raw)[0]
    position = np.linalg.norm(merged[:, :3] * (hi - lo) + lo - pos, axis=1)
    # The same measures as `train` records for one network.
    angle = [orientation_error_deg(q, t) for q, t in zip(merged[:, 3:7], quat)]
    meta["val_error"] = [float(np.median(position)), float(np.median(angle))]
    report = (f"{len(files)} members, {len(graph.ops)} ops; validation median "
              f"{meta['val_error'][0]:.2f} m, {meta['val_error'][1]:.2f} deg; k_position {k_pos:.3f}, "
              f"k_rotation {k_rot:.3f} on {len(raw)} frames of {val}: {100 * cov[0]:.1f} % / "
              f"{100 * cov[1]:.1f} % of the position / yaw errors inside the 95 % regions")
    return serialise(graph, meta), report
