"""Export the reference model to ONNX with a static input: (1, C, S, S) images,
(1, 6, N, 1) points.

A points model's PointNet++ operators become nodes of the custom domain
"aprt" (model/point_ops.py), which the converter maps onto engine ops;
`portable=True` spells them in standard ONNX instead, for ONNX Runtime (the
benchmark peer), at the price of a much larger graph."""

from __future__ import annotations

import io

import torch

from .model import point_ops
from .model.apr_transformer import AprTransformer

SUPPORTED_OPSETS = (13, 17)


def export_onnx(model: AprTransformer, opset: int = 13, portable: bool = False) -> bytes:
    if opset not in SUPPORTED_OPSETS:
        raise ValueError(f"opset {opset}: choose one of {SUPPORTED_OPSETS}")
    cfg = model.cfg
    model.eval()
    dummy = torch.zeros(cfg.input_shape())
    if cfg.points:  # FPS on all-zero points is degenerate but exports the same graph
        dummy = torch.randn(cfg.input_shape(), generator=torch.Generator().manual_seed(0))
    buf = io.BytesIO()
    extra = {}
    if cfg.points and not portable:
        extra["custom_opsets"] = {point_ops.DOMAIN: 1}
    with torch.no_grad():
        if portable:
            with point_ops.portable_export():
                torch.onnx.export(model, dummy, buf, opset_version=opset, input_names=["image"],
                                  output_names=["pose"], do_constant_folding=True,
                                  training=torch.onnx.TrainingMode.EVAL)
        else:
            torch.onnx.export(model, dummy, buf, opset_version=opset, input_names=["image"],
                              output_names=["pose"], do_constant_folding=True,
                              training=torch.onnx.TrainingMode.EVAL, **extra)
    return buf.getvalue()
