"""A converted model file back into the reference network (fp32 image and BEV
models), so training can continue from a shipped model_bin without its
PyTorch checkpoint (`train --init MODEL.aprt`).

The converter (convert/) folds what the engine does not need, so the way
back chooses, where information was folded away, parameters that compute
the same function:

- BatchNorm was folded into the convolution before it: the convolution gets
  the folded weights, and each BatchNorm is re-estimated on the frames given
  (`frames`): running mean and variance are those of its input, and its
  affine parameters undo them, so the network in eval mode computes exactly
  the file's function and in training mode nearly it.
- The decoder's first layer acts on a constant (tgt = 0): its self-attention
  is folded into the cross-attention's query and output bias; the way back
  sets that self-attention's output to zero and puts the folded query in the
  query projection's bias.
- With one query, later self-attentions return their value row: their query
  and key projections never mattered and keep a fresh initialisation.
- The learned position tables are read back from the positions the encoder
  adds (rows and columns the feature maps reach; the rest keep a fresh
  initialisation).

`check()` runs the file's graph (convert/engine_ir.py) and the network on
the same inputs: the caller refuses a mismatch.
"""

from __future__ import annotations

import json
import re

import numpy as np
import torch
from torch import nn

from ..convert import engine_ir
from ..model.apr_transformer import AprConfig, AprTransformer
from . import reader, spec


class ToTorchError(ValueError):
    pass


def _t(a) -> torch.Tensor:
    return torch.from_numpy(np.ascontiguousarray(a, np.float32))


def config_of(meta: dict) -> AprConfig:
    if "config_json" not in meta:
        raise ToTorchError("the file carries no configuration (config_json): it was not "
                           "written by aprt_tools convert from the reference model")
    cfg = AprConfig.from_json(meta["config_json"])
    cfg.pose_min = tuple(float(v) for v in meta["pose_min"])
    cfg.pose_max = tuple(float(v) for v in meta["pose_max"])
    cfg.dropout = 0.0
    return cfg


class _Mapper:
    def __init__(self, model: AprTransformer, graph):
        self.model = model
        self.graph = graph
        self.state = {k: v.clone() for k, v in model.state_dict().items()}
        self.seen_bn = []  # BatchNorm modules whose statistics must be re-estimated
        self.pos_tables = {}  # (rows, cols) -> NHWC positions [h, w, d]

    def set(self, key: str, value):
        if key not in self.state:
            raise ToTorchError(f"no parameter {key!r} in the reference network")
        value = _t(value) if not isinstance(value, torch.Tensor) else value
        if tuple(self.state[key].shape) != tuple(value.shape):
            raise ToTorchError(f"{key}: file has shape {tuple(value.shape)}, network "
                               f"{tuple(self.state[key].shape)}")
        self.state[key] = value.clone()

    # -- the trunk ------------------------------------------------------------
    def conv(self, op, module: str, bn: str | None):
        w, b = op.inputs[1].data, op.inputs[2].data
        if op.code == spec.OP_LINEAR:
            w = w[:, :, None, None]
        elif op.code == spec.OP_DWCONV2D:
            w = w.transpose(2, 0, 1)[:, None]
        else:
            w = w.transpose(0, 3, 1, 2)
        self.set(module + ".weight", w)
        if bn is None:
            self.set(module + ".bias", b)
            return
        if module + ".bias" in self.state:
            self.set(module + ".bias", np.zeros_like(b))
        # identity BatchNorm carrying the folded bias, until re-estimated
        self.set(bn + ".weight", np.ones_like(b))
        self.set(bn + ".bias", b)
        self.set(bn + ".running_mean", np.zeros_like(b))
        eps = dict(self.model.named_modules())[bn].eps
        self.set(bn + ".running_var", np.full_like(b, 1.0 - eps))  # exactly the identity
        self.seen_bn.append(bn)

    def trunk_op(self, op, body: str) -> bool:
        name = op.name
        if name == "/_conv_stem/Conv":
            self.conv(op, body + "._conv_stem", body + "._bn0")
            return True
        m = re.fullmatch(r"/_blocks\.(\d+)/_(expand|depthwise|project)_conv/Conv", name)
        if m:
            blk = f"{body}._blocks.{m.group(1)}"
            bn = {"expand": "_bn0", "depthwise": "_bn1", "project": "_bn2"}[m.group(2)]
            self.conv(op, f"{blk}._{m.group(2)}_conv", f"{blk}.{bn}")
            return True
        m = re.fullmatch(r"/_blocks\.(\d+)", name)
        if m and op.code == spec.OP_SQUEEZE_EXCITE:
            blk = f"{body}._blocks.{m.group(1)}"
            w1, b1, w2, b2 = (t.data for t in op.inputs[1:5])
            self.set(blk + "._se_reduce.weight", w1[:, :, None, None])
            self.set(blk + "._se_reduce.bias", b1)
            self.set(blk + "._se_expand.weight", w2[:, :, None, None])
            self.set(blk + "._se_expand.bias", b2)
            return True
        m = re.fullmatch(r"/input_proj_(t|rot)/Conv", name)
        if m:
            self.conv(op, f"input_proj_{m.group(1)}", None)
            return True
        return False

    # -- the transformers -----------------------------------------------------
    def linear(self, op, key: str):
        self.set(key + ".weight", op.inputs[1].data)
        self.set(key + ".bias", op.inputs[2].data)

    def in_proj(self, key: str, part: int, w, b):
        """Part 0/1/2 (q/k/v) of a MultiheadAttention's packed input projection."""
        d = w.shape[0]
        W, B = self.state[key + ".in_proj_weight"].clone(), self.state[key + ".in_proj_bias"].clone()
        W[part * d:(part + 1) * d] = _t(w)
        B[part * d:(part + 1) * d] = _t(b)
        self.state[key + ".in_proj_weight"], self.state[key + ".in_proj_bias"] = W, B

    def branch(self, ops: list, tr: str):
        cfg = self.model.cfg
        producer = {}
        for op in ops:
            producer[id(op.outputs[0])] = op
        enc = f"transformer_{tr}.encoder"
        dec = f"transformer_{tr}.decoder"
        query_pos = None
        cross_q0 = None
        d_model = cfg.hidden_dim
        for op in ops:
            name = op.name
            m = re.fullmatch(rf"/transformer_{tr}/encoder/layers\.(\d+)/(.*)", name)
            if m:
                lay, rest = f"{enc}.layers.{m.group(1)}", m.group(2)
                if op.code == spec.OP_LAYERNORM:
                    self.linear(op, f"{lay}.{rest}")
                elif op.code == spec.OP_ADD:
                    c = [t for t in op.inputs if t.kind == spec.KIND_CONST]
                    if len(c) != 1:
                        raise ToTorchError(f"{name}: expected the positions as a constant")
                    pos = c[0].data
                    self.pos_tables[pos.shape] = pos
                elif op.code == spec.OP_ATTENTION:
                    for part, t in enumerate(op.inputs[:3]):
                        lin = producer.get(id(t))
                        if lin is None or lin.code != spec.OP_LINEAR:
                            raise ToTorchError(f"{name}: its input {part} is not a projection")
                        self.in_proj(f"{lay}.self_attn", part, lin.inputs[1].data,
                                     lin.inputs[2].data)
                elif rest == "self_attn/Gemm":
                    self.linear(op, f"{lay}.self_attn.out_proj")
                elif rest in ("linear1", "linear2"):
                    self.linear(op, f"{lay}.{rest}")
                elif op.code == spec.OP_LINEAR and rest == "self_attn":
                    pass  # a projection, taken with its ATTENTION
                else:
                    raise ToTorchError(f"unexpected op {op} in an encoder layer")
                continue
            if name == f"/transformer_{tr}/encoder/norm":
                self.linear(op, f"{enc}.norm")
                continue
            if name == f"/transformer_{tr}/decoder/norm":
                self.linear(op, f"{dec}.norm")
                continue
            m = re.fullmatch(rf"/transformer_{tr}/decoder/layers\.(\d+)/(.*)", name)
            if not m:
                raise ToTorchError(f"unexpected op {op} in the {tr} branch")
            k, rest = int(m.group(1)), m.group(2)
            lay = f"{dec}.layers.{k}"
            if op.code == spec.OP_LAYERNORM or rest in ("linear1", "linear2"):
                self.linear(op, f"{lay}.{rest}")
            elif rest == "self_attn" and op.code == spec.OP_LINEAR:
                self.in_proj(f"{lay}.self_attn", 2, op.inputs[1].data, op.inputs[2].data)
            elif rest == "self_attn/Gemm":
                self.linear(op, f"{lay}.self_attn.out_proj")
            elif op.code == spec.OP_ADD:  # norm2(tgt) + query_pos
                c = [t for t in op.inputs if t.kind == spec.KIND_CONST]
                if len(c) != 1:
                    raise ToTorchError(f"{name}: expected the query positions as a constant")
                query_pos = c[0].data.reshape(-1)
            elif rest == "multihead_attn" and op.code == spec.OP_LINEAR:
                self.in_proj(f"{lay}.multihead_attn", 0, op.inputs[1].data, op.inputs[2].data)
            elif op.code == spec.OP_CROSS_ATTENTION_1Q:
                q, _, _, wk, bk, wv, bv = op.inputs
                self.in_proj(f"{lay}.multihead_attn", 1, wk.data, bk.data)
                self.in_proj(f"{lay}.multihead_attn", 2, wv.data, bv.data)
                if q.kind == spec.KIND_CONST:
                    if k != 0:
                        raise ToTorchError(f"{name}: a constant query after the first layer")
                    # ONNX folded the attention's 1/sqrt(head width) into the
                    # constant query (its op says scale 1): take it out again.
                    head_scale = (d_model // cfg.nheads) ** -0.5
                    cross_q0 = q.data.reshape(-1) * op.params["scale"] / head_scale
            elif rest == "multihead_attn/Gemm":
                self.linear(op, f"{lay}.multihead_attn.out_proj")
            else:
                raise ToTorchError(f"unexpected op {op} in a decoder layer")
        # The first decoder layer on tgt = 0: its self-attention returns a
        # constant that the converter added into the cross-attention's output
        # bias; zero it here (the bias read above holds it) and give the
        # cross-attention its folded query through the projection's bias.
        d = cfg.hidden_dim
        lay0 = f"{dec}.layers.0"
        self.state[f"{lay0}.self_attn.out_proj.weight"] = torch.zeros(d, d)
        self.state[f"{lay0}.self_attn.out_proj.bias"] = torch.zeros(d)
        self.state[f"{lay0}.norm2.weight"] = torch.ones(d)
        self.state[f"{lay0}.norm2.bias"] = torch.zeros(d)
        qp = np.zeros(d, np.float32) if query_pos is None else query_pos
        self.state[f"query_embed_{tr}.weight"] = _t(qp[None, :])
        if cross_q0 is None:
            raise ToTorchError(f"the {tr} branch's first cross-attention has no constant query")
        # q = (norm2(0) + query_pos) W_q^T + b_q = query_pos W_q^T + b_q
        W = self.state[f"{lay0}.multihead_attn.in_proj_weight"][:d]
        self.in_proj(f"{lay0}.multihead_attn", 0, W.numpy(),
                     cross_q0 - qp @ W.numpy().T)

    def positions(self):
        """Row and column tables from the largest grid of positions seen."""
        if not self.pos_tables:
            raise ToTorchError("no encoder positions found")
        shape = max(self.pos_tables, key=lambda s: int(np.prod(s)))
        pos = self.pos_tables[shape]
        _, h, w, d = pos.shape
        half = d // 2
        col = self.state["backbone.1.col_embed.weight"].clone()
        row = self.state["backbone.1.row_embed.weight"].clone()
        col[:w] = _t(pos[0, 0, :, :half])
        row[:h] = _t(pos[0, :, 0, half:])
        for s, p in self.pos_tables.items():  # every grid must agree with the tables
            _, hh, ww, _ = s
            want = torch.cat([col[:ww].unsqueeze(0).expand(hh, ww, half),
                              row[:hh].unsqueeze(1).expand(hh, ww, half)], dim=-1)
            if not torch.allclose(want, _t(p[0]), atol=1e-6):
                raise ToTorchError(f"positions of a {hh}x{ww} grid are not row/column tables")
        self.state["backbone.1.col_embed.weight"] = col
        self.state["backbone.1.row_embed.weight"] = row


def _estimate_batchnorm(model: AprTransformer, names: list, frames: torch.Tensor):
    """Each BatchNorm, identity so far, gets its input's statistics on `frames`
    (eval mode: the upstream layers already compute the file's function) and
    affine parameters that undo them."""
    modules = dict(model.named_modules())
    stats = {}

    def hook(name):
        def fn(_, inputs):
            x = inputs[0].detach().double()
            stats[name] = (x.mean(dim=(0, 2, 3)), x.var(dim=(0, 2, 3), unbiased=False))
        return fn

    handles = [modules[n].register_forward_pre_hook(hook(n)) for n in names]
    model.eval()
    with torch.no_grad():
        model(frames)
    for h in handles:
        h.remove()
    for n in names:
        bn = modules[n]
        mean, var = stats[n]
        running_var = (var - bn.eps).clamp(min=1e-6)
        bias = bn.bias.detach().double()  # the folded bias
        with torch.no_grad():  # (x - mean) / s * s + mean + bias = x + bias, s = sqrt(rv + eps)
            bn.running_mean.copy_(mean.float())
            bn.running_var.copy_(running_var.float())
            bn.weight.copy_(torch.sqrt(running_var + bn.eps).float())
            bn.bias.copy_((mean + bias).float())


def load(data: bytes, frames: torch.Tensor | None = None):
    """model_bin bytes -> (AprTransformer in eval mode, AprConfig). `frames`:
    normalised network inputs (N, C, S, S) to re-estimate BatchNorm on (a
    fixed random set is used without them; give real frames to continue
    training)."""
    graph, meta = reader.read(data)
    if any(t.dtype != spec.DTYPE_F32 for t in graph.tensors if t.kind == spec.KIND_CONST):
        raise ToTorchError("an int8 file: continue from its fp32 source instead")
    if "ensemble" in meta:
        raise ToTorchError(f"an ensemble of {meta['ensemble']} networks: continue from one of "
                           "its members instead")
    cfg = config_of(meta)
    if cfg.points:
        raise ToTorchError("raw-points models cannot be read back yet (image and BEV only)")
    model = AprTransformer(cfg)
    mapper = _Mapper(model, graph)
    body = "backbone.0.body"
    branches = {"t": [], "rot": []}
    for op in graph.ops:
        if mapper.trunk_op(op, body):
            continue
        m = re.match(r"/transformer_(t|rot)/", op.name)
        if m:
            branches[m.group(1)].append(op)
            continue
        m = re.fullmatch(r"/regressor_head_(t|rot)\.0/(fc_h|fc_o)/Gemm", op.name)
        if m:
            mapper.linear(op, f"regressor_head_{m.group(1)}.0.{m.group(2)}")
            continue
        m = re.fullmatch(r"/uncertainty_head_(t|rot)/(fc_h|fc_o)/Gemm", op.name)
        if m:
            mapper.linear(op, f"uncertainty_head_{m.group(1)}.{m.group(2)}")
            continue
        if op.code == spec.OP_CONCAT:
            continue
        raise ToTorchError(f"op {op} has no counterpart in the reference network")
    for tr, ops in branches.items():
        mapper.branch(ops, tr)
    mapper.positions()
    model.load_state_dict(mapper.state, strict=True)
    if frames is None:
        gen = torch.Generator().manual_seed(0)
        frames = torch.randn((8,) + cfg.input_shape()[1:], generator=gen)
    _estimate_batchnorm(model, mapper.seen_bn, frames)
    model.eval()
    return model, cfg


def check(data: bytes, model: AprTransformer, frames: torch.Tensor) -> float:
    """Largest relative difference between the file's graph and the network
    on `frames` (normalised inputs, N x C x S x S), per the golden tests'
    measure: |got - want| / max(|want|, 0.1 max|want|)."""
    graph, _ = reader.read(data)
    inp = next(t for t in graph.tensors if t.kind == spec.KIND_INPUT)
    out = next(t for t in graph.tensors if t.kind == spec.KIND_OUTPUT)
    worst = 0.0
    model.eval()
    with torch.no_grad():
        got = model(frames).double().numpy()
    for i in range(len(frames)):
        x = frames[i].permute(1, 2, 0).numpy()[None].astype(np.float64)  # NHWC
        want = engine_ir.run(graph, {inp: x}, keep_all=False)[id(out)].reshape(-1)
        denom = np.maximum(np.abs(want), 0.1 * np.abs(want).max())
        worst = max(worst, float((np.abs(got[i] - want) / denom).max()))
    return worst


def describe(meta: dict) -> str:
    cfg = json.loads(meta.get("config_json", "{}"))
    return (f"{cfg.get('backbone', '?')} {cfg.get('image_size', '?')} d_model "
            f"{cfg.get('hidden_dim', '?')} x {cfg.get('enc_layers', '?')} layers")
