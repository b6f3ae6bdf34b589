"""The reference model loads upstream checkpoints: same keys, shapes, order."""

import os
import unittest

import torch

from aprt_tools.model.apr_transformer import AprConfig, AprTransformer
from aprt_tools.model.efficientnet import EfficientNet, same_padding

HERE = os.path.dirname(os.path.abspath(__file__))
KEYS = os.path.join(HERE, "..", "golden", "upstream", "upstream_state_dict_keys.txt")


def upstream_keys():
    out = []
    for line in open(KEYS):
        if line.startswith("#") or not line.strip():
            continue
        key, shape, dtype = line.split()
        out.append((key, shape, dtype))
    return out


class ReferenceModelTest(unittest.TestCase):
    def test_state_dict_matches_upstream(self):
        model = AprTransformer(AprConfig.named("full"))
        mine = [(k, "x".join(map(str, v.shape)) if v.dim() else "scalar",
                 str(v.dtype).replace("torch.", "")) for k, v in model.state_dict().items()]
        self.assertEqual(mine, upstream_keys())

    def test_upstream_style_checkpoint_loads_strictly(self):
        src = AprTransformer(AprConfig.named("full"))
        state = {k: v.clone() for k, v in src.state_dict().items()}
        dst = AprTransformer(AprConfig.named("full"))
        dst.load_state_dict(state, strict=True)
        x = torch.randn(1, 3, 64, 64)
        src.eval(), dst.eval()
        with torch.no_grad():
            self.assertTrue(torch.equal(src(x), dst(x)))

    def test_tf_same_padding_is_asymmetric_on_stride_2(self):
        self.assertEqual(same_padding(224, 3, 2), (0, 1))
        self.assertEqual(same_padding(224, 5, 2), (1, 2))
        self.assertEqual(same_padding(112, 3, 1), (1, 1))
        self.assertEqual(same_padding(64, 5, 1), (2, 2))

    def test_larger_backbones_build(self):
        for variant, channels in (("efficientnet-b1", (40, 112)), ("efficientnet-b2", (48, 120)),
                                  ("efficientnet-b3", (48, 136))):
            net = EfficientNet(variant, 64)
            self.assertEqual(net.endpoint_channels(), channels, variant)
            r3, r4 = net.endpoints(torch.randn(1, 3, 64, 64))
            self.assertEqual((r3.shape[1], r4.shape[1]), channels)
            self.assertEqual((r3.shape[2], r4.shape[2]), (8, 4))

    def test_output_shape_and_config_round_trip(self):
        cfg = AprConfig.named("tiny")
        self.assertEqual(AprConfig.from_json(cfg.to_json()), cfg)
        model = AprTransformer(cfg).eval()
        with torch.no_grad():
            self.assertEqual(tuple(model(torch.randn(2, 3, 64, 64)).shape), (2, 7))


if __name__ == "__main__":
    unittest.main()
