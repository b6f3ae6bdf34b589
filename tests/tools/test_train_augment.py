"""The trainer's colour augmentation (train_data.augment): lighting and sensor
changes within [0, 1], nothing at strength 0, reproducible from its generator,
and a white balance that reaches a low sun's warm cast."""

import unittest

import torch

from aprt_tools.train_data import augment


def grey(n=256, side=6):
    return torch.full((n, 3, side, side), 0.5)


class Augment(unittest.TestCase):
    def test_strength_zero_is_the_image(self):
        x = torch.rand(5, 3, 7, 9)
        self.assertTrue(torch.equal(augment(x, torch.Generator().manual_seed(1), 0.0), x))

    def test_range_shape_and_generator(self):
        x = torch.rand(9, 3, 5, 11)
        a = augment(x, torch.Generator().manual_seed(3))
        b = augment(x, torch.Generator().manual_seed(3))
        self.assertEqual(a.shape, x.shape)
        self.assertTrue(torch.equal(a, b), "the same generator state must give the same frames")
        self.assertGreaterEqual(float(a.min()), 0.0)
        self.assertLessEqual(float(a.max()), 1.0)
        self.assertFalse(torch.equal(a, x))

    def test_white_balance_reaches_warm_and_cool_casts(self):
        # A grey frame's red/blue ratio after augmentation: the independent channel
        # gains and the haze's colour alone stayed within 0.58..1.96 on these
        # frames; the correlated temperature shift carries some past 2.4 (a low
        # sun) and some below 0.45 (shade).
        y = augment(grey(), torch.Generator().manual_seed(0))
        ratio = y[:, 0].mean(dim=(1, 2)) / y[:, 2].mean(dim=(1, 2)).clamp_min(1e-3)
        self.assertGreater(float(ratio.max()), 2.4)
        self.assertLess(float(ratio.min()), 0.45)
        # The middle of the distribution stays near neutral.
        self.assertLess(abs(float(ratio.median()) - 1.0), 0.25)


if __name__ == "__main__":
    unittest.main()
