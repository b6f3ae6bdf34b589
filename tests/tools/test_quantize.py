"""int8 quantisation (issue #4): calibration refusals, the rewrite, the reader."""

import json
import os
import tempfile
import unittest

import numpy as np
import torch
from PIL import Image

from aprt_tools.convert import engine_ir
from aprt_tools.convert.convert import convert
from aprt_tools.convert.quantize import (CalibrationError, backbone_ops, choose_range,
                                         Observed, quantize_model, quantize_weights)
from aprt_tools.export import export_onnx
from aprt_tools.model.apr_transformer import AprConfig, AprTransformer
from aprt_tools.model.weights import vary
from aprt_tools.model_bin import spec
from aprt_tools.model_bin.reader import ModelBinError, read
from aprt_tools.model_bin.writer import serialise


def tiny_model() -> bytes:
    cfg = AprConfig.named("tiny")
    torch.manual_seed(5)
    model = vary(AprTransformer(cfg), 5)
    blob, _ = convert(export_onnx(model, 13), config=json.loads(cfg.to_json()))
    return blob


class Quantize(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.fp32 = tiny_model()
        cls.eg, cls.meta = read(cls.fp32)
        cls.tmp = tempfile.TemporaryDirectory()
        _, h, w, c = cls.meta["input_shape"]
        rng = np.random.default_rng(0)
        cls.calib = os.path.join(cls.tmp.name, "calib.npy")
        np.save(cls.calib, rng.standard_normal((6, h, w, c)).astype(np.float32))
        cls.shape = (h, w, c)

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def path(self, name):
        return os.path.join(self.tmp.name, name)

    def refused(self, calibration, fragment, **kw):
        with self.assertRaises(CalibrationError) as ctx:
            quantize_model(self.fp32, calibration, **kw)
        self.assertIn(fragment, str(ctx.exception))

    def test_reader_round_trips_the_converters_file(self):
        self.assertEqual(serialise(self.eg, self.meta), self.fp32)

    def test_reader_refuses_corruption(self):
        bad = bytearray(self.fp32)
        bad[-1] ^= 0xFF
        with self.assertRaisesRegex(ModelBinError, "checksum mismatch"):
            read(bytes(bad))
        with self.assertRaisesRegex(ModelBinError, "truncated"):
            read(self.fp32[:-64])

    def test_calibration_data_missing_empty_or_wrong(self):
        h, w, c = self.shape
        self.refused(self.path("nowhere"), "does not exist")
        os.makedirs(self.path("empty"), exist_ok=True)
        self.refused(self.path("empty"), "holds no images")
        np.save(self.path("wrong.npy"), np.zeros((2, h + 1, w, c), np.float32))
        self.refused(self.path("wrong.npy"), f"the model's input is [N, {h}, {w}, {c}]")
        np.save(self.path("nchw.npy"), np.zeros((2, c, h, w), np.float32))
        self.refused(self.path("nchw.npy"), "NHWC")
        np.save(self.path("none.npy"), np.zeros((0, h, w, c), np.float32))
        self.refused(self.path("none.npy"), "holds no frames")
        nan = np.zeros((1, h, w, c), np.float32)
        nan[0, 0, 0, 0] = np.nan
        np.save(self.path("nan.npy"), nan)
        self.refused(self.path("nan.npy"), "non-finite")
        with open(self.path("junk.npy"), "wb") as f:
            f.write(b"not numpy")
        self.refused(self.path("junk.npy"), "neither a folder of images nor a .npy")
        self.refused(self.calib, "method 'best'", method="best")
        self.refused(self.calib, "percentile 20", percentile=20)
        self.refused(self.calib, "no op qualifies", fp32_ops=".")

    def test_images_folder_is_preprocessed_like_the_runtime(self):
        os.makedirs(self.path("imgs"), exist_ok=True)
        rng = np.random.default_rng(1)
        for i in range(3):
            Image.fromarray(rng.integers(0, 255, (48, 80, 3), np.uint8)).save(
                self.path(f"imgs/{i:03d}.png"))
        blob, report = quantize_model(self.fp32, self.path("imgs"), frames=2)
        self.assertEqual(report.frames, 2)
        self.assertGreater(len(report.ops), 0)

    def test_rewrite_policy_and_parameters(self):
        blob, report = quantize_model(self.fp32, self.calib)
        eg, meta = read(blob)
        q = [op for op in eg.ops if op.code == spec.OP_LINEAR and
             op.inputs[1].dtype == spec.DTYPE_I8]
        self.assertEqual(len(q), len(report.ops))
        self.assertGreater(len(q), 0)
        skip = backbone_ops(eg)
        for op in q:
            w = op.inputs[1]
            self.assertNotIn(id(op), skip)  # the backbone stays fp32 by default
            self.assertGreater(int(np.prod(op.inputs[0].shape[:-1])), 1)
            self.assertIsNotNone(w.qscale)
            self.assertTrue((w.qscale.data > 0).all())
            self.assertLessEqual(int(np.abs(w.data.astype(int)).max()), 127)
            self.assertGreater(op.params["input_scale"], 0)
            self.assertTrue(0 <= op.params["input_zero"] <= 255)
        info = json.loads(meta["quantization"])
        self.assertEqual(info["frames"], 6)
        self.assertEqual(len(info["int8_ops"]), len(q))
        # The int8 graph differs from fp32, and only a little.
        inp = next(t for t in eg.tensors if t.kind == spec.KIND_INPUT)
        out = next(t for t in eg.tensors if t.kind == spec.KIND_OUTPUT)
        x = np.load(self.calib)[:1]
        ref_in = next(t for t in self.eg.tensors if t.kind == spec.KIND_INPUT)
        ref_out = next(t for t in self.eg.tensors if t.kind == spec.KIND_OUTPUT)
        a = engine_ir.run(self.eg, {ref_in: x})[id(ref_out)].reshape(-1)
        b = engine_ir.run(eg, {inp: x})[id(out)].reshape(-1)
        dev = np.abs(a - b).max() / np.abs(a).max()
        self.assertGreater(dev, 0)
        self.assertLess(dev, 0.05)
        with self.assertRaises(CalibrationError):
            quantize_model(blob, self.calib)  # already quantised

    def test_backbone_flag_quantises_more(self):
        _, default = quantize_model(self.fp32, self.calib)
        _, more = quantize_model(self.fp32, self.calib, backbone=True)
        self.assertGreater(len(more.ops), len(default.ops))

    def test_attention_precision_int8_or_bf16(self):
        for kw, code, key in ((dict(int8_attention=True), 1, "int8_attention"),
                              (dict(bf16_attention=True), 2, "bf16_attention")):
            blob, report = quantize_model(self.fp32, self.calib, **kw)
            eg, meta = read(blob)
            att = [op for op in eg.ops if op.code == spec.OP_ATTENTION]
            self.assertGreater(len(att), 0)
            self.assertEqual({op.params.get("scores") for op in att}, {code})
            self.assertEqual(json.loads(meta["quantization"])[key], [op.name for op in att])
        self.refused(self.calib, "not both", int8_attention=True, bf16_attention=True)

    def test_bf16_rounding_is_the_engines(self):
        x = np.array([1.0, 1 + 2.0 ** -8, 1 + 3 * 2.0 ** -8, -2.5, 3.4e38, 1e-39, -1e-39,
                      np.inf, np.nan], np.float32)
        y = engine_ir.bf16_round(x)
        np.testing.assert_array_equal(y[:4], np.array([1.0, 1.0, 1 + 2.0 ** -6, -2.5],
                                                      np.float32))
        self.assertEqual(y[4], np.inf)  # beyond the largest bf16
        self.assertEqual(y[5], 0.0)
        self.assertTrue(np.signbit(y[6]) and y[6] == 0.0)  # denormals to a signed zero
        self.assertEqual(y[7], np.inf)
        self.assertTrue(np.isnan(y[8]))
        r = np.random.default_rng(1).standard_normal(1000).astype(np.float32)
        self.assertTrue((np.abs(engine_ir.bf16_round(r) - r) <= np.abs(r) * 2.0 ** -8).all())
        self.assertTrue(((engine_ir.bf16_round(r).view(np.uint32) & 0xFFFF) == 0).all())

    def test_ranges_and_weights(self):
        o = Observed()
        o.add(np.concatenate([np.linspace(-1, 3, 10001), [50.0]]), np.random.default_rng(0))
        s_mm, z_mm = choose_range(o, "minmax", 99.99)
        self.assertAlmostEqual(s_mm, 51 / 255, places=5)
        s_p, _ = choose_range(o, "percentile", 99.0)
        self.assertLess(s_p, s_mm)  # the outlier is clipped
        s_mse, z = choose_range(o, "mse", 99.99)
        self.assertLess(s_mse, s_mm)
        self.assertTrue(0 <= z <= 255)
        w = np.array([[0.5, -1.0, 0.25], [0.0, 0.0, 0.0]], np.float32)
        q, scales = quantize_weights(w)
        self.assertEqual(q.dtype, np.int8)
        np.testing.assert_array_equal(q[0], [64, -127, 32])
        self.assertTrue((scales > 0).all())  # an all-zero row still gets a valid scale


if __name__ == "__main__":
    unittest.main()
