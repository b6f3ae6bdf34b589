"""Replays a drive in a loop for N frames through `aprt run --timing` and
asserts the run's memory behaviour: no allocation after the first pose
(malloc included: release build), no resident-set growth beyond a page
or two, every frame through. Draws the timing plot beside the report.

Then N/5 frames again with the DDS output on (loopback): Cyclone DDS, being
C, mallocs each serialised sample and frees it after the write, so the
count there is Cyclone's, per pose -- reported, bounded (at most 10 per
pose), and the resident set must not grow. (CAN is not part of the soak:
this machine has no SocketCAN; the sender's path is counted at 0
allocations by CanSender.SendingAllocatesNothing.)

  python3 soak_check.py APRT MODEL DRIVE OUTDIR FRAMES
"""

import json
import os
import subprocess
import sys


def soak(aprt, model, drive, out, name, frames, dds):
    config = os.path.join(out, name + ".yaml")
    output = ("output: {console: false, summary: true, dds: {enabled: true, loopback_only: true, "
              "pose_topic: /aprt/soak_pose}}\n" if dds else "output: {console: false, summary: true}\n")
    with open(config, "w") as f:
        f.write(f"model: {model}\n"
                f"source: {{type: replay, replay: {{path: {drive}, rate_hz: 0, loop: true, "
                f"frames: {frames}}}}}\n" + output +
                "supervisor: {systemd: false, inference_deadline_ms: 10000, frame_timeout_ms: 10000}\n"
                # The pose filter on the drive's odometry.txt: its path allocates
                # nothing either, across the loop's restarts.
                "sanity: {max_jump_m: 0, track: {enabled: false}, filter: {enabled: true}}\n"
                "threads: {lock_memory: false}\n")
    report = os.path.join(out, name + ".json")
    run = subprocess.run([aprt, "run", "--config", config, "--timing", report],
                         capture_output=True, text=True, timeout=3600)
    print(run.stdout[-2000:], run.stderr[-2000:])
    assert run.returncode == 0, f"aprt run exited {run.returncode}"
    r = json.load(open(report))
    print(json.dumps(r["memory"]), json.dumps(r["stages_ms"]["end_to_end"]))
    assert r["frames"]["poses"] == int(frames), r["frames"]
    assert r["memory"]["counter_covers_malloc"], "the counter must cover malloc (release build)"
    return r


def main():
    aprt, model, drive, out, frames = sys.argv[1:6]
    os.makedirs(out, exist_ok=True)
    with_dds = max(int(frames) // 5, 100)
    r = soak(aprt, model, drive, out, "soak", frames, dds=False)
    report = os.path.join(out, "soak.json")
    mem = r["memory"]
    assert mem["allocations_after_first_pose"] == 0, mem
    # Allocations are the leak check (zero, counted); RSS catches memory that is not
    # malloc (mmap, stacks): a few pages of first-touched stack may appear.
    assert mem["rss_growth_kb"] <= 512, mem
    env = dict(os.environ)
    subprocess.run([sys.executable, "-m", "aprt_tools", "plot-timing", report, "--out",
                    os.path.join(out, "soak.png")], check=True, env=env)
    print(f"soak: {frames} frames, 0 allocations after the first pose, RSS growth "
          f"{mem['rss_growth_kb']} KiB, peak {mem['peak_rss_kb']} KiB")
    d = soak(aprt, model, drive, out, "soak_dds", with_dds, dds=True)["memory"]
    per_pose = d["allocations_after_first_pose"] / with_dds
    assert per_pose <= 10, d
    assert d["rss_growth_kb"] <= 512, d
    print(f"soak with DDS: {with_dds} frames, {per_pose:.1f} allocations per pose (Cyclone DDS's "
          f"serialised samples, freed after each write), RSS growth {d['rss_growth_kb']} KiB")


if __name__ == "__main__":
    main()
