"""The trainer's colour augmentation (train_data.augment): lighting and sensor
changes within [0, 1], nothing at strength 0, reproducible from its generator,
a white balance that reaches a low sun's warm cast, and the optional hue and
saturation step (chroma) that keeps the luma."""

import unittest

import torch

from aprt_tools.train_data import _RGB_TO_YIQ, augment, chroma_matrices


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

    def test_chroma_off_keeps_the_random_stream(self):
        # Runs made before the option existed are reproduced bit for bit.
        x = torch.rand(6, 3, 5, 5)
        a = augment(x, torch.Generator().manual_seed(7))
        b = augment(x, torch.Generator().manual_seed(7), chroma=False)
        self.assertTrue(torch.equal(a, b))

    def test_chroma_matrices_keep_the_luma(self):
        hue = torch.tensor([0.0, 0.4, -0.4, 1.0])
        sat = torch.tensor([1.0, 1.3, 0.5, 0.0])
        m = chroma_matrices(hue, sat)
        self.assertTrue(torch.allclose(m[0], torch.eye(3), atol=1e-5))
        x = torch.rand(3, 50)
        luma = _RGB_TO_YIQ[0] @ x
        for k in range(4):
            self.assertTrue(torch.allclose(_RGB_TO_YIQ[0] @ (m[k] @ x), luma, atol=1e-5))
        grey_out = m[3] @ x  # saturation 0: every channel is the luma
        self.assertTrue(torch.allclose(grey_out, luma.expand(3, -1), atol=1e-5))

    def test_chroma_moves_the_hue(self):
        # A red facade: with chroma some frames come out nearly grey or with red
        # no longer the strongest channel, which the gains and white balance
        # alone (almost) never do.
        red = torch.zeros(400, 3, 4, 4)
        red[:, 0] = 0.8
        red[:, 1] = 0.2
        red[:, 2] = 0.2
        plain = augment(red, torch.Generator().manual_seed(2)).mean(dim=(2, 3))
        turned = augment(red, torch.Generator().manual_seed(2), chroma=True).mean(dim=(2, 3))
        grey_share = lambda c: float(((c.amax(1) - c.amin(1)) < 0.05).float().mean())
        not_red_share = lambda c: float((c.argmax(1) != 0).float().mean())
        self.assertLess(grey_share(plain), 0.01)
        self.assertGreater(grey_share(turned), 0.05)
        self.assertLess(not_red_share(plain), 0.01)
        self.assertGreater(not_red_share(turned), 0.03)
        self.assertGreaterEqual(float(turned.min()), 0.0)
        self.assertLessEqual(float(turned.max()), 1.0)

if __name__ == "__main__":
    unittest.main()
