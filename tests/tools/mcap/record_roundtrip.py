#!/usr/bin/env python3
"""`aprt run --record` and `source.type: mcap`, end to end:

  record_roundtrip.py APRT WORKDIR SEQUENCE -- RUN_ARGS...

1. aprt run RUN_ARGS --replay SEQUENCE --record WORKDIR/a.mcap   (a replayed drive, recorded)
2. aprt run RUN_ARGS --replay WORKDIR/a.mcap --record WORKDIR/b.mcap
3. the independent readers (node, npm @mcap/core and Foxglove's ROS 2
   deserialiser): a.mcap well formed and decodable (mcap_check.js), and b.mcap
   the same drive -- frames, stamps, every estimate bit for bit, published
   poses (mcap_roundtrip.js).
Both runs must end 0 with nothing dropped and no write error, and the first
allocate nothing after its first pose (`--timing`'s process-wide counter).
"""
import json
import os
import re
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))


def run(cmd):
    p = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    out = p.stdout + p.stderr
    print('$ ' + ' '.join(cmd) + '\n' + out)
    if p.returncode != 0:
        sys.exit(f'FAIL: exit {p.returncode}')
    return out


def main():
    aprt, work, sequence = sys.argv[1], sys.argv[2], sys.argv[3]
    args = sys.argv[sys.argv.index('--') + 1:]
    os.makedirs(work, exist_ok=True)
    a, b = os.path.join(work, 'a.mcap'), os.path.join(work, 'b.mcap')
    for f in (a, b):
        if os.path.exists(f):
            os.remove(f)
    timing = os.path.join(work, 'timing.json')
    misses = 0
    for out in (run([aprt, 'run'] + args + ['--replay', sequence, '--record', a, '--timing', timing]),
                run([aprt, 'run'] + args + ['--replay', a, '--record', b])):
        m = re.search(r'^record: .*: (\d+) frames, .*dropped \(ring full\) (\d+) frames, (\d+) poses, '
                      r'(\d+) diagnostics; (\d+) write errors', out, re.M)
        if not m:
            sys.exit('FAIL: no record summary line')
        if int(m.group(1)) == 0 or any(int(m.group(k)) for k in (2, 3, 4, 5)):
            sys.exit('FAIL: ' + m.group(0))
        d = re.search(r'^summary: .* (\d+) deadline misses', out, re.M)
        misses += int(d.group(1)) if d else 0
    # Recording adds nothing to what the loop allocates (the process's
    # counter; builds without one report none).
    with open(timing) as f:
        allocations = json.load(f)['memory'].get('allocations_after_first_pose')
    print(f'allocations after the first pose while recording: {allocations}')
    if allocations:
        sys.exit('FAIL: the loop allocated while recording')
    run(['node', os.path.join(HERE, 'mcap_check.js'), a])
    # Which estimates go out as valid depends on the run's timing as well as
    # its frames (a missed inference deadline withholds a pose and so moves
    # the track): on a machine too busy to keep the deadline, the published
    # poses are not compared; the frames and every estimate still are.
    if misses:
        print(f'{misses} deadline misses in the two runs: published poses not compared')
    run(['node', os.path.join(HERE, 'mcap_roundtrip.js'), a, b] + (['--estimates-only'] if misses else []))
    print('ok')


if __name__ == '__main__':
    main()
