"""Replays a drive in a loop for N frames through `aprt run --timing` and
asserts the run's memory behaviour: no allocation after the first pose
(malloc included: release build), no resident-set growth beyond a page
or two, every frame through. Draws the timing plot beside the report.

  python3 soak_check.py APRT MODEL DRIVE OUTDIR FRAMES
"""

import json
import os
import subprocess
import sys


def main():
    aprt, model, drive, out, frames = sys.argv[1:6]
    os.makedirs(out, exist_ok=True)
    config = os.path.join(out, "soak.yaml")
    with open(config, "w") as f:
        f.write(f"model: {model}\n"
                f"source: {{type: replay, replay: {{path: {drive}, rate_hz: 0, loop: true, "
                f"frames: {frames}}}}}\n"
                "output: {console: false, summary: true}\n"
                "supervisor: {systemd: false, inference_deadline_ms: 10000, frame_timeout_ms: 10000}\n"
                "sanity: {max_jump_m: 0}\n"
                "threads: {lock_memory: false}\n")
    report = os.path.join(out, "soak.json")
    run = subprocess.run([aprt, "run", "--config", config, "--timing", report],
                         capture_output=True, text=True, timeout=3600)
    print(run.stdout[-2000:], run.stderr[-2000:])
    assert run.returncode == 0, f"aprt run exited {run.returncode}"
    r = json.load(open(report))
    print(json.dumps(r["memory"]), json.dumps(r["stages_ms"]["end_to_end"]))
    assert r["frames"]["poses"] == int(frames), r["frames"]
    mem = r["memory"]
    assert mem["counter_covers_malloc"], "the allocation counter must cover malloc (release build)"
    assert mem["allocations_after_first_pose"] == 0, mem
    # Allocations are the leak check (zero, counted); RSS catches memory that is not
    # malloc (mmap, stacks): a few pages of first-touched stack may appear.
    assert mem["rss_growth_kb"] <= 512, mem
    env = dict(os.environ)
    subprocess.run([sys.executable, "-m", "aprt_tools", "plot-timing", report, "--out",
                    os.path.join(out, "soak.png")], check=True, env=env)
    print(f"soak: {frames} frames, 0 allocations after the first pose, RSS growth "
          f"{mem['rss_growth_kb']} KiB, peak {mem['peak_rss_kb']} KiB")


if __name__ == "__main__":
    main()
