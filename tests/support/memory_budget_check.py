#!/usr/bin/env python3
"""The process footprint on the shipped configuration (docs/configuration.md,
"Memory"): runs `aprt run` on the demo drive with a timing report and checks
its measured budget: the parts add up to the resident set, and the resident
set stays within the engine's block plus a margin (the program, its
libraries, stacks and heap).

usage: memory_budget_check.py APRT [--margin-mib N] [--frames N]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("aprt", nargs="+", help="the aprt command (an emulator may come first)")
    ap.add_argument("--margin-mib", type=float, default=16.0)
    ap.add_argument("--frames", type=int, default=60)
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as d:
        report = os.path.join(d, "timing.json")
        cmd = a.aprt + ["run", "--quiet", "--frames", str(a.frames), "--timing", report]
        run = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
        out = run.stdout + run.stderr
        if run.returncode != 0:
            print(out)
            print(f"memory_budget_check: aprt run exited {run.returncode}")
            return 1
        with open(report) as f:
            memory = json.load(f)["memory"]
    b = memory.get("budget_kb")
    if not b:
        print(f"memory_budget_check: no budget_kb in the timing report: {memory}")
        return 1
    print("memory:", ", ".join(f"{k} {v}" for k, v in b.items()))
    parts = b["engine_block"] + b["program_and_libraries"] + b["stacks"] + b["heap_and_other"]
    ok = True
    if parts != b["total"]:
        print(f"memory_budget_check: the parts add up to {parts} KiB, the total is {b['total']}")
        ok = False
    limit = b["engine_block"] + a.margin_mib * 1024
    if b["total"] > limit:
        print(f"memory_budget_check: resident {b['total']} KiB > engine block "
              f"{b['engine_block']} KiB + {a.margin_mib} MiB")
        ok = False
    if b["locked"] > limit:
        print(f"memory_budget_check: locked {b['locked']} KiB > engine block + {a.margin_mib} MiB")
        ok = False
    print("memory_budget_check:", "ok" if ok else "FAILED")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
