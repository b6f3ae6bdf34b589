"""train --resume: a run stopped by OUT/STOP, or at the end of its budget,
goes on with its optimiser, step, frame order and schedule; what cannot be
resumed says why.

APRT_SYNTH names the aprt_synth binary (the ctest entry sets it)."""

import json
import os
import subprocess
import sys
import tempfile
import unittest

import torch

from test_synth import SYNTH, synth

TOOLS = os.path.join(os.path.dirname(__file__), "..", "..", "tools")
TINY = dict(size=32, batch=4, hidden=32, layers=1)


def stop_at(out, step):
    """A log callback that asks the run to stop once it logs `step`."""
    lines = []

    def log(line):
        lines.append(line)
        if f" step {step} " in line:
            open(os.path.join(out, "STOP"), "w").close()
    return log, lines


def log_rows(out):
    with open(os.path.join(out, "train_log.json")) as f:
        return json.load(f)


def adam_steps(checkpoint):
    return {int(s["step"]) for s in checkpoint["resume"]["optimizer"]["state"].values()}


@unittest.skipUnless(os.access(SYNTH, os.X_OK), "APRT_SYNTH does not name the aprt_synth binary")
class Resume(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.tmp = tempfile.TemporaryDirectory()
        cls.day, cls.val = (os.path.join(cls.tmp.name, n) for n in ("day", "val"))
        synth(cls.day, "--split", "test", "--route-seed", "1", "--frames", "24")
        synth(cls.val, "--split", "test", "--route-seed", "3", "--frames", "8",
              "--lighting", "haze")

    @classmethod
    def tearDownClass(cls):
        cls.tmp.cleanup()

    def out(self, name):
        return os.path.join(self.tmp.name, name)

    def test_a_stopped_run_goes_on_where_it_stopped(self):
        from aprt_tools.train import train
        from aprt_tools.train_resume import resume

        out = self.out("stopped")
        os.makedirs(out)
        log, lines = stop_at(out, 50)
        # A budget no loaded machine reaches: only the stop ends the run.
        train([self.day], out, minutes=60, val=self.val, ema=0.99, seed=3, log=log, **TINY)
        self.assertTrue(any("stopped by" in line for line in lines), lines)
        self.assertFalse(os.path.exists(os.path.join(out, "STOP")), "the stop is consumed")
        first = torch.load(os.path.join(out, "checkpoint.pth"))
        rec = first["resume"]
        # 24 frames in batches of 4: six steps an epoch; step 50 is two into the ninth.
        self.assertEqual((rec["step"], rec["epoch"], rec["offset"]), (50, 9, 8))
        self.assertEqual(len(rec["perm"]), 24)
        self.assertLess(rec["elapsed_s"], 60 * 60)
        self.assertEqual(adam_steps(first), {50})
        self.assertTrue(log_rows(out)[-1]["partial"])
        self.assertNotIn("resume", torch.load(os.path.join(out, "best.pth")))

        log, lines = stop_at(out, 100)
        _, _, run = resume(out, log=log)
        self.assertEqual((run["data"], run["val"], run["ema"], run["seed"]),
                         ([self.day], self.val, 0.99, 3))
        self.assertTrue(any("resuming" in line and "step 50" in line for line in lines), lines)
        second = torch.load(os.path.join(out, "checkpoint.pth"))
        rec2 = second["resume"]
        # The optimiser's moments came along: AdamW counts on from 50, not from 0.
        self.assertEqual(adam_steps(second), {100})
        self.assertEqual((rec2["step"], rec2["epoch"], rec2["offset"]), (100, 17, 16))
        self.assertGreater(rec2["elapsed_s"], rec["elapsed_s"])
        rows = log_rows(out)
        self.assertEqual([r["epoch"] for r in rows[:9]], list(range(1, 10)))
        self.assertEqual(rows[9]["epoch"], 9, "the stopped epoch is finished, not restarted")
        self.assertNotIn("partial", rows[9])
        self.assertTrue(all(r["step"] > 50 for r in rows[9:]))

    def test_a_timed_out_run_goes_on_with_a_longer_budget_in_two_workers(self):
        from aprt_tools.train import train
        from aprt_tools.train_resume import resume

        out = self.out("workers")
        train([self.day], out, minutes=0.03, val=self.val, workers=2, log=lambda _: None, **TINY)
        rec = torch.load(os.path.join(out, "checkpoint.pth"))["resume"]
        with self.assertRaisesRegex(ValueError, "give --minutes more than"):
            resume(out, log=lambda _: None)
        # Three seconds more than it spent (on a loaded machine more than its budget).
        longer = rec["elapsed_s"] / 60 + 0.05
        resume(out, minutes=longer, log=lambda _: None)
        second = torch.load(os.path.join(out, "checkpoint.pth"))
        self.assertGreater(second["resume"]["step"], rec["step"])
        self.assertEqual(adam_steps(second), {second["resume"]["step"]})
        self.assertGreater(second["resume"]["elapsed_s"], longer * 60)

    def test_what_cannot_be_resumed_says_why(self):
        from aprt_tools.train import train
        from aprt_tools.train_resume import resume

        with self.assertRaisesRegex(ValueError, "no checkpoint.pth to resume"):
            resume(self.out("nothing"))
        old = self.out("old.pth")
        torch.save({"model_state_dict": {}, "config": {}}, old)
        with self.assertRaisesRegex(ValueError, "written before runs could be resumed.*--init"):
            resume(old)
        bad = self.out("truncated.pth")
        with open(bad, "wb") as f:
            f.write(b"PK\x03\x04 cut short")
        with self.assertRaisesRegex(ValueError, "not readable as a checkpoint"):
            resume(bad)
        # A drive that lost a frame since: not the run's data any more.
        shrunk = self.out("shrunk")
        synth(shrunk, "--split", "test", "--route-seed", "1", "--frames", "12")
        out = self.out("changed")
        train([shrunk], out, minutes=0.01, val=self.val, log=lambda _: None, **TINY)
        with open(os.path.join(shrunk, "poses.txt")) as f:
            kept = f.readlines()[:-1]
        with open(os.path.join(shrunk, "poses.txt"), "w") as f:
            f.writelines(kept)
        with self.assertRaisesRegex(ValueError, "its drives changed"):
            resume(out, minutes=1, log=lambda _: None)
        # A drive that is not on this machine.
        os.rename(shrunk, shrunk + ".moved")
        with self.assertRaisesRegex(ValueError, "shrunk is not here.*--init"):
            resume(out, minutes=1, log=lambda _: None)

    def test_the_command_line_keeps_the_run_its_own(self):
        env = dict(os.environ, PYTHONPATH=TOOLS)
        for args, message in ((["--resume", "x", "--data", "y"], "--data not taken"),
                              (["--out", "x"], "--data and --out are required")):
            r = subprocess.run([sys.executable, "-m", "aprt_tools", "train", *args], env=env,
                               capture_output=True, text=True, stdin=subprocess.DEVNULL)
            self.assertEqual(r.returncode, 2, r.stderr)
            self.assertIn(message, r.stderr)


if __name__ == "__main__":
    unittest.main()
