"""A converted model file read back into the reference network
(model_bin/to_torch.py: `train --init MODEL.aprt`) computes the file's
function; the confidence calibration (confidence.py) gives the coverage it
is fitted for."""

import tempfile
import unittest

import numpy as np
import torch

from aprt_tools.model.apr_transformer import AprConfig, AprTransformer
from aprt_tools.model.weights import vary


def converted(cfg, seed=3):
    from aprt_tools.convert.convert import convert
    from aprt_tools.export import export_onnx

    model = vary(AprTransformer(cfg), seed=seed)
    config = __import__("json").loads(cfg.to_json())
    blob, _ = convert(export_onnx(model, 13), config=config)
    return model, blob


class ReadBack(unittest.TestCase):
    def check(self, cfg):
        from aprt_tools.model_bin import to_torch

        _, blob = converted(cfg)
        x = torch.randn((3,) + cfg.input_shape()[1:], generator=torch.Generator().manual_seed(1))
        model, got_cfg = to_torch.load(blob, x)
        self.assertEqual(got_cfg.hidden_dim, cfg.hidden_dim)
        self.assertLess(to_torch.check(blob, model, x), 1e-4)
        # The read-back network trains: its BatchNorm in training mode is near
        # its eval function on the frames it was estimated on.
        model.train()
        with torch.no_grad():
            y_train = model(x)
        model.eval()
        with torch.no_grad():
            y_eval = model(x)
        self.assertLess(float((y_train - y_eval).abs().max()), 0.5)
        return model

    def test_one_decoder_layer(self):  # no query positions in the graph: recovered as zero
        cfg = AprConfig.named("tiny")
        cfg.pose_min, cfg.pose_max = (0.0, 0.0, 0.0), (100.0, 50.0, 3.0)
        self.check(cfg)

    def test_two_layers_with_confidence_heads(self):
        cfg = AprConfig.named("tiny")
        cfg.enc_layers = cfg.dec_layers = 2
        cfg.uncertainty = True
        cfg.pose_min, cfg.pose_max = (0.0, 0.0, 0.0), (100.0, 50.0, 3.0)
        model = self.check(cfg)
        self.assertTrue(hasattr(model, "uncertainty_head_t"))

    def test_refuses_a_file_without_its_configuration(self):
        from aprt_tools.model_bin import reader, to_torch
        from aprt_tools.model_bin.writer import serialise

        cfg = AprConfig.named("tiny")
        cfg.pose_min, cfg.pose_max = (0.0, 0.0, 0.0), (100.0, 50.0, 3.0)
        _, blob = converted(cfg)
        graph, meta = reader.read(blob)
        meta.pop("config_json")
        with self.assertRaisesRegex(to_torch.ToTorchError, "no configuration"):
            to_torch.load(serialise(graph, meta))


class Calibration(unittest.TestCase):
    def test_fit_gives_the_coverage_it_is_fitted_for(self):
        from aprt_tools import confidence

        rng = np.random.default_rng(5)
        n = 4000
        lo, hi = np.array([0.0, 0.0, 0.0]), np.array([200.0, 200.0, 2.0])
        truth = rng.uniform([10, 10, 0], [190, 190, 2], (n, 3))
        truth[:, 2] = 1.5
        b = np.exp(rng.uniform(-6, -3, (n, 3)))  # Laplace scales, normalised units
        raw = np.zeros((n, 13))
        raw[:, :3] = (truth - lo) / (hi - lo) + rng.laplace(0, 1, (n, 3)) * b * 3.0
        raw[:, 3] = 1.0  # identity orientation, truth the same
        raw[:, 7:10] = np.log(b)  # over-confident by a factor of 3
        raw[:, 10:13] = np.log(0.01)
        quat = np.tile([1.0, 0, 0, 0], (n, 1))
        k_pos, k_rot = confidence.fit(raw, truth, quat, lo, hi)
        self.assertGreater(k_pos, 2.0)  # it finds the factor
        cov = confidence.coverage(raw, truth, quat, lo, hi, k_pos, k_rot)
        self.assertAlmostEqual(cov[0], 0.95, delta=0.01)


if __name__ == "__main__":
    unittest.main()
