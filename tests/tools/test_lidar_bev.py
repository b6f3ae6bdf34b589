"""The LiDAR BEV modality's offline side (issue #5): the histogram the model is
trained on, the configurations, and the converter's 'bev' metadata. (That the
runtime's kernels compute the same histogram is checked by the C++
Preprocess.BevHistogramMatchesTheTrainingTransform on cases this module writes.)"""

import json
import os
import tempfile
import unittest

import numpy as np
import torch

from aprt_tools.convert.convert import convert
from aprt_tools.convert.quantize import CalibrationError, quantize_model
from aprt_tools.export import export_onnx
from aprt_tools.lidar_bev import BEV_KEYS, bev_histogram, bev_meta
from aprt_tools.model.apr_transformer import AprConfig, AprTransformer
from aprt_tools.model.weights import vary
from aprt_tools.model_bin import spec
from aprt_tools.model_bin.reader import read

GEOM = dict(cell_m=1.0, x_min=-2.0, y_min=-2.0, height_threshold_m=0.0, clip_count=2.0)


class Histogram(unittest.TestCase):
    def test_cells_channels_clip_and_what_is_dropped(self):
        pts = np.array([
            [-2.0, -2.0, -1.0, 0],   # row 0, col 0, below
            [-1.5, -2.0, 0.0, 0],    # row 0, col 0, at the threshold: above
            [1.99, 0.5, 5.0, 0],     # row 3, col 2, above
            [1.99, 0.5, 5.0, 0],
            [1.99, 0.5, 5.0, 0],     # third in the cell: clipped at 2
            [2.0, 0.0, 0.0, 0],      # x at the far edge: off the grid
            [-2.01, 0.0, 0.0, 0],    # just below x_min: off the grid
            [np.nan, 0.0, 0.0, 0],   # dropped
            [0.0, 0.0, np.inf, 0],   # dropped
        ], np.float32)
        h = bev_histogram(pts, 4, GEOM)
        self.assertEqual(h.shape, (4, 4, 2))
        self.assertEqual(h[0, 0, 0], 0.5)
        self.assertEqual(h[0, 0, 1], 0.5)
        self.assertEqual(h[3, 2, 1], 1.0)
        self.assertEqual(float(h.sum()), 2.0)

    def test_empty_scan_is_all_zero(self):
        h = bev_histogram(np.zeros((0, 4), np.float32), 8, GEOM)
        self.assertFalse(h.any())

    def test_meta_order_is_the_formats(self):
        self.assertEqual(BEV_KEYS, ("cell_m", "x_min", "y_min", "height_threshold_m",
                                    "clip_count"))
        self.assertEqual(bev_meta(GEOM), [1.0, -2.0, -2.0, 0.0, 2.0])


class Configurations(unittest.TestCase):
    def test_the_grid_spans_32_m_unless_told(self):
        for name, size, grid in (("bev", None, 256), ("tiny-bev", None, 64), ("bev", 64, 64)):
            cfg = AprConfig.named(name, size)
            self.assertEqual(cfg.image_size, grid)
            self.assertEqual(cfg.in_channels, 2)
            self.assertAlmostEqual(cfg.bev["cell_m"] * grid, 32.0)
            self.assertEqual(AprConfig.from_json(cfg.to_json()).bev, cfg.bev)
        cfg = AprConfig.named("bev", 64, bev_span_m=64.0)  # the shipped town_bev.aprt's square
        self.assertEqual((cfg.bev["cell_m"], cfg.bev["x_min"], cfg.bev["y_min"]), (1.0, -32.0, -32.0))
        with self.assertRaisesRegex(ValueError, "BEV span 1.0 m"):
            AprConfig.named("bev", 64, bev_span_m=1.0)

    def test_converter_writes_modality_and_geometry(self):
        cfg = AprConfig.named("tiny-bev")
        torch.manual_seed(2)
        model = vary(AprTransformer(cfg), 2)
        blob, report = convert(export_onnx(model, 13), config=json.loads(cfg.to_json()))
        _, meta = read(blob)
        self.assertEqual(meta["modality"], spec.MODALITY_LIDAR_BEV)
        self.assertEqual(meta["input_shape"], [1, 64, 64, 2])
        np.testing.assert_allclose(meta["bev"], bev_meta(cfg.bev), rtol=1e-7)
        self.assertLess(report.max_rel_error_output, 1e-4)


def scans_only_sequence(d, n=3, seed=0):
    """A LiDAR sequence without camera images (aprt_synth --lidar --no-images)."""
    os.makedirs(os.path.join(d, "lidar"))
    rng = np.random.default_rng(seed)
    lines = []
    for k in range(n):
        pts = rng.uniform(-20, 20, (3000, 4)).astype(np.float32)
        pts[:, 2] = rng.uniform(-2, 2, 3000)
        pts.tofile(os.path.join(d, "lidar", f"{k}.bin"))
        lines.append(f"lidar/{k}.bin {k} 0 1.9 1 0 0 0")
    with open(os.path.join(d, "lidar_poses.txt"), "w") as f:
        f.write("\n".join(lines) + "\n")


class Confidence(unittest.TestCase):
    def test_calibrates_on_the_scans(self):
        # The confidence is calibrated on the validation drive's scans as the
        # model sees them (it used to read camera images whatever the model).
        from aprt_tools.confidence import calibrate_file

        cfg = AprConfig.named("tiny-bev")
        cfg.uncertainty = True
        torch.manual_seed(5)
        blob, _ = convert(export_onnx(vary(AprTransformer(cfg), 5), 13),
                          config=json.loads(cfg.to_json()))
        with tempfile.TemporaryDirectory() as d:
            scans_only_sequence(d, n=6)
            out, report = calibrate_file(blob, d)
        self.assertIn("on 6 frames", report)
        self.assertEqual(len(read(out)[1]["uncertainty"]), 2)


class Int8(unittest.TestCase):
    def test_bev_model_calibrates_on_a_lidar_sequence(self):
        cfg = AprConfig.named("tiny-bev")
        torch.manual_seed(4)
        blob, _ = convert(export_onnx(vary(AprTransformer(cfg), 4), 13),
                          config=json.loads(cfg.to_json()))
        with tempfile.TemporaryDirectory() as d:
            scans_only_sequence(d)
            q, report = quantize_model(blob, d, frames=8)
            self.assertEqual(report.frames, 3)
            self.assertGreater(len(report.ops), 0)
            _, meta = read(q)
            self.assertEqual(meta["bev"], read(blob)[1]["bev"])
            os.remove(os.path.join(d, "lidar_poses.txt"))
            with self.assertRaisesRegex(CalibrationError, "no lidar_poses.txt"):
                quantize_model(blob, d)


if __name__ == "__main__":
    unittest.main()
