"""The LiDAR raw-points modality's offline side (issue #5): the PointNet++
primitives by hand (model/point_ops.py is the definition the engine's ops
follow), the input transform (lidar_points.py; the C++
Preprocess.PointsInputMatchesTheTrainingTransform checks the runtime against
cases it writes), the configuration checks, the export's custom nodes, the
converter's lowering and 'points' metadata, and its refusals."""

import json
import unittest

import numpy as np
import onnx
import torch

from aprt_tools.convert.convert import convert
from aprt_tools.export import export_onnx
from aprt_tools.lidar_points import fps, points_features, points_meta, radius_crop
from aprt_tools.model import point_ops as po
from aprt_tools.model.apr_transformer import AprConfig, AprTransformer
from aprt_tools.model.pointnet2 import check_points_config, points_config
from aprt_tools.model.weights import vary
from aprt_tools.model_bin import spec
from aprt_tools.model_bin.reader import read
from aprt_tools.onnx.evaluate import UnsupportedOnnx


def coords(rows):
    """[[x, y, z], ...] -> (1, 3, N, 1)."""
    return torch.tensor(rows, dtype=torch.float32).T[None, :, :, None].contiguous()


class PointOps(unittest.TestCase):
    def test_fps_farthest_first_lower_index_on_ties(self):
        xyz = coords([[0, 0, 0], [4, 0, 0], [10, 0, 0], [6, 0, 0], [1, 0, 0]])
        idx = po.fps_indices(po._points(xyz), 4)
        self.assertEqual(idx.tolist(), [[0, 2, 1, 3]])
        with self.assertRaises(ValueError):
            po.fps_indices(po._points(xyz), 6)

    def test_ball_group_first_k_in_index_order_padding_and_none(self):
        xyz = coords([[0, 0, 0], [0.5, 0, 0], [3, 0, 0], [0.2, 0, 0]])
        feats = torch.tensor([10.0, 11, 12, 13])[None, None, :, None]
        centres = coords([[0, 0, 0], [10, 0, 0]])
        g = po.ball_group_plain(xyz, centres, feats, 1.0, 4)  # (1, 4, 2, 4)
        self.assertEqual(g.shape, (1, 4, 2, 4))
        f32 = lambda v: np.asarray(v, np.float32).tolist()
        self.assertEqual(g[0, 0, 0].tolist(), f32([0.0, 0.5, 0.2, 0.0]))  # x - centre
        self.assertEqual(g[0, 3, 0].tolist(), [10.0, 11.0, 13.0, 10.0])
        self.assertEqual(g[0, 0, 1].tolist(), [-10.0] * 4)  # nothing within 1 m: point 0
        edge = coords([[1, 0, 0], [0, 0, 0]])
        e = po.ball_group_plain(edge, centres[:, :, :1], None, 1.0, 2)
        self.assertEqual(e[0, 0, 0].tolist(), [0.0, 0.0])  # strictly inside only

    def test_three_interpolate_weights_and_ties(self):
        known = coords([[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]])
        feats = torch.tensor([0.0, 10, 20, 30])[None, None, :, None]
        target = coords([[1.5, 0, 0]])
        d, i = po.three_nn(po._points(target), po._points(known))
        self.assertEqual(i.tolist(), [[[1, 2, 0]]])  # 0 and 3 tie at 2.25: 0 first
        y = po.three_interpolate_plain(target, known, feats)
        w = 4.0 + 4.0 + 1.0 / 2.25
        self.assertAlmostEqual(float(y), (40 + 80) / w, places=4)

    def test_grid_tokens_stable_and_ordered(self):
        xyz = coords([[1, 1, 0], [0, 0, 0], [0, 1, 0], [1, 0, 0],
                      [1, 1, 5], [0, 0, 5], [0, 1, 5], [1, 0, 5]])
        feats = torch.arange(8.0)[None, None, :, None]
        t = po.grid_tokens_plain(xyz, feats, 2, 2, 2)
        self.assertEqual(t.shape, (1, 1, 2, 4))
        self.assertEqual(t.reshape(-1).tolist(), [1, 2, 3, 0, 5, 6, 7, 4])
        ties = coords([[0, 3, 1], [0, 2, 1], [0, 1, 1], [0, 0, 1]])
        f = torch.tensor([30.0, 20, 10, 0])[None, None, :, None]
        self.assertEqual(po.grid_tokens_plain(ties, f, 1, 2, 2).reshape(-1).tolist(),
                         [20, 30, 0, 10])


class Input(unittest.TestCase):
    CFG = dict(crop_radius_m=10.0, coord_scale_m=5.0)

    def test_crop_sample_and_features(self):
        pts = np.array([[0, 0, 0, 0], [5, 0, 0, 0], [20, 0, 0, 0], [0, 5, 0, 0],
                        [0, -5, 1, 0], [-5, 0, 0, 0], [np.nan, 0, 0, 0]], np.float32)
        self.assertEqual(len(radius_crop(pts[:6], 10.0)), 5)
        f, ok = points_features(pts, 4, self.CFG)
        self.assertTrue(ok)
        self.assertEqual(f.shape, (4, 6))
        self.assertEqual(f[0, :3].tolist(), [0, 0, 0])
        # (0, -5, 1) / 5: the farthest from the first
        self.assertEqual(f[1, :3].tolist(), np.asarray([0.0, -1.0, 0.2], np.float32).tolist())
        np.testing.assert_allclose(f[:, 3:], f[:, :3] - f[:, :3].mean(axis=0), atol=1e-6)

    def test_too_few_points_repeat_and_empty_is_zero(self):
        pts = np.array([[0, 0, 0, 0], [3, 0, 0, 0]], np.float32)
        f, ok = points_features(pts, 5, self.CFG)
        self.assertFalse(ok)
        self.assertEqual(f[:, 0].tolist(), np.asarray([0, 0.6, 0, 0.6, 0], np.float32).tolist())
        f, ok = points_features(np.zeros((0, 4), np.float32), 5, self.CFG)
        self.assertFalse(ok)
        self.assertFalse(f.any())
        idx, ok = fps(np.zeros((0, 3), np.float32), 3)
        self.assertFalse(ok)

    def test_batched_sampling_equals_one_by_one(self):
        from aprt_tools.lidar_points import points_features_many, synthetic_scene

        rng = np.random.default_rng(5)
        scans = [synthetic_scene(rng, n=n) for n in (3000, 1500, 2500)]
        scans.append(scans[0][:100])  # too few points: the single-scan path
        cfg = dict(crop_radius_m=20.0, coord_scale_m=20.0)
        many, oks = points_features_many(scans, 256, cfg, batch=2)
        for k, scan in enumerate(scans):
            f, ok = points_features(scan, 256, cfg)
            np.testing.assert_array_equal(many[k], f)
            self.assertEqual(oks[k], ok)
        self.assertFalse(oks[3])

    def test_meta_order_is_the_formats(self):
        self.assertEqual(points_meta(dict(crop_radius_m=20, coord_scale_m=15)), [20.0, 15.0])


class TrainingInputs(unittest.TestCase):
    def test_inputs_array_must_fit_the_sequence(self):
        import os
        import tempfile

        from aprt_tools.train_data import load_points_sequence

        with tempfile.TemporaryDirectory() as d:
            os.makedirs(os.path.join(d, "lidar"))
            with open(os.path.join(d, "lidar_poses.txt"), "w") as f:
                for i in range(4):
                    np.zeros((600, 4), np.float32).tofile(os.path.join(d, f"lidar/{i}.bin"))
                    f.write(f"lidar/{i}.bin {i} 0 0 1 0 0 0\n")
            cfg = dict(points_config(tiny=True))
            good = np.random.default_rng(1).standard_normal((2, 512, 1, 6)).astype(np.float32)
            np.save(os.path.join(d, "in.npy"), good)
            x, pos, _ = load_points_sequence(d, cfg, lambda *a: None, os.path.join(d, "in.npy"), 2)
            self.assertEqual(tuple(x.shape), (2, 6, 512, 1))
            self.assertEqual(pos[:, 0].tolist(), [0.0, 2.0])  # every 2nd pose
            np.testing.assert_array_equal(x[1, :, 7, 0].numpy(), good[1, 7, 0])
            with self.assertRaisesRegex(ValueError, "needs \\[4, 512, 1, 6\\]"):
                load_points_sequence(d, cfg, lambda *a: None, os.path.join(d, "in.npy"), 1)


class Configuration(unittest.TestCase):
    def test_presets(self):
        full = AprConfig.named("points")
        self.assertEqual(full.input_shape(), (1, 6, 4096, 1))
        self.assertEqual([s["npoint"] for s in full.points["sa"]], [1024, 256, 64, 16])
        self.assertEqual(full.points["tokens"], dict(groups=8, gx=4, gy=4))
        self.assertEqual(full.backbone, "pointnet2")
        tiny = AprConfig.named("tiny-points")
        self.assertEqual(tiny.input_shape(), (1, 6, 512, 1))
        self.assertEqual(AprConfig.from_json(tiny.to_json()).points, tiny.points)

    def test_refusals(self):
        bad = points_config(tiny=True)
        bad["sa"][0]["npoint"] = 100  # not 8 x 4 x 4 cells
        with self.assertRaisesRegex(ValueError, "do not split"):
            check_points_config(bad)
        bad = points_config(tiny=True)
        bad["sa"][1]["npoint"] = 1000
        with self.assertRaisesRegex(ValueError, "level 2 samples 1000 of 128"):
            check_points_config(bad)
        bad = points_config(tiny=True)
        bad["fp"] = bad["fp"][:1]
        with self.assertRaisesRegex(ValueError, "propagation layers"):
            check_points_config(bad)


class ExportAndConvert(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        torch.manual_seed(4)
        cls.cfg = AprConfig.named("tiny-points")
        cls.model = vary(AprTransformer(cls.cfg), 4)
        cls.onnx = export_onnx(cls.model, 13)

    def test_export_has_one_custom_node_per_op(self):
        m = onnx.load_from_string(self.onnx)
        custom = [n.op_type for n in m.graph.node if n.domain == "aprt"]
        self.assertEqual(custom.count("FarthestPointSample"), 4)
        self.assertEqual(custom.count("BallGroup"), 4)
        self.assertEqual(custom.count("ThreeInterpolate"), 3)
        self.assertEqual(custom.count("GridTokens"), 1)

    def test_converts_with_points_metadata_and_matches_pytorch(self):
        blob, report = convert(self.onnx, config=json.loads(self.cfg.to_json()))
        self.assertLess(report.max_rel_error_output, 1e-5)
        for op in ("FPS", "BALL_GROUP", "GROUP_MAX", "THREE_INTERP", "GRID_TOKENS"):
            self.assertIn(op, report.ops)
        eg, meta = read(blob)
        self.assertEqual(meta["modality"], spec.MODALITY_LIDAR_POINTS)
        self.assertEqual(meta["points"], [20.0, 20.0])
        self.assertEqual(meta["input_shape"], [1, 512, 1, 6])
        # The file's graph, run by the converter's statement of the ops, is the network.
        from aprt_tools.convert import engine_ir
        from aprt_tools.model.weights import sample_inputs

        x = sample_inputs(1, self.cfg, torch.Generator().manual_seed(9))
        with torch.no_grad():
            want = self.model(x).numpy().reshape(-1)
        inp = next(t for t in eg.tensors if t.kind == spec.KIND_INPUT)
        out = next(t for t in eg.tensors if t.kind == spec.KIND_OUTPUT)
        got = engine_ir.run(eg, {inp: x.numpy().transpose(0, 2, 3, 1)})[id(out)].reshape(-1)
        np.testing.assert_allclose(got, want, rtol=1e-4, atol=1e-4 * np.abs(want).max())

    def test_portable_export_is_refused_by_name(self):
        # ONNX Runtime's spelling (FPS as an ONNX Loop over sequences, TopK,
        # Gather): the converter does not pattern-match it and names the node
        # it cannot run.
        small = AprConfig.named("tiny-points")
        small.points["samples"] = 128
        small.image_size = 128
        small.points["sa"] = [dict(npoint=128, radius=0.3, nsample=4, mlp=[8]),
                              dict(npoint=4, radius=0.6, nsample=4, mlp=[8])]
        small.points["fp"] = [[8]]
        blob = export_onnx(AprTransformer(small), 13, portable=True)
        with self.assertRaisesRegex(UnsupportedOnnx, "node '[^']+': operator '[A-Za-z]+' is "
                                                     "not supported"):
            convert(blob, config=json.loads(small.to_json()))


if __name__ == "__main__":
    unittest.main()
