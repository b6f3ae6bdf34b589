"""An ensemble file (aprt_tools/ensemble.py) computes the mean of its members'
outputs (engine_ir's statement of the engine; the C++ engine against PyTorch
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
        want = np.mean([engine_output(m, x) for m in members], axis=0)
        got = engine_output(blob, x)
        self.assertEqual(got.shape, (13,))
        np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-6)
        # The members differ, or the test would prove nothing.
        self.assertGreater(np.abs(engine_output(members[0], x) - want).max(), 1e-3)

    def test_refuses_members_that_are_not_one_model(self):
        from aprt_tools.ensemble import EnsembleError, build

        a = converted(tiny(), 3)
        with self.assertRaisesRegex(EnsembleError, "pose_max differs"):
            build([a, converted(tiny(pose_max=(90.0, 50.0, 3.0)), 4)], ["a", "b"])
        with self.assertRaisesRegex(EnsembleError, "confidence outputs"):
            build([converted(tiny(uncertainty=False), 3), converted(tiny(uncertainty=False), 4)],
                  ["a", "b"])
        with self.assertRaisesRegex(EnsembleError, "2 to 8"):
            build([a], ["a"])

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
        want = fit(np.mean(raws, axis=0), pos, quat, cfg.pose_min, cfg.pose_max)
        np.testing.assert_allclose(reader.read(blob)[1]["uncertainty"], want, rtol=1e-6)
        self.assertIn("2 members", report)


if __name__ == "__main__":
    unittest.main()
