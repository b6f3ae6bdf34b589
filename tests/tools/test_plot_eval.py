"""plot-eval: reads `aprt eval --csv` output, draws a PNG, refuses foreign files."""

import os
import tempfile
import unittest

from aprt_tools.plot_eval import EvalCsvError, plot_eval, read_eval_csv

HEADER = ("name,x,y,z,qw,qx,qy,qz,gt_x,gt_y,gt_z,gt_qw,gt_qx,gt_qy,gt_qz,"
          "position_error_m,orientation_error_deg,flags\n")


def write_csv(path, n=40, offset=0.5):
    with open(path, "w") as f:
        f.write(HEADER)
        for i in range(n):
            gx, gy = 10.0 + i, 5.0 + 0.1 * i * i
            f.write(f"images/{i:06d}.png,{gx + offset},{gy},1.5,1,0,0,0,{gx},{gy},1.5,1,0,0,0,"
                    f"{offset},{0.1 * (i % 5)},{0 if i % 7 else 16384}\n")


class PlotEval(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        self.addCleanup(self.dir.cleanup)

    def path(self, name):
        return os.path.join(self.dir.name, name)

    def test_one_and_two_panels(self):
        write_csv(self.path("fp32.csv"))
        write_csv(self.path("int8.csv"), offset=0.7)
        plot_eval([self.path("fp32.csv")], self.path("one.png"))
        with open(self.path("dataset.json"), "w") as f:
            f.write('{"generator": "aprt_synth", "town_extent_m": 200.0, '
                    '"street_spacing_m": 50.0, "road_width_m": 10.0}')
        plot_eval([self.path("fp32.csv"), self.path("int8.csv")], self.path("two.png"),
                  labels=["fp32", "int8"], title="demo", dataset=self.path("dataset.json"))
        for name in ("one.png", "two.png"):
            with open(self.path(name), "rb") as f:
                self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n")
        self.assertAlmostEqual(float(read_eval_csv(self.path("int8.csv"))["position_error_m"][3]),
                               0.7)

    def test_foreign_and_empty_files_are_refused(self):
        with open(self.path("other.csv"), "w") as f:
            f.write("a,b\n1,2\n")
        with self.assertRaisesRegex(EvalCsvError, "missing column"):
            read_eval_csv(self.path("other.csv"))
        with open(self.path("empty.csv"), "w") as f:
            f.write(HEADER)
        with self.assertRaisesRegex(EvalCsvError, "no frames"):
            read_eval_csv(self.path("empty.csv"))

    def test_the_published_pose(self):
        with open(self.path("f.csv"), "w") as f:
            f.write(HEADER.strip() + ",published_x,published_y,published_yaw_deg,"
                    "published_position_error_m,published_orientation_error_deg\n")
            for i in range(20):
                f.write(f"images/{i:06d}.png,{10 + i + 3},5,1.5,1,0,0,0,{10 + i},5,1.5,1,0,0,0,"
                        f"3,1,0,{10 + i + 0.5},5,0,0.5,0.2\n")
        d = read_eval_csv(self.path("f.csv"), published=True)
        self.assertAlmostEqual(float(d["position_error_m"][0]), 0.5)
        self.assertAlmostEqual(float(d["x"][0]), 10.5)
        self.assertAlmostEqual(float(read_eval_csv(self.path("f.csv"))["x"][0]), 13.0)
        plot_eval([self.path("f.csv")], self.path("p.png"), published=True)
        self.assertTrue(os.path.getsize(self.path("p.png")) > 1000)
        write_csv(self.path("old.csv"))
        with self.assertRaisesRegex(EvalCsvError, "no published_"):
            read_eval_csv(self.path("old.csv"), published=True)

    def test_label_count_must_match(self):
        write_csv(self.path("a.csv"))
        with self.assertRaisesRegex(EvalCsvError, "labels"):
            plot_eval([self.path("a.csv")], self.path("x.png"), labels=["a", "b"])


if __name__ == "__main__":
    unittest.main()
