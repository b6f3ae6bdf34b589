"""The converter: refuses what the engine cannot run, naming the node; checks itself."""

import io
import os
import struct
import unittest
import zlib

import numpy as np
import onnx
import torch
from onnx import TensorProto, helper

from aprt_tools.convert.convert import convert
from aprt_tools.export import export_onnx
from aprt_tools.model.apr_transformer import AprConfig, AprTransformer
from aprt_tools.model.weights import vary
from aprt_tools.model_bin import spec
from aprt_tools.onnx.evaluate import UnsupportedOnnx, run_model
from aprt_tools.onnx.graph import fold
from aprt_tools.onnx.patterns import rewrite

BOUNDS = dict(pose_min=[0, 0, 0], pose_max=[1, 1, 1])
IMAGENET = dict(norm_mean=[0.485, 0.456, 0.406], norm_std=[0.229, 0.224, 0.225])


def torch_onnx(module, shape, opset=13):
    buf = io.BytesIO()
    module.eval()
    torch.onnx.export(module, torch.zeros(shape), buf, opset_version=opset,
                      input_names=["image"], output_names=["pose"])
    return buf.getvalue()


class Refusals(unittest.TestCase):
    def assertRefused(self, data, *fragments):
        with self.assertRaises(UnsupportedOnnx) as ctx:
            convert(data, overrides=dict(BOUNDS, **IMAGENET))
        for f in fragments:
            self.assertIn(f, str(ctx.exception))

    def test_not_onnx(self):
        self.assertRefused(b"definitely not a protobuf" * 10, "not an ONNX model")

    def test_unsupported_operator_is_named(self):
        net = torch.nn.Sequential(torch.nn.Conv2d(3, 8, 3), torch.nn.MaxPool2d(2))
        self.assertRefused(torch_onnx(net, (1, 3, 16, 16)), "MaxPool", "not supported")

    def test_dynamic_input_shape(self):
        x = helper.make_tensor_value_info("image", TensorProto.FLOAT, ["n", 3, 8, 8])
        y = helper.make_tensor_value_info("pose", TensorProto.FLOAT, ["n", 3, 8, 8])
        g = helper.make_graph([helper.make_node("Relu", ["image"], ["pose"], name="r")], "g", [x], [y])
        m = helper.make_model(g, opset_imports=[helper.make_opsetid("", 13)])
        self.assertRefused(m.SerializeToString(), "static")

    def test_old_opset(self):
        net = torch.nn.Conv2d(3, 4, 1)
        self.assertRefused(torch_onnx(net, (1, 3, 8, 8), opset=11), "opset 11")

    def test_grouped_convolution(self):
        net = torch.nn.Sequential(torch.nn.Conv2d(4, 8, 3, groups=2))
        self.assertRefused(torch_onnx(net, (1, 4, 8, 8)), "groups", "Conv")

    def test_graph_without_attention_is_not_an_apr_transformer(self):
        net = torch.nn.Sequential(torch.nn.Conv2d(3, 7, 8), torch.nn.Flatten())
        self.assertRefused(torch_onnx(net, (1, 3, 8, 8)), "not an APR-Transformer")

    def test_metadata_must_be_known(self):
        cfg = AprConfig.named("tiny")
        data = export_onnx(AprTransformer(cfg), 13)
        with self.assertRaises(UnsupportedOnnx) as ctx:
            convert(data, overrides=dict(IMAGENET))
        self.assertIn("pose_min", str(ctx.exception))


class Conversion(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.cfg = AprConfig.named("tiny")
        torch.manual_seed(3)
        cls.model = vary(AprTransformer(cls.cfg), 3)
        cls.onnx13 = export_onnx(cls.model, 13)
        cls.onnx17 = export_onnx(cls.model, 17)

    def test_both_opsets_give_the_same_op_list(self):
        cfg = dict(json_cfg(self.cfg))
        _, r13 = convert(self.onnx13, config=cfg)
        _, r17 = convert(self.onnx17, config=cfg)
        self.assertEqual(r13.ops, r17.ops)
        self.assertLess(r13.max_rel_error_output, 1e-5)
        self.assertLess(r17.max_rel_error_output, 1e-5)

    def test_rewrite_leaves_only_engine_vocabulary(self):
        m = onnx.load_from_string(self.onnx13)
        g = fold(m, np.random.default_rng(0).standard_normal((1, 3, 64, 64)).astype(np.float32))
        rewrite(g)
        left = {n.op for n in g.nodes if not n.op.startswith("aprt.")}
        self.assertLessEqual(left, {"Conv", "Pad", "Add", "Concat", "Reshape", "Transpose",
                                    "Squeeze", "Unsqueeze", "Gather", "Flatten", "Slice"})

    def test_interpreter_matches_pytorch(self):
        x = torch.randn(1, 3, 64, 64)
        with torch.no_grad():
            want = self.model(x).numpy()
        got = run_model(onnx.load_from_string(self.onnx13), {"image": x.numpy()})[0]
        np.testing.assert_allclose(got, want, rtol=1e-4, atol=1e-5)

    def test_file_is_well_formed(self):
        blob, report = convert(self.onnx13, config=json_cfg(self.cfg))
        self.assertEqual(blob[:8], spec.MAGIC)
        major, minor, hb, total, count = struct.unpack_from("<HHIQI", blob, 8)
        self.assertEqual((major, hb, total, count), (spec.VERSION_MAJOR, 64, len(blob), 5))
        for i in range(count):
            tag, _, off, size, crc, _ = struct.unpack_from("<IIQQII", blob, 64 + 32 * i)
            self.assertEqual(off % 64, 0)
            self.assertEqual(zlib.crc32(blob[off:off + size]), crc)
        self.assertEqual(report.meta["d_model"], 32)
        self.assertEqual(report.meta["nheads"], 8)
        self.assertEqual((report.meta["enc_layers"], report.meta["dec_layers"]), (1, 1))

    def test_wrong_configuration_is_refused(self):
        cfg = json_cfg(self.cfg)
        cfg["nheads"] = 4
        with self.assertRaises(UnsupportedOnnx) as ctx:
            convert(self.onnx13, config=cfg)
        self.assertIn("nheads", str(ctx.exception))


def json_cfg(cfg):
    import json

    return json.loads(cfg.to_json())


if __name__ == "__main__":
    unittest.main()


class SingleQueryAlgebra(unittest.TestCase):
    """The decoder rewrites give what the plain path gives."""

    def test_fused_and_plain_graphs_agree(self):
        from aprt_tools.convert import engine_ir
        from aprt_tools.convert.fuse import fuse
        from aprt_tools.convert.lower import lower

        cfg = AprConfig.named("full", 64)
        cfg.enc_layers = cfg.dec_layers = 2  # keeps the test fast; the decoder still repeats
        torch.manual_seed(5)
        model = vary(AprTransformer(cfg), 5)
        m = onnx.load_from_string(export_onnx(model, 13))
        x = np.random.default_rng(1).standard_normal((1, 3, 64, 64)).astype(np.float32)
        outs = []
        counts = []
        for single_query in (False, True):
            g = fold(m, x)
            rewrite(g)
            eg, _ = lower(g)
            fuse(eg, single_query=single_query)
            inp = next(t for t in eg.tensors if t.kind == spec.KIND_INPUT)
            out = next(t for t in eg.tensors if t.kind == spec.KIND_OUTPUT)
            outs.append(engine_ir.run(eg, {inp: x.transpose(0, 2, 3, 1)})[id(out)].reshape(-1))
            counts.append({spec.OP_NAMES[c]: sum(1 for op in eg.ops if op.code == c)
                           for c in spec.OP_NAMES})
        np.testing.assert_allclose(outs[1], outs[0], rtol=1e-5, atol=1e-6)
        plain, fused = counts
        self.assertEqual(fused["CROSS_ATTENTION_1Q"], 4)  # 2 layers x 2 branches
        self.assertEqual(plain["CROSS_ATTENTION_1Q"], 0)
        # Self-attention over the single query disappears (layer 0 is folded as constant).
        self.assertEqual(plain["ATTENTION"] - fused["ATTENTION"], 4 + 2)
