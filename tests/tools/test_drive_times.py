"""aprt_tools drive-times: a speed profile along a sequence's poses."""

import math
import os
import tempfile
import unittest

import numpy as np

from aprt_tools.drive_times import drive_times, speed_profile, write_drive_times


def l_shaped(folder, radius=5.0):
    """100 m east, a quarter circle of `radius` to the north, 100 m north; 1 m apart."""
    pts = [(x, 0.0) for x in np.arange(0.0, 100.0, 1.0)]
    for a in np.arange(0.0, math.pi / 2, 1.0 / radius):
        pts.append((100.0 + radius * math.sin(a), radius - radius * math.cos(a)))
    pts += [(100.0 + radius, radius + y) for y in np.arange(0.0, 100.0, 1.0)]
    with open(os.path.join(folder, "poses.txt"), "w") as f:
        f.write("# name x y z qw qx qy qz\n")
        for k, (x, y) in enumerate(pts):
            f.write(f"images/{k:06d}.png {x:.4f} {y:.4f} 1.5 1 0 0 0\n")
    return np.array(pts)


class DriveTimes(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        self.addCleanup(self.dir.cleanup)

    def test_slow_in_the_corner_fast_on_the_straights(self):
        xy = l_shaped(self.dir.name, radius=5.0)
        v = speed_profile(xy, 13.9, 3.0, 2.0)
        corner = np.argmin(v)
        self.assertTrue(95 <= corner <= 110, corner)
        self.assertAlmostEqual(v[corner], math.sqrt(3.0 * 5.0), delta=0.6)  # sqrt(a r)
        self.assertAlmostEqual(v[30], 13.9)
        self.assertTrue(np.all(np.abs(np.diff(v ** 2)) <= 2 * 2.0 * 1.0 + 1e-6))  # a <= 2 m/s^2

    def test_times_file(self):
        l_shaped(self.dir.name)
        path, _ = write_drive_times(self.dir.name)
        lines = open(path).read().split("\n")[:-1]
        names, t = drive_times(self.dir.name)
        self.assertEqual(len(lines), len(names))
        self.assertEqual(lines[0], "images/000000.png 0.000000")
        self.assertTrue(np.all(np.diff(t) > 0))
        self.assertAlmostEqual(t[1], 1.0 / 13.9, places=4)
        with self.assertRaisesRegex(ValueError, "must be positive"):
            drive_times(self.dir.name, max_speed=0)


if __name__ == "__main__":
    unittest.main()
