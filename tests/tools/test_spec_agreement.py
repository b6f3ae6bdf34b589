"""The Python writer's numbers equal the C++ reader's (runtime/engine/model_format.h)."""

import os
import re
import unittest

from aprt_tools.model_bin import spec

HEADER = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "runtime",
                      "engine", "model_format.h")


def enum_values(text, enum):
    body = re.search(r"enum class %s\s*:\s*\w+\s*\{(.*?)\};" % enum, text, re.S).group(1)
    return {m.group(1): int(m.group(2)) for m in re.finditer(r"(k\w+)\s*=\s*(\d+)", body)}


def const(text, name):
    m = re.search(r"%s\s*=\s*(0x[0-9a-fA-F]+|\d+)" % name, text)
    return int(m.group(1), 0)


class SpecAgreement(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.h = open(HEADER).read()

    def test_layout_constants(self):
        for py, cc in (("VERSION_MAJOR", "kVersionMajor"), ("VERSION_MINOR", "kVersionMinor"),
                       ("HEADER_BYTES", "kHeaderBytes"), ("SECTION_ENTRY_BYTES", "kSectionEntryBytes"),
                       ("TENSOR_ENTRY_BYTES", "kTensorEntryBytes"), ("OP_ENTRY_BYTES", "kOpEntryBytes"),
                       ("ALIGN", "kAlign"), ("ENDIAN_MARK", "kEndianMark"),
                       ("MAX_OP_INPUTS", "kMaxOpInputs"), ("MAX_OP_OUTPUTS", "kMaxOpOutputs"),
                       ("MAX_OP_PARAMS", "kMaxOpParams"), ("MAX_RANK", "kMaxRank")):
            self.assertEqual(getattr(spec, py), const(self.h, cc), py)

    def test_enums(self):
        cc_names = {"kConv2d": "CONV2D", "kDwConv2d": "DWCONV2D", "kLinear": "LINEAR",
                    "kSqueezeExcite": "SQUEEZE_EXCITE", "kAdd": "ADD", "kLayerNorm": "LAYERNORM",
                    "kAttention": "ATTENTION", "kActivation": "ACTIVATION", "kConcat": "CONCAT",
                    "kCrossAttention1q": "CROSS_ATTENTION_1Q", "kFps": "FPS",
                    "kBallGroup": "BALL_GROUP", "kGroupMax": "GROUP_MAX",
                    "kThreeInterp": "THREE_INTERP", "kGridTokens": "GRID_TOKENS"}
        ops = enum_values(self.h, "OpCode")
        self.assertEqual({cc_names[k]: v for k, v in ops.items()},
                         {n: c for c, n in spec.OP_NAMES.items()})
        self.assertEqual(enum_values(self.h, "DType"),
                         {"kF32": spec.DTYPE_F32, "kI8": spec.DTYPE_I8, "kI32": spec.DTYPE_I32,
                          "kU8": spec.DTYPE_U8})
        self.assertEqual(enum_values(self.h, "Act"),
                         {"kNone": spec.ACT_NONE, "kSilu": spec.ACT_SILU, "kGelu": spec.ACT_GELU,
                          "kSigmoid": spec.ACT_SIGMOID, "kRelu": spec.ACT_RELU})
        keys = enum_values(self.h, "MetaKey")
        self.assertEqual(sorted(keys.values()), sorted(spec.META_KEYS))
        self.assertEqual(enum_values(self.h, "Modality"),
                         {"kImage": spec.MODALITY_IMAGE, "kLidarBev": spec.MODALITY_LIDAR_BEV,
                          "kLidarPoints": spec.MODALITY_LIDAR_POINTS})

    def test_section_tags(self):
        for tag in ("META", "STRS", "TENS", "OPSQ", "WGHT"):
            self.assertIn("'%s', '%s', '%s', '%s'" % tuple(tag), self.h)


if __name__ == "__main__":
    unittest.main()
