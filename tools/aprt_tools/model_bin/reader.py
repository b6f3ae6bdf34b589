"""Reads a model_bin file back into an engine graph and its metadata, so tools
(the int8 quantiser) can work on a converted model without its ONNX source.

Checks what the tools rely on (magic, version, checksums, table sizes); the
runtime's loader remains the full validator (FORMAT.md).
"""

from __future__ import annotations

import struct
import zlib

import numpy as np

from ..convert.engine_ir import EngineGraph, Op, Tensor
from . import spec


class ModelBinError(ValueError):
    pass


_NUMPY = {spec.DTYPE_F32: "<f4", spec.DTYPE_I8: "i1", spec.DTYPE_I32: "<i4", spec.DTYPE_U8: "u1"}


def _f(bits: int) -> float:
    return struct.unpack("<f", struct.pack("<i", bits))[0]


def _params(code: int, raw: list) -> dict:
    """The inverse of writer._op_params."""
    if code in (spec.OP_CONV2D, spec.OP_DWCONV2D):
        return dict(stride=(raw[0], raw[1]), pads=tuple(raw[2:6]), act=raw[6])
    if code == spec.OP_LINEAR:
        return dict(act=raw[0])  # int8 LINEAR's input quantisation is added by the caller
    if code == spec.OP_LAYERNORM:
        return dict(eps=_f(raw[0]))
    if code == spec.OP_ATTENTION:
        p = dict(heads=raw[0], scale=_f(raw[1]))
        if raw[2]:
            p["scores"] = raw[2]
        return p
    if code == spec.OP_CROSS_ATTENTION_1Q:
        return dict(heads=raw[0], scale=_f(raw[1]))
    if code == spec.OP_ACTIVATION:
        return dict(act=raw[0])
    if code == spec.OP_BALL_GROUP:
        return dict(radius=_f(raw[0]))
    if code == spec.OP_GRID_TOKENS:
        return dict(groups=raw[0], gx=raw[1], gy=raw[2])
    return {}


def _meta(blob: bytes) -> dict:
    out, pos = {}, 0
    while pos + 8 <= len(blob):
        key, typ, n = struct.unpack_from("<HHI", blob, pos)
        v = blob[pos + 8:pos + 8 + n]
        pos += 8 + (n + 3) // 4 * 4
        if key not in spec.META_KEYS:
            continue
        name = spec.META_KEYS[key][1]
        if typ == spec.T_U32:
            out[name] = list(struct.unpack(f"<{n // 4}I", v))
        elif typ == spec.T_F32:
            out[name] = list(struct.unpack(f"<{n // 4}f", v))
        elif typ == spec.T_STR:
            out[name] = v.decode("utf-8")
        else:
            out[name] = bytes(v)
    for k in ("modality", "resize_policy", "d_model", "nheads", "enc_layers", "dec_layers",
              "dim_feedforward", "ensemble"):
        if k in out and len(out[k]) == 1:
            out[k] = out[k][0]
    return out


def read(data: bytes):
    """model_bin bytes -> (EngineGraph, metadata dict)."""
    if len(data) < spec.HEADER_BYTES or data[:8] != spec.MAGIC:
        raise ModelBinError("not an aprt model file (bad magic)")
    major, minor, _, file_bytes, count = struct.unpack_from("<HHIQI", data, 8)
    if major != spec.VERSION_MAJOR:
        raise ModelBinError(f"unsupported version {major}.{minor}")
    if file_bytes != len(data):
        raise ModelBinError(f"header says {file_bytes} bytes, file has {len(data)} "
                            "(file truncated?)")
    sections = {}
    for i in range(count):
        tag, _, off, size, crc, _ = struct.unpack_from("<IIQQII", data,
                                                       spec.HEADER_BYTES + 32 * i)
        blob = data[off:off + size]
        if len(blob) != size or zlib.crc32(blob) != crc:
            raise ModelBinError(f"section {struct.pack('<I', tag).decode(errors='replace')} "
                                "checksum mismatch (file corrupted or truncated?)")
        sections[tag] = blob
    for tag in (spec.SEC_META, spec.SEC_STRS, spec.SEC_TENS, spec.SEC_OPSQ, spec.SEC_WGHT):
        if tag not in sections:
            raise ModelBinError(f"section {struct.pack('<I', tag).decode()} missing")
    strs = sections[spec.SEC_STRS]

    def string(off: int) -> str:
        return strs[off:strs.index(b"\x00", off)].decode("utf-8")

    meta = _meta(sections[spec.SEC_META])
    wght = sections[spec.SEC_WGHT]
    tens = sections[spec.SEC_TENS]
    n_t = struct.unpack_from("<I", tens, 0)[0]
    g = EngineGraph()
    qscale_of = []
    for i in range(n_t):
        (name, dtype, rank, kind, _, d0, d1, d2, d3, off, size, scale, zero,
         qs) = struct.unpack_from("<IBBBB4IQQfii", tens, 16 + spec.TENSOR_ENTRY_BYTES * i)
        shape = tuple((d0, d1, d2, d3)[:rank])
        t = Tensor(string(name), shape, kind, dtype=dtype, scale=scale, zero_point=zero)
        if kind == spec.KIND_CONST:
            t.data = np.frombuffer(wght, _NUMPY[dtype], int(np.prod(shape)), off).reshape(shape)
            t.data = t.data.copy()
        g.add(t)
        qscale_of.append(qs)
    for t, qs in zip(g.tensors, qscale_of):
        t.qscale = g.tensors[qs] if qs >= 0 else None
    ops = sections[spec.SEC_OPSQ]
    n_o = struct.unpack_from("<I", ops, 0)[0]
    for i in range(n_o):
        rec = struct.unpack_from("<HBBI8i2i12i", ops, 16 + spec.OP_ENTRY_BYTES * i)
        code, n_in, n_out, name = rec[:4]
        ins = [g.tensors[j] if j >= 0 else None for j in rec[4:4 + n_in]]
        outs = [g.tensors[j] for j in rec[12:12 + n_out]]
        raw = list(rec[14:26])
        params = _params(code, raw)
        if code == spec.OP_LINEAR and ins[1].dtype == spec.DTYPE_I8:
            params.update(input_scale=_f(raw[1]), input_zero=raw[2])
        if code == spec.OP_DWCONV2D and ins[1].dtype == spec.DTYPE_I8:
            params.update(input_scale=_f(raw[7]), input_zero=raw[8])
        g.ops.append(Op(code, string(name), ins, outs, params))
    return g, meta
