"""ONNX -> model_bin: fold, rewrite, lower, fuse, check against ONNX, write."""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field

import numpy as np
import onnx

from .. import __version__
from ..model_bin import spec
from ..model_bin.writer import serialise
from ..onnx.evaluate import UnsupportedOnnx
from ..onnx.graph import fold
from ..onnx.patterns import rewrite
from . import engine_ir
from .fuse import fuse
from .lower import lower

MIN_OPSET, MAX_OPSET = 13, 17


@dataclass
class Report:
    ops: dict = field(default_factory=dict)
    tensors: int = 0
    weight_bytes: int = 0
    max_rel_error_lowered: float = 0.0
    max_rel_error_output: float = 0.0
    meta: dict = field(default_factory=dict)

    def text(self) -> str:
        ops = ", ".join(f"{k} {v}" for k, v in sorted(self.ops.items()))
        return (f"{sum(self.ops.values())} ops ({ops}); {self.tensors} tensors; "
                f"{self.weight_bytes / 1e6:.2f} MB weights; max relative deviation from ONNX "
                f"{self.max_rel_error_output:.2e} (outputs), {self.max_rel_error_lowered:.2e} "
                "(every intermediate)")


def _rel(ref, got) -> float:
    ref = np.asarray(ref, np.float64)
    return float(np.abs(ref - got).max() / max(np.abs(ref).max(), 1e-6))


def _infer_architecture(eg) -> dict:
    att = [op for op in eg.ops if op.code == spec.OP_ATTENTION]
    cross = [op for op in eg.ops if op.code == spec.OP_CROSS_ATTENTION_1Q]
    if not att and not cross:
        raise UnsupportedOnnx("the graph has no attention: not an APR-Transformer")
    first = (att or cross)[0]
    e = first.inputs[0].shape[-1]
    heads = first.params["heads"]
    enc = sum(1 for op in att if _rows(op.inputs[0]) == _rows(op.inputs[1]) > 1)
    cross_count = len(cross) + sum(1 for op in att if _rows(op.inputs[0]) == 1 and
                                   _rows(op.inputs[1]) > 1)
    return dict(d_model=e, nheads=heads, enc_layers=enc // 2, dec_layers=cross_count // 2)


def _rows(t) -> int:
    return int(np.prod(t.shape[:-1]))


def build_meta(eg, source: bytes, source_name: str, config: dict | None, overrides: dict) -> dict:
    inp = next(t for t in eg.tensors if t.kind == spec.KIND_INPUT)
    meta = dict(producer=f"aprt_tools {__version__}",
                source_sha256=hashlib.sha256(source).digest(),
                source_name=source_name,
                input_shape=list(inp.shape))
    meta.update(_infer_architecture(eg))
    if config:
        modality = (spec.MODALITY_LIDAR_POINTS if config.get("points") else
                    spec.MODALITY_IMAGE if config.get("in_channels", 3) == 3 else
                    spec.MODALITY_LIDAR_BEV)
        meta.update(modality=modality,
                    norm_mean=list(config["mean"]), norm_std=list(config["std"]),
                    pose_min=list(config["pose_min"]), pose_max=list(config["pose_max"]),
                    backbone=config["backbone"], dim_feedforward=config["dim_feedforward"],
                    config_json=json.dumps(config, sort_keys=True))
        for k in ("d_model", "nheads", "enc_layers", "dec_layers"):
            want = {"d_model": config["hidden_dim"], "nheads": config["nheads"],
                    "enc_layers": config["enc_layers"], "dec_layers": config["dec_layers"]}[k]
            if meta[k] != want:
                raise UnsupportedOnnx(f"the graph has {k} = {meta[k]}, the configuration says "
                                      f"{want}: wrong configuration for this ONNX file?")
        if config.get("bev"):
            from ..lidar_bev import bev_meta

            meta["bev"] = bev_meta(config["bev"])
        if config.get("points"):
            from ..lidar_points import points_meta

            meta["points"] = points_meta(config["points"])
        if "val_error" in config.get("extra", {}):
            meta["val_error"] = list(config["extra"]["val_error"])
    meta.setdefault("modality", spec.MODALITY_IMAGE)
    meta.setdefault("resize_policy", spec.RESIZE_SHORTER_THEN_CENTER_CROP)
    meta.update({k: v for k, v in overrides.items() if v is not None})
    for k in ("norm_mean", "norm_std", "pose_min", "pose_max"):
        if k not in meta:
            raise UnsupportedOnnx(f"metadata {k!r} is unknown for this ONNX file: pass a "
                                  "configuration (--config) or the value on the command line")
    c = inp.shape[-1]
    if len(meta["norm_mean"]) != c or len(meta["norm_std"]) != c:
        raise UnsupportedOnnx(f"normalisation has {len(meta['norm_mean'])} values for {c} channels")
    if any(s <= 0 for s in meta["norm_std"]):
        raise UnsupportedOnnx("normalisation std must be positive")
    if any(lo >= hi for lo, hi in zip(meta["pose_min"], meta["pose_max"])) or \
            len(meta["pose_min"]) != 3 or len(meta["pose_max"]) != 3:
        raise UnsupportedOnnx("pose bounds must be three (min, max) pairs with min < max")
    return meta


def convert(onnx_bytes: bytes, *, source_name: str = "model.onnx", config: dict | None = None,
            overrides: dict | None = None, seed: int = 0, tolerance: float = 1e-4):
    """Returns (model_bin bytes, Report). Raises UnsupportedOnnx with the node named."""
    try:
        model = onnx.load_from_string(onnx_bytes)
    except Exception as e:  # protobuf decode errors
        raise UnsupportedOnnx(f"not an ONNX model: {e}") from None
    opset = next((o.version for o in model.opset_import if o.domain in ("", "ai.onnx")), None)
    if opset is None or not MIN_OPSET <= opset <= MAX_OPSET:
        raise UnsupportedOnnx(f"ONNX opset {opset}: supported are {MIN_OPSET}..{MAX_OPSET}")
    inits = {t.name for t in model.graph.initializer}
    inputs = [i for i in model.graph.input if i.name not in inits]
    if len(inputs) != 1:
        raise UnsupportedOnnx(f"the graph has {len(inputs)} inputs; expected one image")
    dims = [d.dim_value if d.HasField("dim_value") else None
            for d in inputs[0].type.tensor_type.shape.dim]
    if len(dims) != 4 or any(d is None or d <= 0 for d in dims) or dims[0] != 1:
        raise UnsupportedOnnx(f"input {inputs[0].name!r} has shape {dims}; export with a static "
                              "(1, C, H, W) shape")
    rng = np.random.default_rng(seed)
    probe = rng.standard_normal(dims).astype(np.float32)

    g = fold(model, probe)
    rewrite(g)
    eg, views = lower(g)

    inp = next(t for t in eg.tensors if t.kind == spec.KIND_INPUT)
    feed = {inp: probe.transpose(0, 2, 3, 1)}
    vals = engine_ir.run(eg, feed)
    report = Report()
    for name, (t, idx) in views.items():
        if id(t) in vals:
            report.max_rel_error_lowered = max(report.max_rel_error_lowered,
                                               _rel(g.values[name], vals[id(t)].reshape(-1)[idx]))
    fuse(eg)
    vals = engine_ir.run(eg, feed)
    for name in g.output_names:
        t, idx = views[name]
        report.max_rel_error_output = max(report.max_rel_error_output,
                                          _rel(g.values[name], vals[id(t)].reshape(-1)[idx]))
    if report.max_rel_error_output > tolerance:
        raise UnsupportedOnnx(f"the converted graph deviates from ONNX by "
                              f"{report.max_rel_error_output:.2e} (> {tolerance:.0e}) on a probe "
                              "input: a pattern was matched wrongly; please report this model")
    meta = build_meta(eg, onnx_bytes, source_name, config, overrides or {})
    blob = serialise(eg, meta)
    for op in eg.ops:
        name = spec.OP_NAMES[op.code]
        report.ops[name] = report.ops.get(name, 0) + 1
    report.tensors = len(eg.tensors)
    report.weight_bytes = sum(t.data.nbytes for t in eg.tensors if t.kind == spec.KIND_CONST)
    report.meta = meta
    return blob, report
