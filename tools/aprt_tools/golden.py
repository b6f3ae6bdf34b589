"""Golden data: a model with varied weights, its ONNX, inputs and PyTorch outputs.

Inputs are NCHW float32, already normalised (what the network sees), written
raw little-endian; outputs are the 7 pose values. A manifest records the
configuration and how much the outputs vary across the inputs, which must be
far more than any tolerance a test uses.
"""

from __future__ import annotations

import json
import os

import numpy as np
import torch

from .export import export_onnx
from .model.apr_transformer import AprConfig, AprTransformer
from .model.weights import sample_inputs, vary

MIN_SPREAD = 0.05  # std across inputs / mean magnitude, per output, at least


def _write_cases(cfg: AprConfig, out_dir: str, forward, seed: int, count: int, **extra) -> dict:
    """`count` inputs (the first random, the rest sample-like; all sampled
    scans for points models) and `forward`'s outputs for them as in_K.f32 /
    out_K.f32, and golden.json (with `extra`); refuses outputs that barely vary."""
    gen = torch.Generator().manual_seed(seed + 1000)
    if cfg.points:  # scans: random points would make FPS and the ball query meaningless
        inputs = [sample_inputs(1, cfg, gen) for _ in range(count)]
    else:
        inputs = [torch.randn(*cfg.input_shape(), generator=gen)]
        inputs += [sample_inputs(1, cfg, gen) for _ in range(count - 1)]
    outs = []
    with torch.no_grad():
        for k, x in enumerate(inputs):
            y = forward(x)
            x.numpy().astype("<f4").tofile(os.path.join(out_dir, f"in_{k}.f32"))
            y.numpy().astype("<f4").tofile(os.path.join(out_dir, f"out_{k}.f32"))
            outs.append(y.numpy().reshape(-1))
    outs = np.stack(outs)
    spread = float((outs.std(axis=0) / (np.abs(outs).mean(axis=0) + 1e-9)).min())
    manifest = dict(config=json.loads(cfg.to_json()), seed=seed, **extra, count=count,
                    input_shape=list(cfg.input_shape()),
                    min_relative_spread=spread, outputs=outs.tolist())
    with open(os.path.join(out_dir, "golden.json"), "w") as f:
        json.dump(manifest, f, indent=1)
    if count > 1 and spread < MIN_SPREAD:
        raise RuntimeError(f"outputs barely vary across inputs (relative spread {spread:.3f} < "
                           f"{MIN_SPREAD}): the golden data would prove nothing")
    return manifest


def make_golden(cfg: AprConfig, out_dir: str, *, seed: int = 1, opset: int = 13,
                count: int = 3, portable: bool = False) -> dict:
    """portable: also write model_portable.onnx, the points model's PointNet++
    in standard ONNX ops (for ONNX Runtime; export.py)."""
    os.makedirs(out_dir, exist_ok=True)
    torch.manual_seed(seed)
    model = vary(AprTransformer(cfg), seed)
    onnx_bytes = export_onnx(model, opset)
    with open(os.path.join(out_dir, "model.onnx"), "wb") as f:
        f.write(onnx_bytes)
    if portable and cfg.points:
        with open(os.path.join(out_dir, "model_portable.onnx"), "wb") as f:
            f.write(export_onnx(model, opset, portable=True))
    with open(os.path.join(out_dir, "model.json"), "w") as f:
        f.write(cfg.to_json())
    return _write_cases(cfg, out_dir, model, seed, count, opset=opset)


def make_golden_int8(src_dir: str, out_dir: str, method: str = "percentile",
                     backbone: bool = False, int8_attention: bool = False,
                     bf16_attention: bool = False) -> dict:
    """Golden data for the int8 path: quantises `src_dir`/model.aprt (calibrated
    on the golden inputs) and writes the int8 graph's outputs as computed by the
    converter's statement of the runtime's int8 arithmetic (engine_ir), next to
    the same inputs."""
    import glob
    import shutil

    from .convert import engine_ir
    from .convert.quantize import quantize_model
    from .model_bin import spec
    from .model_bin.reader import read

    os.makedirs(out_dir, exist_ok=True)
    fp32 = open(os.path.join(src_dir, "model.aprt"), "rb").read()
    _, meta = read(fp32)
    _, h, w, c = meta["input_shape"]
    names = sorted(glob.glob(os.path.join(src_dir, "in_*.f32")))
    xs = [np.fromfile(n, "<f4").reshape(1, c, h, w).transpose(0, 2, 3, 1) for n in names]
    calib = os.path.join(out_dir, "calibration.npy")
    np.save(calib, np.concatenate(xs).astype(np.float32))
    blob, report = quantize_model(fp32, calib, method=method, frames=len(xs), backbone=backbone,
                                  int8_attention=int8_attention, bf16_attention=bf16_attention)
    with open(os.path.join(out_dir, "model.aprt"), "wb") as f:
        f.write(blob)
    eg, _ = read(blob)
    inp = next(t for t in eg.tensors if t.kind == spec.KIND_INPUT)
    out = next(t for t in eg.tensors if t.kind == spec.KIND_OUTPUT)
    for k, (name, x) in enumerate(zip(names, xs)):
        shutil.copyfile(name, os.path.join(out_dir, f"in_{k}.f32"))
        y = engine_ir.run(eg, {inp: x})[id(out)]
        np.asarray(y, "<f4").tofile(os.path.join(out_dir, f"out_{k}.f32"))
    return dict(ops=len(report.ops), frames=report.frames)


def make_golden_ensemble(cfg: AprConfig, out_dir: str, *, members: int = 2, seed: int = 1,
                         count: int = 3) -> dict:
    """Golden data for an ensemble file (ensemble.py): `members` varied-weight
    networks with confidence heads, each with its own position bounds (as
    networks trained on different drives have), converted, laid into one
    graph; the expected outputs are the PyTorch members' 13 outputs side by
    side, each mapped to the ensemble's bounds (ensemble.rebound)."""
    from .convert.convert import convert
    from .ensemble import build, rebound, union_bounds
    from .model_bin.writer import serialise

    os.makedirs(out_dir, exist_ok=True)
    cfg.uncertainty = True
    models, blobs, bounds = [], [], []
    for i in range(members):
        config = json.loads(cfg.to_json())
        lo, hi = np.asarray(config["pose_min"]), np.asarray(config["pose_max"])
        lo, hi = lo + 0.02 * i * (hi - lo), hi - 0.03 * i * (hi - lo)  # within member 0's
        config["pose_min"], config["pose_max"] = lo.tolist(), hi.tolist()
        torch.manual_seed(seed + i)
        model = vary(AprTransformer(cfg), seed + i).eval()
        blob, _ = convert(export_onnx(model, 13), config=config)
        models.append(model)
        blobs.append(blob)
        bounds.append(dict(pose_min=lo.tolist(), pose_max=hi.tolist()))
    graph, meta = build(blobs, [f"member {i}" for i in range(members)])
    meta["uncertainty"] = [1.0, 1.0]  # the raw outputs are compared; the scales are not used
    with open(os.path.join(out_dir, "model.aprt"), "wb") as f:
        f.write(serialise(graph, meta))
    lo_e, hi_e = union_bounds(bounds)
    maps = [rebound(np.asarray(b["pose_min"]), np.asarray(b["pose_max"]), lo_e, hi_e)
            for b in bounds]
    maps = [(torch.tensor(w, dtype=torch.float32), torch.tensor(b, dtype=torch.float32))
            for w, b in maps]
    def expected(x):
        # The members' outputs side by side (FORMAT.md 1.5).
        return torch.cat([m(x) @ w.T + b for m, (w, b) in zip(models, maps)], dim=1)

    manifest = _write_cases(cfg, out_dir, expected, seed, count, members=members)
    return dict(report=f"{members} members, {len(graph.ops)} ops",
                min_relative_spread=manifest["min_relative_spread"])
