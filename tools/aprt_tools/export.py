"""Export the reference model to ONNX with a static (1, C, S, S) input."""

from __future__ import annotations

import io

import torch

from .model.apr_transformer import AprTransformer

SUPPORTED_OPSETS = (13, 17)


def export_onnx(model: AprTransformer, opset: int = 13) -> bytes:
    if opset not in SUPPORTED_OPSETS:
        raise ValueError(f"opset {opset}: choose one of {SUPPORTED_OPSETS}")
    cfg = model.cfg
    model.eval()
    dummy = torch.zeros(1, cfg.in_channels, cfg.image_size, cfg.image_size)
    buf = io.BytesIO()
    with torch.no_grad():
        torch.onnx.export(model, dummy, buf, opset_version=opset, input_names=["image"],
                          output_names=["pose"], do_constant_folding=True,
                          training=torch.onnx.TrainingMode.EVAL)
    return buf.getvalue()
