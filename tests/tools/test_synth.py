"""aprt_synth (tools/synth): deterministic drives, the lighting presets, refusals;
and the trainer on several drives with a separate validation drive.

APRT_SYNTH names the binary (the ctest entry sets it)."""

import json
import os
import subprocess
import tempfile
import unittest

import numpy as np

from aprt_tools.dataset import load_image, read_poses

SYNTH = os.environ.get("APRT_SYNTH", "")
LIGHTINGS = ("day", "overcast", "morning", "noon", "haze", "dusk", "night")


def read(path):
    with open(path) as f:
        return f.read()


def synth(out, *args, check=True):
    r = subprocess.run([SYNTH, "--out", out, "--width", "48", "--height", "32", *args],
                       capture_output=True, text=True)
    if check and r.returncode != 0:
        raise AssertionError(f"aprt_synth {' '.join(args)} failed: {r.stderr}")
    return r


@unittest.skipUnless(os.access(SYNTH, os.X_OK), "APRT_SYNTH does not name the aprt_synth binary")
class Synth(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        self.addCleanup(self.dir.cleanup)

    def path(self, name):
        return os.path.join(self.dir.name, name)

    def test_same_arguments_give_the_same_drive(self):
        for name in ("a", "b"):
            synth(self.path(name), "--split", "test", "--route-seed", "5", "--frames", "6",
                  "--lighting", "morning", "--threads", "1" if name == "a" else "2")
        self.assertEqual(read(self.path("a/poses.txt")), read(self.path("b/poses.txt")))
        for name, _, _ in read_poses(self.path("a")):
            np.testing.assert_array_equal(load_image(self.path("a"), name),
                                          load_image(self.path("b"), name))

    def test_every_lighting_renders_the_same_places_differently(self):
        images = {}
        for light in LIGHTINGS:
            synth(self.path(light), "--split", "test", "--frames", "3", "--lighting", light)
            meta = json.loads(read(self.path(f"{light}/dataset.json")))
            self.assertEqual(meta["lighting"], light)
            images[light] = load_image(self.path(light), "images/000002.png").astype(float)
        poses = {light: read(self.path(f"{light}/poses.txt")) for light in LIGHTINGS}
        self.assertEqual(len(set(poses.values())), 1, "lighting must not move the route")
        for i, a in enumerate(LIGHTINGS):
            for b in LIGHTINGS[i + 1:]:
                self.assertGreater(np.abs(images[a] - images[b]).mean(), 3.0, f"{a} vs {b}")
        # Night: darker than any other light, its street lights still visible.
        for light in LIGHTINGS[:-1]:
            self.assertLess(images["night"].mean(), images[light].mean() - 20, light)
        self.assertGreater(images["night"].max(), 200, "no lit street light in view")

    def test_sun_moves_the_shadows_not_the_route(self):
        # The day preset's sun (135, 50) against the same colours with a low sun
        # from another side: the same poses, a different image, both recorded.
        synth(self.path("preset"), "--split", "test", "--frames", "3", "--lighting", "day")
        synth(self.path("low"), "--split", "test", "--frames", "3", "--lighting", "day",
              "--sun", "245,12")
        self.assertEqual(read(self.path("preset/poses.txt")), read(self.path("low/poses.txt")))
        a = load_image(self.path("preset"), "images/000002.png").astype(float)
        b = load_image(self.path("low"), "images/000002.png").astype(float)
        self.assertGreater(np.abs(a - b).mean(), 3.0)
        meta = json.loads(read(self.path("low/dataset.json")))
        self.assertEqual(meta["sun_deg"], [245.0, 12.0])
        self.assertIn("--sun 245,12", meta["command"])
        self.assertIsNone(json.loads(read(self.path("preset/dataset.json")))["sun_deg"])
        for value in ("245,2", "400,20", "245"):
            r = synth(self.path("bad"), "--sun", value, check=False)
            self.assertEqual(r.returncode, 2, value)
            self.assertIn("--sun", r.stderr)

    def test_training_routes_cover_every_street_both_ways(self):
        synth(self.path("t"), "--split", "train", "--route-seed", "3", "--spacing", "5",
              "--lane-jitter", "0.8")
        meta = json.loads(read(self.path("t/dataset.json")))
        self.assertAlmostEqual(meta["lane_jitter_m"], 0.8)
        poses = read_poses(self.path("t"))
        xy = np.stack([p[:2] for _, p, _ in poses])
        heading = np.array([2 * np.arctan2(q[3], q[0]) for _, _, q in poses])
        # Every street segment's midpoint is passed in both directions.
        n, block = 5, 50.0
        for i in range(n):
            for j in range(n - 1):
                for mid, along in (((i * block, (j + 0.5) * block), np.pi / 2),
                                   (((j + 0.5) * block, i * block), 0.0)):
                    near = np.hypot(xy[:, 0] - mid[0], xy[:, 1] - mid[1]) < 6.0
                    dirs = np.cos(heading[near] - along)
                    self.assertTrue((dirs > 0.9).any() and (dirs < -0.9).any(),
                                    f"street through {mid} not driven both ways")

    def test_mounting_and_lidar_options(self):
        synth(self.path("m"), "--frames", "2", "--camera-mount", "1.0,0.2,2.0,5", "--lidar",
              "--beams", "4", "--azimuths", "90", "--lidar-range", "40", "--lidar-noise", "0",
              "--lidar-mount", "0,0,2.5")
        meta = json.loads(read(self.path("m/dataset.json")))
        self.assertEqual(meta["camera_to_base_link"], {"xyz": [1.0, 0.2, 2.0], "rpy_deg": [0, 5, 0]})
        self.assertEqual(meta["lidar_to_base_link"]["xyz"], [0.0, 0.0, 2.5])
        self.assertEqual((meta["beams"], meta["azimuths"], meta["lidar_range_m"]), (4, 90, 40.0))
        cam = read_poses(self.path("m"))[0][1]
        lidar = read_poses(self.path("m"), "lidar_poses.txt")[0][1]
        self.assertAlmostEqual(cam[2], 2.0, places=3)
        self.assertAlmostEqual(lidar[2], 2.5, places=3)
        pts = np.fromfile(self.path("m/lidar/000000.bin"), np.float32).reshape(-1, 4)
        self.assertGreater(len(pts), 0)
        self.assertLessEqual(len(pts), 4 * 90)
        self.assertLessEqual(np.linalg.norm(pts[:, :3], axis=1).max(), 40.0 + 1e-3)

    def test_scans_only_are_the_same_scans(self):
        lidar = ("--split", "test", "--route-seed", "3", "--frames", "3", "--lidar", "--beams", "4",
                 "--azimuths", "64")
        synth(self.path("both"), *lidar)
        synth(self.path("scans"), *lidar, "--no-images")
        self.assertFalse(os.path.exists(self.path("scans/images")))
        self.assertEqual(read(self.path("both/lidar_poses.txt")),
                         read(self.path("scans/lidar_poses.txt")))
        self.assertEqual(read(self.path("both/poses.txt")), read(self.path("scans/poses.txt")))
        for k in range(3):
            name = f"lidar/{k:06d}.bin"
            with open(self.path("both/" + name), "rb") as a, open(self.path("scans/" + name),
                                                                  "rb") as b:
                self.assertEqual(a.read(), b.read())
        meta = json.loads(read(self.path("scans/dataset.json")))
        self.assertFalse(meta["images"])
        self.assertIn("--no-images", meta["command"])
        r = synth(self.path("none"), "--frames", "1", "--no-images", check=False)
        self.assertEqual(r.returncode, 2)
        self.assertIn("--no-images without --lidar", r.stderr)

    def test_view_jitter_moves_every_frame_within_its_bounds(self):
        synth(self.path("plain"), "--split", "test", "--route-seed", "9", "--frames", "40")
        synth(self.path("jit"), "--split", "test", "--route-seed", "9", "--frames", "40",
              "--view-jitter", "1.5,0.3,3,10")
        a, b = read_poses(self.path("plain")), read_poses(self.path("jit"))
        dxy = np.array([np.hypot(*(pb[:2] - pa[:2])) for (_, pa, _), (_, pb, _) in zip(a, b)])
        dz = np.array([pb[2] - pa[2] for (_, pa, _), (_, pb, _) in zip(a, b)])
        dyaw = np.degrees([abs(2 * np.arctan2(qb[3], qb[0]) - 2 * np.arctan2(qa[3], qa[0]))
                           for (_, _, qa), (_, _, qb) in zip(a, b)])
        self.assertGreater(dxy.mean(), 0.3)
        self.assertLessEqual(dxy.max(), 1.5 + 1.2 * np.radians(10) + 0.05)  # lateral + yaw lever
        self.assertLessEqual(np.abs(dz).max(), 0.3 + 1e-3)
        self.assertLessEqual(dyaw.max(), 10.0 + 3.5)  # yaw, plus the pitch's share of it
        meta = json.loads(read(self.path("jit/dataset.json")))
        self.assertEqual(meta["view_jitter"], {"lateral_m": 1.5, "height_m": 0.3, "pitch_deg": 3.0,
                                               "yaw_deg": 10.0})
        for args, message in ((["--view-jitter", "3,0,0,0"], "out of range"),
                              (["--view-jitter", "1,2,3"], "4 comma-separated numbers")):
            r = synth(self.path("bad"), *args, check=False)
            self.assertEqual(r.returncode, 2, args)
            self.assertIn(message, r.stderr)

    def test_dataset_json_regenerates_the_drive(self):
        synth(self.path("a"), "--split", "test", "--route-seed", "4", "--frames", "5",
              "--lighting", "noon", "--view-jitter", "0.5,0.1,1,2", "--max-length", "80",
              "--sun", "200.5,17")
        meta = json.loads(read(self.path("a/dataset.json")))
        self.assertEqual((meta["frames_limit"], meta["max_length_m"], meta["spacing_m"]),
                         (5, 80.0, 1.0))
        r = subprocess.run([SYNTH, "--out", self.path("b")] + meta["command"].split()[1:],
                           capture_output=True, text=True)
        self.assertEqual(r.returncode, 0, r.stderr)
        self.assertEqual(read(self.path("a/poses.txt")), read(self.path("b/poses.txt")))
        np.testing.assert_array_equal(load_image(self.path("a"), "images/000004.png"),
                                      load_image(self.path("b"), "images/000004.png"))

    def test_help_lists_the_options_and_the_data_split(self):
        r = subprocess.run([SYNTH, "--help"], capture_output=True, text=True)
        self.assertEqual(r.returncode, 0)
        for word in ("--view-jitter", "--lighting", "--sun", "--camera-mount", "training",
                     "validation",
                     "test", "[1.0]"):
            self.assertIn(word, r.stdout)

    def test_bad_arguments_are_refused(self):
        for args, message in ((["--lighting", "sunset"], "unknown lighting 'sunset'"),
                              (["--frames", "1O"], "--frames '1O' is not a valid number"),
                              (["--split", "val"], "unknown split 'val'"),
                              (["--lane-jitter", "3"], "would leave the 2.5 m lane"),
                              (["--camera-mount", "1,0,2"],
                               "--camera-mount '1,0,2' is not 4 comma-separated numbers")):
            r = synth(self.path("bad"), *args, check=False)
            self.assertEqual(r.returncode, 2, args)
            self.assertIn(message, r.stderr)


@unittest.skipUnless(os.access(SYNTH, os.X_OK), "APRT_SYNTH does not name the aprt_synth binary")
class TrainOnDrives(unittest.TestCase):
    """train(): several drives together, errors on a separate validation drive."""

    def test_two_drives_and_a_validation_drive(self):
        import torch

        from aprt_tools.train import train

        with tempfile.TemporaryDirectory() as d:
            for name, light, seed in (("day", "day", "1"), ("noon", "noon", "2"),
                                      ("val", "haze", "3")):
                synth(os.path.join(d, name), "--split", "test", "--route-seed", seed,
                      "--frames", "12", "--lighting", light)
            logs = []
            train([os.path.join(d, "day"), os.path.join(d, "noon")], os.path.join(d, "run"),
                  size=32, minutes=0.02, batch=4, hidden=32, layers=1, val=os.path.join(d, "val"),
                  log=logs.append)
            self.assertTrue(any("24 frames" in line for line in logs), logs)
            self.assertTrue(any("validation drive" in line and "12 frames" in line
                                for line in logs), logs)
            cfg = json.loads(read(os.path.join(d, "run", "model.json")))
            self.assertEqual(cfg["extra"]["data"], "day,noon")
            self.assertEqual(cfg["extra"]["validation"], "val")
            self.assertTrue(all(np.isfinite(cfg["extra"]["val_error"])))
            # The run exports its best validation point (best.pth), which the
            # model's recorded error is.
            best = torch.load(os.path.join(d, "run", "best.pth"), map_location="cpu")
            rows = json.loads(read(os.path.join(d, "run", "train_log.json")))
            self.assertEqual(best["val_pos_median"], min(r["val_pos_median"] for r in rows))
            self.assertEqual(cfg["extra"]["val_error"][0], best["val_pos_median"])
            self.assertTrue(any("best validation point" in line for line in logs), logs)
            # A second phase from the checkpoint keeps the configuration and the bounds.
            logs = []
            train([os.path.join(d, "noon")], os.path.join(d, "phase2"), minutes=0.02, batch=4,
                  val=os.path.join(d, "val"), init=os.path.join(d, "run", "checkpoint.pth"),
                  log=logs.append)
            self.assertTrue(any("continuing from" in line for line in logs), logs)
            cfg2 = json.loads(read(os.path.join(d, "phase2", "model.json")))
            for key in ("pose_min", "pose_max", "hidden_dim", "image_size", "enc_layers"):
                self.assertEqual(cfg2[key], cfg[key], key)
            with open(os.path.join(d, "junk.pth"), "wb") as f:
                torch.save({"weights": 1}, f)
            with self.assertRaisesRegex(ValueError, "neither a checkpoint"):
                train([os.path.join(d, "noon")], os.path.join(d, "phase3"), minutes=0.01,
                      init=os.path.join(d, "junk.pth"))
            # Two data-parallel workers: the same files, the weights checked equal at the end.
            train([os.path.join(d, "day")], os.path.join(d, "ddp"), size=32, minutes=0.05,
                  batch=4, hidden=32, layers=1, val=os.path.join(d, "val"), workers=2)
            rows = json.loads(read(os.path.join(d, "ddp", "train_log.json")))
            self.assertGreater(rows[-1]["step"], 0)
            self.assertTrue(os.path.exists(os.path.join(d, "ddp", "checkpoint.pth")))
            self.assertFalse([n for n in os.listdir(os.path.join(d, "ddp")) if "workers" in n])
            with self.assertRaisesRegex(ValueError, "does not split over 3 workers"):
                train([os.path.join(d, "day")], os.path.join(d, "ddp3"), batch=4, workers=3)
            with self.assertRaisesRegex(ValueError, "no training sequence"):
                train([], os.path.join(d, "run2"), size=32, minutes=0.01)
            with self.assertRaises(OSError):
                train([os.path.join(d, "day")], os.path.join(d, "run3"), size=32, minutes=0.01,
                      val=os.path.join(d, "missing"))


if __name__ == "__main__":
    unittest.main()
