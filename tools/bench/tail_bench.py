#!/usr/bin/python3
"""Tail latency of one model on 1 and 2 threads, this build against another
(e.g. a build of an earlier commit), interleaved in rounds so that both see
the same machine; prints a markdown table of median, p99, p99.9, max and the
tails' ratios to the median (docs/timing.md, "Tail latency").

  tools/bench/tail_bench.py APRT OTHER_APRT MODEL [RUNS_PER_ROUND] [ROUNDS]

Run it on an idle machine, and again with one core busy (stress-ng --cpu 1):
a thread pool that waits for a descheduled worker shows only in the second.
"""
import json
import subprocess
import sys


def quantile(xs, p):
    xs = sorted(xs)
    pos = p * (len(xs) - 1)
    lo = int(pos)
    hi = min(lo + 1, len(xs) - 1)
    return xs[lo] + (xs[hi] - xs[lo]) * (pos - lo)


def main():
    if len(sys.argv) < 4:
        print(__doc__, file=sys.stderr)
        return 2
    builds = {"this": sys.argv[1], "other": sys.argv[2]}
    model = sys.argv[3]
    runs = int(sys.argv[4]) if len(sys.argv) > 4 else 300
    rounds = int(sys.argv[5]) if len(sys.argv) > 5 else 4
    times = {}
    for _ in range(rounds):
        for threads in (1, 2):
            for name, aprt in builds.items():
                out = subprocess.run([aprt, "bench", model, "--json", "--runs", str(runs),
                                      "--warmup", "5", "--threads", str(threads)],
                                     capture_output=True, text=True, check=True)
                times.setdefault((name, threads), []).extend(json.loads(out.stdout)["ms"])
    print("| build | threads | runs | median ms | p99 ms | p99.9 ms | max ms | p99 / median "
          "| p99.9 / median |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for threads in (1, 2):
        for name in builds:
            xs = times[(name, threads)]
            m, p99, p999 = quantile(xs, 0.5), quantile(xs, 0.99), quantile(xs, 0.999)
            print(f"| {name} | {threads} | {len(xs)} | {m:.1f} | {p99:.1f} | {p999:.1f} | "
                  f"{max(xs):.1f} | {p99 / m:.2f} | {p999 / m:.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
