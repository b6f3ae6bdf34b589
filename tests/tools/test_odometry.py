"""aprt_tools odometry: the speed and yaw rate a sequence's vehicle would report."""

import json
import math
import os
import tempfile
import unittest

import numpy as np

from aprt_tools.odometry import odometry, write_odometry

CAMERA_X = 1.2


def circle_drive(folder, radius=20.0, n=200, times=None):
    """base_link on a circle (1 m apart), the camera CAMERA_X ahead of it."""
    base = []
    with open(os.path.join(folder, "poses.txt"), "w") as f:
        for k in range(n):
            a = k / radius
            x, y, yaw = radius * math.sin(a), radius * (1 - math.cos(a)), a
            base.append((x, y, yaw))
            cx, cy = x + CAMERA_X * math.cos(yaw), y + CAMERA_X * math.sin(yaw)
            f.write(f"images/{k:06d}.png {cx:.6f} {cy:.6f} 1.5 {math.cos(yaw / 2):.9f} 0 0 "
                    f"{math.sin(yaw / 2):.9f}\n")
    with open(os.path.join(folder, "dataset.json"), "w") as f:
        json.dump({"camera_to_base_link": {"xyz": [CAMERA_X, 0, 1.5]}}, f)
    if times is not None:
        with open(os.path.join(folder, "times.txt"), "w") as f:
            for k, t in enumerate(times):
                f.write(f"images/{k:06d}.png {t:.6f}\n")
    return np.array(base)


def integrate(samples):
    """The base's poses from zero-order-hold arcs (what drivers/input/odometry.h does)."""
    x = y = yaw = 0.0
    out = [(x, y, yaw)]
    for (t0, v, w), (t1, _, _) in zip(samples, samples[1:]):
        h = t1 - t0
        if abs(w * h) < 1e-12:
            x, y = x + v * h * math.cos(yaw), y + v * h * math.sin(yaw)
        else:
            x += v / w * (math.sin(yaw + w * h) - math.sin(yaw))
            y += v / w * (math.cos(yaw) - math.cos(yaw + w * h))
        yaw += w * h
        out.append((x, y, yaw))
    return np.array(out)


class Odometry(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        self.addCleanup(self.dir.cleanup)

    def test_without_errors_it_integrates_back_to_the_base(self):
        base = circle_drive(self.dir.name)
        s = odometry(self.dir.name, speed_scale=0, speed_noise=0, yaw_rate_bias_dps=0,
                     yaw_rate_noise_dps=0)
        self.assertEqual(s.shape, (200, 3))
        self.assertAlmostEqual(s[1, 0], 0.04)  # 25 Hz without times.txt
        self.assertAlmostEqual(s[10, 1], 25.0, places=4)  # 1 m per frame
        self.assertAlmostEqual(s[10, 2], 25.0 / 20.0, places=4)  # v / r
        track = integrate(s)
        np.testing.assert_allclose(track[:, :2], base[:, :2], atol=1e-4)

    def test_the_camera_offset_matters(self):
        circle_drive(self.dir.name)
        # Taken as the base itself, the camera ahead would drift off the circle.
        s = odometry(self.dir.name, speed_scale=0, speed_noise=0, yaw_rate_bias_dps=0,
                     yaw_rate_noise_dps=0, camera=(0.0, 0.0))
        s_true = odometry(self.dir.name, speed_scale=0, speed_noise=0, yaw_rate_bias_dps=0,
                          yaw_rate_noise_dps=0)
        np.testing.assert_allclose(s[:, 1], s_true[:, 1], atol=1e-3)  # same speed on a circle
        np.testing.assert_allclose(s[:, 2], s_true[:, 2], atol=1e-9)  # same yaw rate

    def test_errors_stay_within_their_bounds_and_the_clock_is_times_txt(self):
        times = np.cumsum(np.full(200, 0.1)) - 0.1
        circle_drive(self.dir.name, times=times)
        path, s = write_odometry(self.dir.name, seed=3, speed_scale=0.02, speed_noise=0,
                                 yaw_rate_bias_dps=0.5, yaw_rate_noise_dps=0)
        np.testing.assert_allclose(s[:, 0], times, atol=1e-9)
        self.assertTrue(np.all(np.abs(s[:-1, 1] / 10.0 - 1) <= 0.02 + 1e-6))  # 1 m per 0.1 s
        bias = s[:-1, 2] - 1.0 / 20.0 * 10.0
        self.assertTrue(np.all(np.abs(bias) <= math.radians(0.5) + 1e-9))
        lines = open(path).read().split("\n")
        self.assertTrue(lines[0].startswith("# seconds speed_mps yaw_rate_radps"))
        self.assertEqual(len(lines[1].split()), 3)
        with self.assertRaisesRegex(ValueError, "must not be negative"):
            odometry(self.dir.name, speed_noise=-1)


if __name__ == "__main__":
    unittest.main()
