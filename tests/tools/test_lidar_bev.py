"""The LiDAR BEV modality's offline side (issue #5): the histogram the model is
trained on, the configurations, and the converter's 'bev' metadata. (That the
runtime's kernels compute the same histogram is checked by the C++
Preprocess.BevHistogramMatchesTheTrainingTransform on cases this module writes.)"""

import json
import unittest

import numpy as np
import torch

from aprt_tools.convert.convert import convert
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
    def test_the_grid_always_spans_32_m(self):
        for name, size, grid in (("bev", None, 256), ("tiny-bev", None, 64), ("bev", 64, 64)):
            cfg = AprConfig.named(name, size)
            self.assertEqual(cfg.image_size, grid)
            self.assertEqual(cfg.in_channels, 2)
            self.assertAlmostEqual(cfg.bev["cell_m"] * grid, 32.0)
            self.assertEqual(AprConfig.from_json(cfg.to_json()).bev, cfg.bev)

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


if __name__ == "__main__":
    unittest.main()
