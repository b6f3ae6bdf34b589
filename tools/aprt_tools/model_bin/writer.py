"""Serialises an engine graph and its metadata to a model_bin file (FORMAT.md)."""

from __future__ import annotations

import struct
import zlib

import numpy as np

from . import spec


def _align(n: int, a: int = spec.ALIGN) -> int:
    return (n + a - 1) // a * a


class Strings:
    def __init__(self):
        self.blob = bytearray(b"\x00")  # offset 0 is the empty string
        self.index = {"": 0}

    def add(self, s: str) -> int:
        if s not in self.index:
            self.index[s] = len(self.blob)
            self.blob += s.encode("utf-8") + b"\x00"
        return self.index[s]


def _meta_record(key: int, typ: int, value, strings: Strings) -> bytes:
    if typ == spec.T_U32:
        payload = struct.pack(f"<{len(value)}I", *[int(v) for v in value])
    elif typ == spec.T_F32:
        payload = struct.pack(f"<{len(value)}f", *[float(v) for v in value])
    elif typ == spec.T_STR:
        payload = value.encode("utf-8")
    elif typ == spec.T_BYTES:
        payload = bytes(value)
    else:
        raise ValueError(typ)
    rec = struct.pack("<HHI", key, typ, len(payload)) + payload
    return rec + b"\x00" * (_align(len(rec), 4) - len(rec))


def encode_meta(meta: dict, strings: Strings) -> bytes:
    out = bytearray()
    for name in meta:
        if name not in spec.META_BY_NAME:
            raise ValueError(f"unknown metadata field {name!r}")
    for missing in spec.META_REQUIRED:
        if missing not in meta:
            raise ValueError(f"metadata field {missing!r} is required")
    for name, value in meta.items():
        key, typ = spec.META_BY_NAME[name]
        if typ in (spec.T_U32, spec.T_F32) and np.ndim(value) == 0:
            value = [value]
        out += _meta_record(key, typ, value, strings)
    return bytes(out)


_NUMPY_DTYPE = {spec.DTYPE_F32: "<f4", spec.DTYPE_I8: "i1", spec.DTYPE_I32: "<i4",
                spec.DTYPE_U8: "u1"}


def _op_params(op) -> list:
    p = op.params
    f = lambda v: struct.unpack("<i", struct.pack("<f", float(v)))[0]
    c = op.code
    if c in (spec.OP_CONV2D, spec.OP_DWCONV2D):
        conv = [p["stride"][0], p["stride"][1], *p["pads"], p.get("act", 0)]
        if "input_scale" in p:  # int8 depthwise weights (FORMAT.md)
            conv += [f(p["input_scale"]), int(p["input_zero"])]
        return conv
    if c == spec.OP_LINEAR:
        if "input_scale" in p:  # int8 weights: the input's quantisation (FORMAT.md)
            return [p.get("act", 0), f(p["input_scale"]), int(p["input_zero"])]
        return [p.get("act", 0)]
    if c == spec.OP_LAYERNORM:
        return [f(p["eps"])]
    if c == spec.OP_ATTENTION:  # scores: 0 fp32, 1 int8 (FORMAT.md)
        return [p["heads"], f(p["scale"]), int(p.get("scores", 0))]
    if c == spec.OP_CROSS_ATTENTION_1Q:
        return [p["heads"], f(p["scale"])]
    if c == spec.OP_ACTIVATION:
        return [p["act"]]
    if c == spec.OP_BALL_GROUP:
        return [f(p["radius"])]
    if c == spec.OP_GRID_TOKENS:
        return [p["groups"], p["gx"], p["gy"]]
    return []


def serialise(eg, meta: dict) -> bytes:
    """The whole file as bytes. `eg` is an EngineGraph (see convert/engine_ir.py)."""
    strings = Strings()
    meta_blob = encode_meta(meta, strings)

    index = {id(t): i for i, t in enumerate(eg.tensors)}
    weights = bytearray()
    tens = bytearray(struct.pack("<IIII", len(eg.tensors), spec.TENSOR_ENTRY_BYTES, 0, 0))
    for t in eg.tensors:
        if len(t.shape) < 1 or len(t.shape) > spec.MAX_RANK:
            raise ValueError(f"tensor {t.name}: rank {len(t.shape)}")
        dims = list(t.shape) + [0] * (spec.MAX_RANK - len(t.shape))
        off = size = 0
        if t.kind == spec.KIND_CONST:
            data = np.ascontiguousarray(t.data, dtype=_NUMPY_DTYPE[t.dtype]).tobytes()
            off = _align(len(weights))
            weights += b"\x00" * (off - len(weights)) + data
            size = len(data)
        tens += struct.pack("<IBBBB4IQQfii12x", strings.add(t.name), t.dtype, len(t.shape),
                            t.kind, 0, *dims, off, size, float(t.scale), int(t.zero_point),
                            -1 if t.qscale is None else index[id(t.qscale)])
    ops = bytearray(struct.pack("<IIII", len(eg.ops), spec.OP_ENTRY_BYTES, 0, 0))
    for op in eg.ops:
        ins = [index[id(t)] if t is not None else -1 for t in op.inputs]
        outs = [index[id(t)] for t in op.outputs]
        # Trailing absent inputs are not counted.
        while ins and ins[-1] == -1:
            ins.pop()
        params = _op_params(op)
        if len(ins) > spec.MAX_OP_INPUTS or len(outs) > spec.MAX_OP_OUTPUTS or \
                len(params) > spec.MAX_OP_PARAMS:
            raise ValueError(f"op {op}: too many inputs/outputs/params")
        ops += struct.pack("<HBBI8i2i12i", op.code, len(ins), len(outs), strings.add(op.name),
                           *(ins + [-1] * (8 - len(ins))), *(outs + [-1] * (2 - len(outs))),
                           *(params + [0] * (12 - len(params))))
    sections = [(spec.SEC_META, meta_blob), (spec.SEC_STRS, bytes(strings.blob)),
                (spec.SEC_TENS, bytes(tens)), (spec.SEC_OPSQ, bytes(ops)),
                (spec.SEC_WGHT, bytes(weights))]
    table_end = spec.HEADER_BYTES + spec.SECTION_ENTRY_BYTES * len(sections)
    offset = _align(table_end)
    layout = []
    for tag, blob in sections:
        layout.append((tag, offset, blob))
        offset = _align(offset + len(blob))
    file_bytes = layout[-1][1] + len(layout[-1][2])
    table = b"".join(struct.pack("<IIQQII", tag, 0, off, len(blob), zlib.crc32(blob), 0)
                     for tag, off, blob in layout)
    header = bytearray(struct.pack("<8sHHIQIIII24x", spec.MAGIC, spec.VERSION_MAJOR,
                                   spec.VERSION_MINOR, spec.HEADER_BYTES, file_bytes,
                                   len(sections), spec.ENDIAN_MARK, 0, 0))
    crc = zlib.crc32(bytes(header) + table)
    struct.pack_into("<I", header, 36, crc)
    out = bytearray(file_bytes)
    out[:spec.HEADER_BYTES] = header
    out[spec.HEADER_BYTES:table_end] = table
    for _, off, blob in layout:
        out[off:off + len(blob)] = blob
    return bytes(out)
