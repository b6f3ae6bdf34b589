"""plot-timing: reads an `aprt run --timing` report and its CSV, refuses incomplete ones."""

import json
import os
import tempfile
import unittest

from aprt_tools.plot_timing import TimingReportError, plot_timing, read_report

STAGE = {"count": 3, "min": 1.0, "median": 2.0, "mean": 2.0, "p99": 3.0, "p99.9": 3.0, "max": 3.0}
REPORT = {"model": "m.aprt", "source": "d", "isa": "ref", "threads": 1, "duration_s": 1.0,
          "frames": {"captured": 3, "skipped": 0, "dropped_stale": 0, "poses": 3, "flagged": 0,
                     "deadline_misses": 0, "ring_full": 0, "source_restarts": 0, "timed": 3},
          "stages_ms": {k: STAGE for k in ("capture_to_inference", "inference",
                                          "inference_to_publish", "end_to_end")},
          "jitter": {"camera_period_ms": 100, "inference_deadline_ms": 200, "bound_ms": 102,
                     "p99.9_end_to_end_ms": 3, "within_bound": True},
          "memory": {"allocations_after_first_pose": 0, "peak_rss_kb": 1000}}


class PlotTiming(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.TemporaryDirectory()
        self.addCleanup(self.dir.cleanup)
        self.json = os.path.join(self.dir.name, "r.json")
        with open(self.json, "w") as f:
            json.dump(REPORT, f)

    def write_csv(self):
        with open(os.path.join(self.dir.name, "r.csv"), "w") as f:
            f.write("index,capture_ns,inference_start_ns,inference_end_ns,publish_ns\n")
            for i in range(3):
                c = i * 100_000_000
                f.write(f"{i},{c},{c + 100000},{c + 2_000_000 + i * 500_000},{c + 2_500_000}\n")

    def test_plot(self):
        self.write_csv()
        _, series = read_report(self.json)
        self.assertAlmostEqual(float(series["inference"][2]), 2.9)
        out = os.path.join(self.dir.name, "t.png")
        plot_timing(self.json, out)
        with open(out, "rb") as f:
            self.assertEqual(f.read(4), b"\x89PNG")

    def test_missing_csv_and_foreign_json(self):
        with self.assertRaisesRegex(TimingReportError, "r.csv: missing"):
            read_report(self.json)
        with open(self.json, "w") as f:
            f.write("{\"a\": 1}")
        with self.assertRaisesRegex(TimingReportError, "no stages_ms"):
            read_report(self.json)


if __name__ == "__main__":
    unittest.main()
