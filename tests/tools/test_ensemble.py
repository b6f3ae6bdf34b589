"""An ensemble file (aprt_tools/ensemble.py) gives its members' outputs side by
side, merged as the runtime merges them (ensemble_merge.py, mirrored by
tests/unit/ensemble_merge_test.cc on the same numbers) (engine_ir's statement of the engine; the C++ engine against PyTorch
is golden.tiny_ensemble), refuses members that are not one model, and is not
read back into one network."""

import json
import unittest

import numpy as np

from aprt_tools.model.apr_transformer import AprConfig, AprTransformer
from aprt_tools.model.weights import vary


def tiny(uncertainty=True, pose_max=(100.0, 50.0, 3.0)):
    cfg = AprConfig.named("tiny")
    cfg.uncertainty = uncertainty
    cfg.pose_min, cfg.pose_max = (0.0, 0.0, 0.0), pose_max
    return cfg


_CACHE = {}


def converted(cfg, seed):
    """model_bin bytes of a varied-weight network (cached: conversion is slow)."""
    from aprt_tools.convert.convert import convert
    from aprt_tools.export import export_onnx

    key = (cfg.to_json(), seed)
    if key not in _CACHE:
        model = vary(AprTransformer(cfg), seed=seed)
        _CACHE[key] = convert(export_onnx(model, 13), config=json.loads(cfg.to_json()))[0]
    return _CACHE[key]


def engine_output(blob, x):
    from aprt_tools.convert import engine_ir
    from aprt_tools.model_bin import reader, spec

    graph, _ = reader.read(blob)
    inp = next(t for t in graph.tensors if t.kind == spec.KIND_INPUT)
    out = next(t for t in graph.tensors if t.kind == spec.KIND_OUTPUT)
    return np.asarray(engine_ir.run(graph, {inp: x})[id(out)]).reshape(-1)


class Ensemble(unittest.TestCase):
    def test_the_graph_computes_the_members_mean(self):
        from aprt_tools.ensemble import build
        from aprt_tools.model_bin import reader
        from aprt_tools.model_bin.writer import serialise

        members = [converted(tiny(), seed) for seed in (3, 4, 5)]
        graph, meta = build(members, ["a", "b", "c"])
        meta["uncertainty"] = [1.0, 1.0]
        blob = serialise(graph, meta)
        self.assertEqual(reader.read(blob)[1]["ensemble"], 3)
        shape = reader.read(members[0])[1]["input_shape"]
        x = np.random.default_rng(2).standard_normal(shape).astype(np.float32)
        each = [engine_output(m, x) for m in members]
        got = engine_output(blob, x)
        self.assertEqual(got.shape, (13 * 3,))  # FORMAT.md 1.5: the members side by side
        np.testing.assert_allclose(got, np.concatenate(each), rtol=1e-5, atol=1e-6)
        # The members differ, or the test would prove nothing.
        self.assertGreater(np.abs(each[0] - each[1]).max(), 1e-3)

    def test_refuses_members_that_are_not_one_model(self):
        from aprt_tools.ensemble import EnsembleError, build

        a = converted(tiny(), 3)
        other = tiny()
        other.hidden_dim *= 2
        with self.assertRaisesRegex(EnsembleError, "config_json differs"):
            build([a, converted(other, 4)], ["a", "b"])
        with self.assertRaisesRegex(EnsembleError, "confidence outputs"):
            build([converted(tiny(uncertainty=False), 3), converted(tiny(uncertainty=False), 4)],
                  ["a", "b"])
        with self.assertRaisesRegex(EnsembleError, "2 to 8"):
            build([a], ["a"])

    def test_members_with_their_own_bounds_are_averaged_in_metres(self):
        """Networks trained on different drives normalise positions by different
        bounds: the ensemble's are their union, and its outputs, read with them,
        are the mean of the members' positions and the geometric mean of their
        sigmas, in metres; a member extracted has its own bounds again."""
        from aprt_tools.ensemble import build, extract
        from aprt_tools.model_bin import reader
        from aprt_tools.model_bin.writer import serialise

        a = converted(tiny(), 3)
        b = converted(tiny(pose_max=(120.0, 40.0, 2.5)), 4)
        cfg_c = tiny(pose_max=(90.0, 60.0, 3.5))
        cfg_c.pose_min = (-10.0, 5.0, 0.5)
        c = converted(cfg_c, 5)
        graph, meta = build([a, b, c], ["a", "b", "c"])
        meta["uncertainty"] = [1.0, 1.0]
        blob = serialise(graph, meta)
        got_meta = reader.read(blob)[1]
        np.testing.assert_allclose(got_meta["pose_min"], [-10.0, 0.0, 0.0])
        np.testing.assert_allclose(got_meta["pose_max"], [120.0, 60.0, 3.5])
        self.assertEqual(sum(op.name.endswith(":rebound") for op in reader.read(blob)[0].ops), 3)
        x = np.random.default_rng(5).standard_normal(got_meta["input_shape"]).astype(np.float32)

        def metres(blob_):
            from aprt_tools.ensemble_merge import merge

            m = reader.read(blob_)[1]
            lo, hi = np.asarray(m["pose_min"]), np.asarray(m["pose_max"])
            y = merge(engine_output(blob_, x).astype(np.float64)[None])[0][0]
            return y[:3] * (hi - lo) + lo, np.exp(y[7:10]) * (hi - lo), y[10:13]

        members = [metres(m) for m in (a, b, c)]
        pos, sigma, rot = metres(blob)
        np.testing.assert_allclose(pos, np.mean([m[0] for m in members], axis=0), rtol=1e-5)
        np.testing.assert_allclose(sigma, np.exp(np.mean([np.log(m[1]) for m in members], axis=0)),
                                   rtol=1e-4)
        np.testing.assert_allclose(rot, np.mean([m[2] for m in members], axis=0), atol=1e-5)
        third = extract(blob, 2)
        np.testing.assert_allclose(reader.read(third)[1]["pose_min"], cfg_c.pose_min, atol=1e-4)
        np.testing.assert_allclose(reader.read(third)[1]["pose_max"], cfg_c.pose_max, atol=1e-4)
        self.assertFalse(any("rebound" in op.name for op in reader.read(third)[0].ops))
        np.testing.assert_array_equal(engine_output(third, x), engine_output(c, x))

    def test_merge_turns_quaternions_to_one_sign_and_measures_the_spread(self):
        """The numbers of tests/unit/ensemble_merge_test.cc: the runtime and the
        calibration merge alike."""
        from aprt_tools.confidence import sigmas
        from aprt_tools.ensemble_merge import merge

        s = np.log(0.01)
        a = [0.45, 0.5, 0.49, 1.0, 0.0, 0.0, 0.0, s, s, s, s, s, s]
        # The same rotation turned 0.2 rad about z, written as -q (its sign
        # flipped, as a network trained apart may write it), and longer.
        b = [0.55, 0.5, 0.51, -2 * np.cos(0.1), 0.0, 0.0, -2 * np.sin(0.1), s, s, s, s, s, s]
        merged, position_sd, rotation_sd = merge(np.array([a + b]))
        np.testing.assert_allclose(merged[0, :3], [0.5, 0.5, 0.5], rtol=1e-6)
        # Member b is the reference (the larger norm); a is turned to its sign.
        np.testing.assert_allclose(merged[0, 3:7], [-(1 + 2 * np.cos(0.1)) / 2, 0, 0,
                                                    -np.sin(0.1)], rtol=1e-6)
        np.testing.assert_allclose(position_sd[0], [0.05, 0.0, 0.01], atol=1e-7)
        self.assertAlmostEqual(rotation_sd[0, 0], 0.0)
        # The merged rotation lies between the two; each is ~0.1 rad away from it.
        self.assertGreater(rotation_sd[0, 2], 0.09)
        self.assertLess(rotation_sd[0, 2], 0.11)
        sp, sr = sigmas(np.array([a + b]), (-100, 50, 0), (300, 250, 10), 2.0, 0.5)
        own = np.sqrt(2.0) * 0.01
        self.assertAlmostEqual(sp[0, 0], 2.0 * np.hypot(own, 0.05) * 400.0, places=4)
        self.assertAlmostEqual(sp[0, 1], 2.0 * own * 200.0, places=4)
        self.assertAlmostEqual(sr[0, 2], 0.5 * np.hypot(own, rotation_sd[0, 2]), places=6)
        # One network: as it is.
        one, p0, r0 = merge(np.array([a]))
        np.testing.assert_allclose(one[0], a)
        self.assertEqual(float(np.abs(p0).max() + np.abs(r0).max()), 0.0)

    def test_refuses_an_ensemble_as_a_member_and_to_torch_refuses_it(self):
        from aprt_tools.ensemble import EnsembleError, build
        from aprt_tools.model_bin import to_torch
        from aprt_tools.model_bin.writer import serialise

        a, b = converted(tiny(), 3), converted(tiny(), 4)
        graph, meta = build([a, b], ["a", "b"])
        meta["uncertainty"] = [1.0, 1.0]
        both = serialise(graph, meta)
        with self.assertRaisesRegex(EnsembleError, "itself an ensemble"):
            build([both, a], ["both", "a"])
        with self.assertRaisesRegex(to_torch.ToTorchError, "one of its members"):
            to_torch.load(both)

    def test_a_member_extracted_computes_what_it_did(self):
        from aprt_tools.ensemble import EnsembleError, build, extract
        from aprt_tools.model_bin import reader
        from aprt_tools.model_bin.writer import serialise

        a, b = converted(tiny(), 3), converted(tiny(), 4)
        graph, meta = build([a, b], ["a", "b"])
        meta["uncertainty"] = [1.0, 1.0]
        both = serialise(graph, meta)
        second = extract(both, 1)
        got, want = reader.read(second), reader.read(b)
        self.assertNotIn("ensemble", got[1])
        self.assertEqual([t.name for t in got[0].tensors], [t.name for t in want[0].tensors])
        self.assertEqual([op.name for op in got[0].ops], [op.name for op in want[0].ops])
        shape = want[1]["input_shape"]
        x = np.random.default_rng(4).standard_normal(shape).astype(np.float32)
        np.testing.assert_array_equal(engine_output(second, x), engine_output(b, x))
        with self.assertRaisesRegex(EnsembleError, "members 0 to 1"):
            extract(both, 2)
        with self.assertRaisesRegex(EnsembleError, "not an ensemble"):
            extract(a, 0)

    def test_refuses_int8_members(self):
        from aprt_tools.convert.quantize import quantize_model
        from aprt_tools.ensemble import EnsembleError, build
        from aprt_tools.model_bin import reader
        import os
        import tempfile

        a = converted(tiny(), 3)
        shape = reader.read(a)[1]["input_shape"]
        with tempfile.TemporaryDirectory() as d:
            calib = os.path.join(d, "calibration.npy")
            np.save(calib, np.random.default_rng(1).standard_normal([4] + shape[1:])
                    .astype(np.float32))
            q, _ = quantize_model(a, calib, frames=4)
        with self.assertRaisesRegex(EnsembleError, "int8 file"):
            build([q, a], ["q", "a"])

    def test_calibration_is_fitted_on_the_members_mean(self):
        from aprt_tools import ensemble
        from aprt_tools.confidence import fit
        from aprt_tools.model_bin import reader

        members = [converted(tiny(), seed) for seed in (3, 4)]
        rng = np.random.default_rng(7)
        n = 200
        raws = [np.concatenate([rng.uniform(0.2, 0.8, (n, 3)), rng.standard_normal((n, 4)),
                                rng.uniform(-4, -2, (n, 6))], axis=1) for _ in members]
        pos = rng.uniform(20, 40, (n, 3))
        quat = np.tile([1.0, 0.0, 0.0, 0.0], (n, 1))
        cfg = tiny()
        saved = ensemble.member_outputs
        ensemble.member_outputs = lambda files, folder: (raws, pos, quat, cfg)
        try:
            blob, report = ensemble.calibrated(members, ["a", "b"], "val")
        finally:
            ensemble.member_outputs = saved
        # The members side by side, as the graph outputs them: their spread is
        # part of the sigma the calibration scales.
        outputs = np.concatenate(raws, axis=1)
        want = fit(outputs, pos, quat, cfg.pose_min, cfg.pose_max)
        np.testing.assert_allclose(reader.read(blob)[1]["uncertainty"], want, rtol=1e-6)
        self.assertNotEqual(want, fit(np.mean(raws, axis=0), pos, quat, cfg.pose_min,
                                      cfg.pose_max))
        self.assertIn("2 members", report)


if __name__ == "__main__":
    unittest.main()
